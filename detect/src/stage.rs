//! The classifier stage: both detectors plus sensor and filter-health checks on
//! the estimator's output.

use crate::{ClassifierConfig, EventKind, LeakEvent, LeakSizeDetector, MaeDetector, Phase, CHANNELS};
use filter::{Estimate, FLAG_AFTER_GAP, FLAG_CONVERGING, FLAG_RESET};

/// A pressure reading repeated exactly this many times holds the leak decision
/// (for `recovery_s` after) until it is judged stuck or moves again: a healthy
/// transducer's noise spans several ADC counts (the longest repeat in the
/// development recordings is 22 samples), and a stuck one kicks the leak
/// sizes at once, long before `stuck_samples` names it.
pub const STUCK_SUSPECT_SAMPLES: u32 = 200;

/// A position reading repeated exactly may be a resting rod with a fine
/// encoder, or one against its stop: the filter then fits the pressures. A
/// frozen encoder on a moving rod does not: the pressures move as the rod
/// does, and the mean NIS over the repeat rises far above the healthy one.
/// This factor on the healthy mean NIS (3 before one is known) tells them
/// apart (a frozen encoder on a moving rod leaves 100 and more; a leak of
/// 0.5 L/min opening while the rod rests, 10 for a moment).
pub const X_STUCK_NIS_RATIO: f64 = 30.0;

/// A position repeated exactly this many times, with the leak filter's mean NIS
/// over the repeat past [`X_SUSPECT_NIS_RATIO`] times the healthy mean, may be a
/// frozen encoder on a moving rod: while the repeat lasts no new leak is raised
/// on rises an internal leak leads
/// ([`LeakSizeDetector::suspect_frozen_position`]). An encoder frozen as the
/// rod slows leaves the rest of its travel to the pressures, which the leak
/// filter reads as an internal leak within 0.2 s; `stuck_samples` names it
/// once the rod moves again.
pub const X_SUSPECT_SAMPLES: u32 = 20;

/// The factor on the healthy mean NIS over a position's repeat that makes it
/// suspect ([`X_SUSPECT_SAMPLES`]): an encoder frozen on a slowing rod leaves
/// 40-60 over the first 50 ms on the plant rigs.
pub const X_SUSPECT_NIS_RATIO: f64 = 10.0;

/// A position sensor whose noise spans this many counts or more (its standard
/// deviation over one count, `[sensors]`) does not repeat a reading for long
/// while healthy: at 1.5 counts two readings in a row agree about once in
/// five at rest, and the longest repeat on healthy plant-rig recordings of
/// 360 000-600 000 samples is 10. On such a sensor a repeat of
/// [`X_SUSPECT_SAMPLES`] holds the leak decision and one of `stuck_samples` is
/// stuck whatever the pressures say (a frozen encoder on a creeping rod leaves
/// the NIS near its healthy mean). Below it (an encoder that only counts) a
/// resting rod repeats its reading, and the NIS rules decide.
pub const X_NOISY_COUNTS: f64 = 1.0;

/// Per-channel sensor watch: stuck, saturated, dead.
#[derive(Debug, Clone, Copy, Default)]
struct ChannelWatch {
    /// Time of the last reading, s.
    last_t_s: f64,
    last: f64,
    /// Since when the present reading has held, s (its first sample).
    last_since_s: f64,
    same: u32,
    /// The sum of the leak filter's NIS over the `same` repeated readings.
    same_nis_sum: f64,
    /// The present repeat of a position reading is suspect ([`X_SUSPECT_SAMPLES`]).
    repeat_suspect: bool,
    saturated: u32,
    /// Since when the present run of readings at the range's end, or without a
    /// usable value, has lasted, s (its first sample).
    bad_since_s: f64,
    dead: u32,
    raised: Option<(EventKind, u64)>,
    /// Outliers.
    spikes: crate::spikes::SpikeWatch,
    /// The `sensor-spikes` event raised on this channel, by id.
    spikes_raised: Option<u64>,
}

/// The classifier stage: both detectors plus sensor and filter-health checks.
#[derive(Debug, Clone)]
pub struct Classifier {
    cfg: ClassifierConfig,
    /// leakwatch's detector.
    pub leak_size: LeakSizeDetector,
    /// The thesis' detector.
    pub thesis: MaeDetector,
    channels: [ChannelWatch; 3],
    next_id: u64,
    not_armed_reported: bool,
    learning_since_s: Option<f64>,
    /// The previous estimate of the leak / thesis filter was a reset: a run of
    /// resets (a filter that cannot start on this rig) is one event, not one per sample.
    resetting: [bool; 2],
}

impl Classifier {
    /// A classifier with settings `cfg`.
    pub fn new(cfg: ClassifierConfig) -> Result<Self, String> {
        cfg.validate()?;
        Ok(Classifier {
            leak_size: LeakSizeDetector::new(cfg.clone()),
            thesis: MaeDetector::new(cfg.clone()),
            cfg,
            channels: [ChannelWatch::default(); 3],
            next_id: 1_000_000,
            not_armed_reported: false,
            learning_since_s: None,
            resetting: [false; 2],
        })
    }

    /// Reads one output of the estimator stage (the leak filter's and the thesis
    /// filter's estimates) and calls `emit` for each event it gives (usually none).
    pub fn on_stage(&mut self, s: &filter::StageEstimate, mut emit: impl FnMut(LeakEvent)) {
        if s.missing_before > 0 && s.leak.flags & FLAG_AFTER_GAP == 0 {
            // Frames lost between the estimator and the classifier: the same gate.
            let mut leak = s.leak;
            leak.flags |= FLAG_AFTER_GAP;
            self.on_estimates(&leak, &s.thesis, &mut emit);
        } else {
            self.on_estimates(&s.leak, &s.thesis, &mut emit);
        }
    }

    /// Whether a commissioning was loaded (else a leak present at start cannot be seen).
    pub fn is_commissioned(&self) -> bool {
        self.leak_size.is_commissioned()
    }

    /// The note to show at start about what the detector can see.
    pub fn start_note(&self) -> String {
        match &self.cfg.commissioning {
            Some(c) => format!(
                "commissioned from {} ({:.0} s of healthy data): a leak present at start is seen once the filter has converged{}",
                if c.source.is_empty() { "a healthy recording" } else { &c.source },
                c.healthy_s,
                c.not_watched().map(|p| format!("; {p}")).unwrap_or_default()
            ),
            None => format!(
                "not commissioned: the healthy state is learned in the first {:.0} s after the filter converges; a leak \
                 present now or opening in that time cannot be seen (run `leakwatch commission HEALTHY.csv` and pass its \
                 file with --config)",
                self.learning_s()
            ),
        }
    }

    /// Reads one estimate of a single filter (both detectors read it) and calls
    /// `emit` for each event.
    pub fn on_estimate(&mut self, e: &Estimate, mut emit: impl FnMut(LeakEvent)) {
        self.on_estimates(e, e, &mut emit);
    }

    /// Reads the leak filter's estimate `e` and the thesis filter's `thesis`.
    pub fn on_estimates(&mut self, e: &Estimate, thesis: &Estimate, mut emit: impl FnMut(LeakEvent)) {
        let leak_reset = e.flags & FLAG_RESET != 0;
        let thesis_reset = thesis.flags & FLAG_RESET != 0 && !std::ptr::eq(e, thesis);
        let first = [
            leak_reset && !self.resetting[0],
            thesis_reset && !self.resetting[1],
        ];
        self.resetting = [leak_reset, thesis_reset];
        if leak_reset {
            // (the detector decides itself whether it keeps what it learned)
            if std::ptr::eq(e, thesis) {
                self.thesis.restart();
            }
            let detail = if self.leak_size.is_armed() {
                "the leak filter restarted; no leak evidence until it has converged again (the learned healthy state is kept)"
            } else {
                "the leak filter restarted; warm-up begins again"
            };
            self.leak_size.restart();
            if first[0] {
                let ev = self.plain(EventKind::EstimatorReset, e.t_s, "", detail);
                emit(ev);
            }
        }
        if thesis_reset {
            self.thesis.restart();
            if first[1] {
                let ev = self.plain(
                    EventKind::EstimatorReset,
                    e.t_s,
                    "",
                    "the thesis filter restarted; its warm-up begins again",
                );
                emit(ev);
            }
        }
        let faulty_before = self.channels.iter().any(|c| c.raised.is_some());
        self.check_sensors(e, &mut emit);
        let faulty = self.channels.iter().any(|c| c.raised.is_some());
        if faulty {
            // A sensor fault corrupts what the filters estimate: no leak decision
            // while it lasts, and the thresholds are learned again after it.
            return;
        }
        if faulty_before {
            self.leak_size.relearn();
            self.thesis.restart();
        }
        if self.learning_since_s.is_none() && e.flags & FLAG_CONVERGING == 0 {
            self.learning_since_s = Some(e.t_s);
        }
        let mut ev = None;
        self.leak_size.on_estimate(e, &mut ev);
        // (a transducer named first: a leak alarm withdrawn at the same sample refers to it)
        if let Some(ev) = self.leak_size.take_sensor_event() {
            emit(ev);
        }
        if let Some(ev) = ev.take() {
            emit(ev);
        }
        if self.cfg.thesis_baseline {
            self.thesis.on_estimate(thesis, &mut ev);
            if let Some(ev) = ev {
                emit(ev);
            }
        }
    }

    /// Ends the stream: reports a warm-up that never completed (thresholds not learned).
    pub fn finish(&mut self, t_s: f64, mut emit: impl FnMut(LeakEvent)) {
        if !self.leak_size.is_armed() && !self.thesis.is_armed() && !self.not_armed_reported {
            self.not_armed_reported = true;
            let seen = self.learning_since_s.map(|t0| t_s - t0).unwrap_or(0.0);
            emit(self.plain(
                EventKind::NotArmed,
                t_s,
                "",
                &format!(
                    "warm-up too short to learn thresholds: {seen:.2} s of converged healthy data, {} s needed \
                     ({} s to settle + {} s to learn)",
                    self.learning_s(),
                    self.cfg.settle_s,
                    self.cfg.warmup_s
                ),
            ));
        }
    }

    fn plain(&mut self, kind: EventKind, t_s: f64, channel: &str, detail: &str) -> LeakEvent {
        let id = self.next_id;
        self.next_id += 1;
        let mut ev = LeakEvent::plain(kind, Phase::Raised, "sensors", id, t_s, t_s);
        ev.channel = channel.into();
        ev.detail = detail.into();
        ev
    }

    /// Outliers on channel `c` (watch `w`) at reading `v` (time `t_s`, `dt_s`
    /// after the last): each blinds the leak detector for `recovery_s` (the
    /// filter took it in); three in 30 s raise `sensor-spikes`.
    fn check_spikes(
        &mut self,
        c: usize,
        w: &mut ChannelWatch,
        t_s: f64,
        dt_s: f64,
        v: f64,
        emit: &mut impl FnMut(LeakEvent),
    ) {
        let unit = if c == 0 { ("mm", 1e3) } else { ("MPa", 1e-6) };
        let floor = if c == 0 {
            crate::spikes::X_SPIKE_FLOOR_M
        } else {
            crate::spikes::PRESSURE_SPIKE_FLOOR * self.cfg.pressure_full_scale_pa
        };
        if w.spikes.on_reading(t_s, dt_s, v, floor).is_some() {
            self.leak_size.hold_evidence_until(t_s + self.cfg.recovery_s);
            if w.spikes_raised.is_none() && w.spikes.is_spiking(t_s) {
                let detail = format!(
                    "{} gives outliers: {} readings in {:.0} s jumped away and straight back (largest {:.2} {}); \
                     each one blinds the leak decision for {:.0} s",
                    CHANNELS[c],
                    crate::spikes::SPIKES_TO_RAISE,
                    crate::spikes::SPIKE_WINDOW_S,
                    w.spikes.largest * unit.1,
                    unit.0,
                    self.cfg.recovery_s
                );
                let mut ev = self.plain(EventKind::SensorSpikes, t_s, CHANNELS[c], &detail);
                // (its onset: the first of the outliers that raised it)
                ev.t_onset_s = w.spikes.first_of_recent_s();
                w.spikes_raised = Some(ev.event_id);
                emit(ev);
            }
        } else if let (Some(id), true) = (w.spikes_raised, w.spikes.is_quiet(t_s)) {
            let mut ev = self.plain(EventKind::SensorSpikes, t_s, CHANNELS[c], "no outlier for 30 s");
            ev.phase = Phase::Cleared;
            ev.event_id = id;
            w.spikes_raised = None;
            w.spikes.largest = 0.0;
            emit(ev);
        }
    }

    /// Whether the position's repeated readings of watch `w` leave the leak
    /// filter's NIS above `ratio` times the healthy mean: the pressures say the
    /// rod moves while the encoder does not.
    fn x_repeat_misfits(&self, w: &ChannelWatch, ratio: f64) -> bool {
        // (NaN before arming: `max` then gives 3)
        let healthy = self.leak_size.nis_healthy().max(3.0);
        w.same > 0 && w.same_nis_sum / f64::from(w.same) > ratio * healthy
    }

    /// What a raised sensor fault of kind `k` on channel `c` (its watch `w`) says:
    /// what the channel did, and that no leak is decided while it stands.
    fn fault_detail(&self, k: EventKind, c: usize, w: &ChannelWatch, x_noisy: bool) -> String {
        let what = match k {
            EventKind::SensorDead => format!("no usable {} value for {} samples", CHANNELS[c], w.dead),
            EventKind::SensorSaturated => format!("{} at the end of its range", CHANNELS[c]),
            _ if c == 0 && x_noisy => format!(
                "x has not changed for {} samples, though its noise spans {:.1} counts",
                w.same, self.cfg.position_noise_counts
            ),
            _ if c == 0 => format!(
                "x has not changed for {} samples while the pressures say the rod moves \
                 (mean NIS {:.0} over them)",
                w.same,
                w.same_nis_sum / f64::from(w.same.max(1))
            ),
            _ => format!("{} has not changed for {} samples", CHANNELS[c], w.same),
        };
        format!(
            "{what}; no leak is decided while it stands; once it clears, the healthy state is learned \
             again over {} s",
            self.learning_s()
        )
    }

    /// How long the healthy state takes to learn after the filter converges,
    /// at the start or after a sensor fault clears, s (`settle_s` + `warmup_s`).
    fn learning_s(&self) -> f64 {
        self.cfg.settle_s + self.cfg.warmup_s
    }

    fn check_sensors(&mut self, e: &Estimate, emit: &mut impl FnMut(LeakEvent)) {
        let x_noisy = self.cfg.position_noise_counts >= X_NOISY_COUNTS;
        // (the watches are read out once and written back once: each channel's
        // checks call the detector's methods, which borrow it whole)
        let mut channels = self.channels;
        for (c, w) in channels.iter_mut().enumerate() {
            let v = e.measured[c];
            if v.is_finite() {
                w.dead = 0;
                w.same = if v == w.last { w.same + 1 } else { 0 };
                if w.same == 0 {
                    w.last_since_s = e.t_s;
                }
                w.same_nis_sum = if w.same == 0 {
                    0.0
                } else {
                    w.same_nis_sum + e.nis.max(0.0)
                };
                w.last = v;
                let sat = c > 0 && (v <= 0.0 || v >= self.cfg.pressure_full_scale_pa);
                w.saturated = if sat { w.saturated + 1 } else { 0 };
                if w.saturated <= 1 {
                    w.bad_since_s = e.t_s;
                }
            } else {
                if w.dead == 0 {
                    w.bad_since_s = e.t_s;
                }
                w.dead += 1;
                w.same = 0;
                w.saturated = 0;
            }
            // The rod may legitimately rest (stiction, a stop): a repeated position from
            // a sensor without noise is stuck only while the pressures say the rod
            // moves ([`X_STUCK_NIS_RATIO`]); a noisy one's is stuck ([`X_NOISY_COUNTS`]).
            let may_be_stuck = c > 0 || x_noisy || self.x_repeat_misfits(w, X_STUCK_NIS_RATIO);
            if c == 0 {
                w.repeat_suspect = w.same > 0
                    && (w.repeat_suspect
                        || (w.same >= X_SUSPECT_SAMPLES
                            && (x_noisy || self.x_repeat_misfits(w, X_SUSPECT_NIS_RATIO))));
                self.leak_size.suspect_frozen_position(w.repeat_suspect);
            }
            let now = if w.dead >= self.cfg.dead_samples {
                Some(EventKind::SensorDead)
            } else if w.saturated >= self.cfg.saturated_samples {
                Some(EventKind::SensorSaturated)
            } else if may_be_stuck && w.same >= self.cfg.stuck_samples {
                Some(EventKind::SensorStuck)
            } else {
                None
            };
            // (a noiseless position is not held on suspicion: a leak opening while the
            // rod rests raises the NIS over a repeat for a moment, and the leak must be
            // seen; a noisy one's repeat is itself the fault's sign)
            let held = if c > 0 {
                w.same >= STUCK_SUSPECT_SAMPLES
            } else {
                x_noisy && w.same >= X_SUSPECT_SAMPLES
            };
            if held || now == Some(EventKind::SensorStuck) {
                self.leak_size.hold_evidence_until(e.t_s + self.cfg.recovery_s);
            }
            let dt_s = if w.last_t_s > 0.0 {
                (e.t_s - w.last_t_s).clamp(0.0, 1.0)
            } else {
                0.0
            };
            w.last_t_s = e.t_s;
            self.check_spikes(c, w, e.t_s, dt_s, v, emit);
            match (now, w.raised) {
                (Some(k), None) => {
                    let detail = self.fault_detail(k, c, w, x_noisy);
                    let since_s = if k == EventKind::SensorStuck {
                        w.last_since_s
                    } else {
                        w.bad_since_s
                    };
                    let mut ev = self.plain(k, e.t_s, CHANNELS[c], &detail);
                    // (its onset: the channel's first frozen, missing or saturated reading)
                    ev.t_onset_s = since_s;
                    w.raised = Some((k, ev.event_id));
                    let fault = format!("{} {} (event {})", CHANNELS[c], k.name(), ev.event_id);
                    emit(ev);
                    // (a leak alarm raised on the channel's bad readings is withdrawn)
                    if let Some(cleared) = self.leak_size.withdraw_for_fault(e.t_s, since_s, &fault) {
                        emit(cleared);
                    }
                }
                (None, Some((k, id))) => {
                    let back = format!(
                        "the channel is back; leaks are decided again once the healthy state is learned \
                         again over {} s",
                        self.learning_s()
                    );
                    let mut ev = self.plain(k, e.t_s, CHANNELS[c], &back);
                    ev.phase = Phase::Cleared;
                    ev.event_id = id;
                    w.raised = None;
                    emit(ev);
                }
                _ => {}
            }
        }
        self.channels = channels;
    }
}
