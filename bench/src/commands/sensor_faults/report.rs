//! Scoring a sensor-fault run and the totals per run kind.

use detect::{LeakEvent, Phase};
use model::sample::Sample;
use model::sensor_fault::{Channel, SensorFault, SensorFaultKind};
use serde::Serialize;

use super::{FaultRunOutcome, RunKind, SensorFaultsArgs, RUN_KINDS};

/// Whether `e` is a sensor event's first report.
fn is_sensor_raise(e: &LeakEvent) -> bool {
    e.phase == Phase::Raised && !e.kind.is_leak_alarm() && !e.channel.is_empty()
}

/// How far a fault makes its transducer read off, beside the least the detector names.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Misreading {
    /// The fault's misreading at its largest: on p1 or p2, kPa (a drift's offset
    /// at the run's end; a span error's g times the channel's mean reading once
    /// grown); on x, mm (the drift's offset at the run's end). NaN for the
    /// healthy twin, a stuck or spiking transducer and the leak.
    pub size: f64,
    /// The least misreading the detector names on that channel, in the same
    /// unit: [`detect::offset::OFFSET_LEAST_SHARE_OF_RANGE`] of the pressure
    /// transducer's range ([`detect::offset::DRIFT_LEAST_SHARE_OF_RANGE`]
    /// for a drift; for a span error, what a sound transducer may read off at
    /// the channel's mean reading where the datasheet gives it and that is
    /// smaller), or [`detect::offset::POSITION_LEAST_OFFSET_MM`].
    pub least_named: f64,
    /// The least misreading commissioning said the detector names on that
    /// channel, on a duty cycle like its recording's, in the same unit
    /// ([`pipeline::commission::SensorReach`]); infinite: it said the channel
    /// is not watched; NaN: not stated.
    pub stated: f64,
}

impl Misreading {
    /// None: a fault without a size to compare (or no fault).
    pub const NONE: Misreading = Misreading {
        size: f64::NAN,
        least_named: f64::NAN,
        stated: f64::NAN,
    };

    /// The misreading of `fault` over the run `samples` (the faulty readings), on
    /// pressure transducers of range `full_scale_pa` (Pa) whose datasheet gives
    /// their largest zero offset `sound[0]` (Pa) and span error `sound[1]` (a
    /// fraction of the reading; both 0: not given).
    pub fn of(fault: &SensorFault, samples: &[Sample], full_scale_pa: f64, sound: [f64; 2]) -> Misreading {
        let end_s = samples.last().map_or(f64::NAN, |s| s.t_s);
        let pressure = fault.channel.is_pressure();
        let (si_per_unit, mut least_named) = if pressure {
            let drifting = matches!(fault.kind, SensorFaultKind::Drift { .. });
            (
                1e3,
                detect::offset::least_pressure_offset_pa(full_scale_pa, drifting) * 1e-3,
            )
        } else {
            (1e-3, detect::offset::POSITION_LEAST_OFFSET_MM)
        };
        let size_si = match fault.kind {
            SensorFaultKind::Drift { .. } => fault.drift_offset_si(end_s).abs(),
            SensorFaultKind::Span { gain_error, ramp_s } if pressure => {
                // (the readings carry the error: read/(1+g) is the pressure, g times it the misreading)
                let grown_s = fault.onset_s + ramp_s;
                let (sum, n) = samples
                    .iter()
                    .filter(|s| s.t_s >= grown_s)
                    .map(|s| {
                        if fault.channel == Channel::P1 {
                            s.p1_pa
                        } else {
                            s.p2_pa
                        }
                    })
                    .filter(|p| p.is_finite())
                    .fold((0.0, 0.0), |(sum, n), p| (sum + p, n + 1.0));
                // (NaN where no reading came after the ramp)
                let mean = sum / n;
                let pressure_mean = (mean / (1.0 + gain_error)).abs();
                if pressure_mean.is_finite() {
                    let bound_pa =
                        detect::offset::sound_transducer_misreading(sound[0], sound[1], pressure_mean);
                    least_named = least_named.min(bound_pa * 1e-3);
                }
                (gain_error / (1.0 + gain_error) * mean).abs()
            }
            _ => f64::NAN,
        };
        Misreading {
            size: size_si / si_per_unit,
            least_named,
            stated: f64::NAN,
        }
    }

    /// The same, with the least commissioning stated on `channel` by `reach`.
    pub fn stated_by(self, channel: Channel, reach: &pipeline::commission::SensorReach) -> Misreading {
        let least = reach.least_named();
        let stated = match channel {
            Channel::P1 => least[0],
            Channel::P2 => least[1],
            Channel::X => least[2],
        };
        // (a drift is named from the least drifting offset, whatever the flow shows)
        let stated = if stated.is_finite() {
            stated.max(self.least_named)
        } else {
            stated
        };
        Misreading { stated, ..self }
    }

    /// Whether the misreading reaches the least the detector names.
    pub fn past_least_named(&self) -> bool {
        self.size >= self.least_named
    }

    /// Whether the misreading reaches the least commissioning stated.
    pub fn past_stated(&self) -> bool {
        self.size >= self.stated
    }

    /// Whether commissioning said the channel is not watched.
    pub fn said_not_watched(&self) -> bool {
        self.stated == f64::INFINITY
    }
}

/// Scores the events of one run against its fault (see [`FaultRunOutcome`];
/// the misreading is the caller's to set).
pub(super) fn score(
    instance: usize,
    kind: RunKind,
    spec: String,
    channel: String,
    onset_s: f64,
    scenario: &str,
    events: &[LeakEvent],
) -> FaultRunOutcome {
    let after = |e: &&LeakEvent| onset_s.is_finite() && e.t_detect_s >= onset_s;
    let raised = || events.iter().filter(|e| e.phase == Phase::Raised);
    let sensors_after: Vec<&LeakEvent> = events
        .iter()
        .filter(|e| is_sensor_raise(e))
        .filter(after)
        .collect();
    let sensor_events_before_onset = events
        .iter()
        .filter(|e| is_sensor_raise(e))
        .filter(|e| !after(e))
        .count();
    let first_sensor = sensors_after
        .first()
        .map(|e| (e.kind.name().to_string(), e.channel.clone(), e.t_detect_s));
    let (leak_events, named_right, delay_s, stated_onset_error_s) = if kind == RunKind::Leak {
        // the run's own leak: its first named kind must be the truth, before any sensor event
        let first_named = raised().find(|e| e.kind.is_leak() && e.t_detect_s >= onset_s);
        let first_sensor_t = sensors_after.first().map_or(f64::INFINITY, |e| e.t_detect_s);
        let before = raised()
            .filter(|e| e.kind.is_leak_alarm() && e.t_detect_s < onset_s)
            .count();
        match first_named {
            Some(e) if e.kind.name() == channel && e.t_detect_s <= first_sensor_t => {
                (before, true, e.t_detect_s - onset_s, f64::NAN)
            }
            _ => (before, false, f64::NAN, f64::NAN),
        }
    } else {
        let right = sensors_after.iter().find(|e| e.channel == channel);
        (
            raised().filter(|e| e.kind.is_leak_alarm()).count(),
            right.is_some(),
            right.map_or(f64::NAN, |e| e.t_detect_s - onset_s),
            right.map_or(f64::NAN, |e| e.t_onset_s - onset_s),
        )
    };
    // (the last leak alarm's report: a re-isolation raises its successor, a clearing ends it)
    let last_alarm = events.iter().rev().find(|e| e.kind.is_leak_alarm());
    let leak_alarm_at_end = kind != RunKind::Leak && last_alarm.is_some_and(|e| e.phase != Phase::Cleared);
    FaultRunOutcome {
        instance,
        kind,
        spec,
        channel,
        onset_s,
        scenario: scenario.to_string(),
        leak_events,
        leak_alarm_at_end,
        first_sensor,
        sensor_events_before_onset,
        named_right,
        delay_s,
        misreading: Misreading::NONE,
        stated_onset_error_s,
    }
}

/// The totals of one run kind.
#[derive(Debug, Clone, Serialize)]
pub struct KindSummary {
    /// The run kind.
    pub kind: RunKind,
    /// Runs.
    pub runs: usize,
    /// Runs with a leak event that is not their own leak.
    pub runs_with_leak_events: usize,
    /// Runs that end with such a leak alarm standing.
    pub runs_ending_with_a_leak_alarm: usize,
    /// Runs with a sensor event before the onset (or, healthy, at all).
    pub runs_with_early_sensor_events: usize,
    /// Runs named right: the sensor event on the faulty channel, or the leak's own kind first.
    pub named_right: usize,
    /// Runs whose misreading reaches the least the detector names ([`Misreading`]).
    pub past_least_named: usize,
    /// Those of them named right.
    pub past_least_named_right: usize,
    /// Runs whose misreading reaches the least commissioning stated ([`Misreading::stated`]).
    pub past_stated: usize,
    /// Those of them named right.
    pub past_stated_right: usize,
    /// Runs on a channel commissioning said is not watched.
    pub said_not_watched: usize,
    /// Median time from the onset to that, s (NaN: none).
    pub median_delay_s: f64,
    /// Longest such time, s (NaN: none).
    pub max_delay_s: f64,
    /// Median of |the onset the sensor event stated − the fault's|, s, over
    /// the runs named right (NaN: none).
    pub median_onset_error_s: f64,
}

/// The totals per run kind, in [`RUN_KINDS`] order.
pub fn summarise(runs: &[FaultRunOutcome]) -> Vec<KindSummary> {
    RUN_KINDS
        .iter()
        .map(|&kind| {
            let mine: Vec<&FaultRunOutcome> = runs.iter().filter(|r| r.kind == kind).collect();
            let mut delays: Vec<f64> = mine.iter().map(|r| r.delay_s).filter(|d| d.is_finite()).collect();
            let median = crate::stats::quantile(&mut delays, 0.5);
            let mut onset_errors: Vec<f64> = mine
                .iter()
                .map(|r| r.stated_onset_error_s.abs())
                .filter(|d| d.is_finite())
                .collect();
            let past: Vec<&&FaultRunOutcome> =
                mine.iter().filter(|r| r.misreading.past_least_named()).collect();
            KindSummary {
                kind,
                runs: mine.len(),
                runs_with_leak_events: mine.iter().filter(|r| r.leak_events > 0).count(),
                runs_ending_with_a_leak_alarm: mine.iter().filter(|r| r.leak_alarm_at_end).count(),
                runs_with_early_sensor_events: mine
                    .iter()
                    .filter(|r| r.sensor_events_before_onset > 0)
                    .count(),
                named_right: mine.iter().filter(|r| r.named_right).count(),
                past_least_named: past.len(),
                past_least_named_right: past.iter().filter(|r| r.named_right).count(),
                past_stated: mine.iter().filter(|r| r.misreading.past_stated()).count(),
                past_stated_right: mine
                    .iter()
                    .filter(|r| r.misreading.past_stated() && r.named_right)
                    .count(),
                said_not_watched: mine.iter().filter(|r| r.misreading.said_not_watched()).count(),
                median_delay_s: median,
                max_delay_s: delays.iter().cloned().fold(f64::NAN, f64::max),
                median_onset_error_s: crate::stats::quantile(&mut onset_errors, 0.5),
            }
        })
        .collect()
}

/// The report's table in Markdown.
pub fn markdown(args: &SensorFaultsArgs, sums: &[KindSummary]) -> String {
    let title = match &args.data {
        Some(dir) => format!(
            "# Sensor faults on the healthy recordings of {}: {} instances, seed {}",
            dir.file_name()
                .map_or_else(|| dir.display().to_string(), |n| n.to_string_lossy().into_owned()),
            args.instances,
            args.seed
        ),
        None => format!(
            "# Sensor faults on the {} rig: {} instances, seed {}, runs of {} s{}",
            args.rig_name(),
            args.instances,
            args.seed,
            args.seconds,
            if args.temp_c { ", with temp_c" } else { "" }
        ),
    };
    let mut s = format!(
        "{title}\n\n\
         | run | runs | with a leak event | ending with a leak alarm standing | sensor event before the onset | named right | median / longest time from onset | stated onset, median error | misreading past the least named: runs, named right | past what commissioning stated: runs, named right (said not watched) |\n\
         |---|---|---|---|---|---|---|---|---|---|\n"
    );
    // (a kind no run carried is left out: a recording carries no leak)
    for k in sums.iter().filter(|k| k.runs > 0) {
        let pct = 100.0 * k.named_right as f64 / k.runs.max(1) as f64;
        let named = if k.kind == RunKind::Healthy {
            "-".to_string()
        } else {
            format!("{} ({pct:.0} %)", k.named_right)
        };
        // (only drifts and span errors have a misreading to compare)
        let (past, stated) = if matches!(
            k.kind,
            RunKind::PressureDrift | RunKind::Span | RunKind::PositionDrift
        ) {
            (
                format!("{}, {}", k.past_least_named, k.past_least_named_right),
                format!(
                    "{}, {} ({})",
                    k.past_stated, k.past_stated_right, k.said_not_watched
                ),
            )
        } else {
            ("-".to_string(), "-".to_string())
        };
        s += &format!(
            "| {} | {} | {} | {} | {} | {named} | {:.1} / {:.1} s | {:.1} s | {past} | {stated} |\n",
            k.kind.name(),
            k.runs,
            k.runs_with_leak_events,
            k.runs_ending_with_a_leak_alarm,
            k.runs_with_early_sensor_events,
            k.median_delay_s,
            k.max_delay_s,
            k.median_onset_error_s
        );
    }
    s += "\nNamed right: a sensor event on the faulty channel after the onset; for the leak run, \
          its own kind named before any sensor event. The stated onset: the time the sensor event on the \
          faulty channel says it began to read off, against the fault's onset. A leak alarm standing at the end was neither \
          cleared nor withdrawn when the transducer was named. A misreading past the least named: \
          a pressure offset (a drift's at the run's end, a span error's at the channel's mean reading) \
          of at least 0.5 % of the transducer's range (1 % for a drift; for a span error, what a sound \
          transducer may read off at the channel's mean reading where the datasheet gives it and that is smaller), \
          an offset on x of at least 1 mm. \
          What commissioning stated: the least offset it said it names on the channel, on a duty cycle like \
          its recording's (at least the least named); \
          not watched: it said an offset on x shows only past the largest fitted.\n";
    s
}
