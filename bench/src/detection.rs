//! The seeded detection suite (docs/detection/README.md): both detectors side by
//! side on the same simulated runs, in parallel over the cores.
//!
//! Each run draws (from its own seed) a scenario, a rig that differs from the
//! model (friction ±20 % and asymmetric, bulk modulus −30..0 %, spool null bias
//! up to 10 % of the spool amplitude), and a fault: a leak of a given kind and
//! size (L/min at the nominal drop p_s/2), as a step or a ramp of up to 5 s, at
//! a random time in [15, 25] s. Healthy runs measure false alarms per hour.

use detect::EventKind;
use serde::Serialize;

mod cases;
mod report;
mod run;

pub use cases::{cases, draw_rig, simulator_for, GapSchedule, GapStep};
pub use report::{markdown, poisson_upper95, probability_figure, summarise};
pub use run::{commission_rig, run_case, run_suite};

/// Leak sizes of the suite, L/min at the nominal drop.
pub const SIZES_LPM: [f64; 6] = [0.05, 0.1, 0.15, 0.25, 0.5, 1.0];
/// Scenarios drawn by the suite.
pub const SCENARIOS: [&str; 6] = [
    "open-loop-sine",
    "open-loop-chirp",
    "closed-loop-sine",
    "closed-loop-random",
    "loaded-sine",
    "loaded-random",
];
/// Variant of a leak run: the leak opens mid-run after the warm-up.
pub const MID_RUN: &str = "";
/// Variant of a leak run: the leak is there from t = 0, with a commissioning learned
/// on a healthy run of the same rig.
pub const FROM_START: &str = "from-start";
/// Variant of a healthy run: samples lost in gaps of 1 to 2000 samples every 10-30 s.
pub const GAPS: &str = "gaps";
/// The two detectors, as named in events.
pub const DETECTORS: [&str; 2] = ["leak-size", "thesis-mae"];
/// Seconds simulated after the onset of a leak.
pub const AFTER_ONSET_S: f64 = 10.0;
/// Length of one healthy run, s.
pub const HEALTHY_RUN_S: f64 = 300.0;

/// One simulated run of the suite.
#[derive(Debug, Clone, Serialize)]
pub struct Case {
    /// Seed of everything random in the run.
    pub seed: u64,
    /// Scenario name.
    pub scenario: String,
    /// Leak kind (`ext1`, `ext2`, `int`) or `none`.
    pub kind: String,
    /// Leak size at nominal drop, L/min (0 when healthy).
    pub size_lpm: f64,
    /// Onset, s (NaN when healthy).
    pub onset_s: f64,
    /// Ramp duration, s (0 = step).
    pub ramp_s: f64,
    /// Simulated length, s.
    pub seconds: f64,
    /// [`MID_RUN`], [`FROM_START`] or [`GAPS`].
    pub variant: String,
}

/// What one detector did in one run.
#[derive(Debug, Clone, Serialize)]
pub struct Outcome {
    /// Detector name.
    pub detector: String,
    /// A leak event was raised at or after the onset.
    pub detected: bool,
    /// That event named the right kind at its first alarm.
    pub isolated: bool,
    /// Detection delay from onset, s (NaN if not detected).
    pub delay_s: f64,
    /// Last reported size, L/min (NaN if none).
    pub size_lpm: f64,
    /// Leak events raised before the onset (or at all, in a healthy run): false alarms.
    pub false_alarms: u32,
    /// Mean |leak flow| the rig lost after the ramp, L/min (the size reference; 0 when healthy).
    pub real_flow_lpm: f64,
}

/// A run and both detectors' outcomes.
#[derive(Debug, Clone, Serialize)]
pub struct RunResult {
    /// The run.
    pub case: Case,
    /// One outcome per detector, in [`DETECTORS`] order.
    pub outcomes: Vec<Outcome>,
}

/// Figures of one detector for one leak kind and size.
#[derive(Debug, Clone, Serialize)]
pub struct Cell {
    /// Detector name.
    pub detector: String,
    /// Leak kind.
    pub kind: String,
    /// Leak size, L/min.
    pub size_lpm: f64,
    /// [`MID_RUN`] or [`FROM_START`].
    pub variant: String,
    /// Runs.
    pub runs: usize,
    /// Fraction of runs with a detection.
    pub p_detect: f64,
    /// Fraction of runs whose detection (after its updates) named the right kind.
    pub p_isolate: f64,
    /// Median delay, s.
    pub delay_median_s: f64,
    /// 95th-percentile delay, s.
    pub delay_p95_s: f64,
    /// Median of |size − real flow| / real flow over correctly isolated runs (NaN if the detector does not size).
    pub size_error_median: f64,
    /// 95th percentile of |size error| / size.
    pub size_error_p95: f64,
}

/// The whole suite's result.
#[derive(Debug, Clone, Serialize)]
pub struct SuiteResult {
    /// Per detector, kind and size.
    pub cells: Vec<Cell>,
    /// Healthy hours simulated.
    pub healthy_hours: f64,
    /// False alarms per hour over the healthy runs, per detector.
    pub false_alarms_per_hour: Vec<(String, f64)>,
    /// False alarms counted over the healthy runs, per detector.
    pub false_alarm_counts: Vec<(String, u32)>,
    /// One-sided 95 % upper bound of the false-alarm rate per hour (Poisson), per detector.
    pub false_alarms_per_hour_upper95: Vec<(String, f64)>,
    /// Healthy hours of the runs that lost samples in gaps.
    pub gap_hours: f64,
    /// Every run.
    pub runs: Vec<RunResult>,
    /// Wall time of the suite, s.
    pub wall_s: f64,
}

/// The event kinds a leak run may raise, for documentation.
pub fn leak_kinds() -> [EventKind; 3] {
    EventKind::LEAKS
}

#[cfg(test)]
mod tests {
    use detect::{LeakEvent, Phase};

    use super::run::score;
    use super::*;

    #[test]
    fn cases_cover_every_kind_and_size_and_the_healthy_hours() {
        let c = cases(2, 0.25, 1);
        assert_eq!(
            c.iter()
                .filter(|c| c.kind != "none" && c.variant == MID_RUN)
                .count(),
            3 * 6 * 2
        );
        assert_eq!(c.iter().filter(|c| c.variant == FROM_START).count(), 3 * 6);
        for sc in SCENARIOS {
            assert!(c.iter().any(|c| c.scenario == sc), "{sc} missing");
        }
        let healthy: f64 = c.iter().filter(|c| c.kind == "none").map(|c| c.seconds).sum();
        assert!(healthy >= 0.25 * 3600.0);
        assert!(c
            .iter()
            .filter(|c| c.kind != "none" && c.variant == MID_RUN)
            .all(|c| (15.0..=25.0).contains(&c.onset_s)));
        // Seeded: the same suite twice.
        assert_eq!(format!("{:?}", cases(2, 0.25, 1)), format!("{c:?}"));
    }

    #[test]
    fn gaps_are_1_to_2000_samples_every_10_to_30_s() {
        let mut g = GapSchedule::new(7);
        let (mut starts, mut lost, mut announced) = (Vec::new(), 0u64, 0u64);
        for i in 0..600_000u64 {
            let t_s = i as f64 * 1e-3;
            match g.step(t_s) {
                GapStep::Kept => {}
                GapStep::Starts(n) => {
                    assert!((1..=2000).contains(&n), "{n}");
                    starts.push(t_s);
                    announced += n;
                    lost += 1;
                }
                GapStep::Lost => lost += 1,
            }
        }
        assert!((10.0..30.0).contains(&starts[0]), "{starts:?}");
        // (10-30 s apart, plus the gap itself)
        assert!(
            starts.windows(2).all(|w| (10.0..32.0).contains(&(w[1] - w[0]))),
            "{starts:?}"
        );
        assert!(starts.len() >= 18 && starts.len() <= 60, "{}", starts.len());
        assert!(announced >= lost && announced - lost < 2000, "{announced} {lost}");
    }

    #[test]
    fn scoring_counts_false_alarms_delay_and_isolation() {
        let case = Case {
            seed: 1,
            scenario: "closed-loop-sine".into(),
            kind: "ext2".into(),
            size_lpm: 0.5,
            onset_s: 20.0,
            ramp_s: 0.0,
            seconds: 30.0,
            variant: String::new(),
        };
        let ev = |kind, phase, t: f64, id, size| {
            let mut e = LeakEvent::plain(kind, phase, "leak-size", id, t, t);
            e.size_lpm = size;
            e.size_lpm_sigma = 0.01;
            e
        };
        let events = vec![
            // a false alarm raised pending and named: one false alarm
            ev(EventKind::Leak, Phase::Raised, 11.0, 1, 0.1),
            ev(EventKind::Ext1, Phase::Raised, 12.0, 1, 0.1),
            ev(EventKind::Ext1, Phase::Cleared, 13.0, 1, 0.0),
            // the leak: detected at the pending alarm, its kind the one named
            ev(EventKind::Leak, Phase::Raised, 20.4, 2, 0.3),
            ev(EventKind::Ext2, Phase::Raised, 21.9, 2, 0.4),
            ev(EventKind::Ext2, Phase::Updated, 22.9, 2, 0.45),
        ];
        let o = score(&case, "leak-size", &events);
        assert_eq!(o.false_alarms, 1);
        assert!(o.detected && o.isolated);
        assert!((o.delay_s - 0.4).abs() < 1e-9);
        assert_eq!(o.size_lpm, 0.45);
        // named wrong first: not isolated, whatever comes later
        let mut wrong = events.clone();
        wrong[4].kind = EventKind::Ext1;
        assert!(!score(&case, "leak-size", &wrong).isolated);
        let none = score(&case, "thesis-mae", &events);
        assert!(!none.detected && none.delay_s.is_nan());
    }

    #[test]
    fn one_real_run_is_detected() {
        let case = Case {
            seed: 3,
            scenario: "closed-loop-sine".into(),
            kind: "ext1".into(),
            size_lpm: 0.5,
            onset_s: 15.0,
            ramp_s: 0.0,
            seconds: 22.0,
            variant: String::new(),
        };
        let r = run_case(&case).unwrap();
        eprintln!("{r:?}");
        // Found within a second, sized against the flow the rig really lost. This step
        // opens at a motion reversal and the filter first books it on chamber 2 for
        // half a second: the first alarm is raised with its kind pending, and ext1 is
        // named once it has led for `kind_confirm_s` (before, the first alarm said ext2).
        let o = &r.outcomes[0];
        assert!(o.detected && o.delay_s < 1.0, "{r:?}");
        assert!(o.isolated, "the kind named first: {r:?}");
        assert!(
            (o.size_lpm - o.real_flow_lpm).abs() < 0.25 * o.real_flow_lpm,
            "{r:?}"
        );
    }
}
