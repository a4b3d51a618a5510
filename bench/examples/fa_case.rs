//! Debug one healthy suite case (with its gaps): the leak-size events, the gaps
//! and the thresholds. cargo run --release -p bench --example fa_case -- SCENARIO SEED [gaps]
//! (env: MAX_COMMAND_HZ, MIN_SIZE_LPM, MIN_INTERNAL_SIZE_LPM override the detector; SUBSTEPS the leak
//! filter's Euler steps per sample; FROM and TO (s) print a trace every EVERY samples, 250)
use bench::detection::{simulator_for, Case, GapSchedule, GapStep};
use detect::{Classifier, ClassifierConfig};
use filter::{EstimatorStage, Tuning};
use model::ActuatorParams;

fn main() {
    let a: Vec<String> = std::env::args().collect();
    let case = Case {
        scenario: a[1].clone(),
        kind: "none".into(),
        size_lpm: 0.0,
        onset_s: f64::NAN,
        ramp_s: 0.0,
        seed: a[2].parse().expect("seed"),
        seconds: 300.0,
        variant: a.get(3).cloned().unwrap_or_default(),
    };
    let mut sim = simulator_for(&case).expect("sim");
    let mut leak_tuning = Tuning::sensor_derived();
    if let Some(n) = std::env::var("SUBSTEPS").ok().and_then(|v| v.parse().ok()) {
        leak_tuning.substeps = n;
    }
    let mut stage =
        EstimatorStage::new(ActuatorParams::default(), leak_tuning, Tuning::thesis()).expect("stage");
    let mut cfg = ClassifierConfig::default();
    if let Some(hz) = std::env::var("MAX_COMMAND_HZ").ok().and_then(|v| v.parse().ok()) {
        cfg.max_command_hz = hz;
    }
    if let Some(m) = std::env::var("MIN_SIZE_LPM").ok().and_then(|v| v.parse().ok()) {
        cfg.min_size_lpm = m;
    }
    if let Some(m) = std::env::var("MIN_INTERNAL_SIZE_LPM")
        .ok()
        .and_then(|v| v.parse().ok())
    {
        cfg.min_internal_size_lpm = m;
    }
    let mut cls = Classifier::new(cfg).expect("cls");
    let mut gaps = GapSchedule::new(case.seed);
    let mut last_thr = [0.0; 3];
    for _ in 0..300_000 {
        let s = sim.step();
        if case.variant == "gaps" {
            match gaps.step(s.t_s) {
                GapStep::Kept => {}
                GapStep::Starts(n) => {
                    println!("gap at {:.3} s of {n} samples", s.t_s);
                    continue;
                }
                GapStep::Lost => continue,
            }
        }
        let e = stage.on_sample(&s);
        let thr = cls.leak_size.thresholds_lpm();
        if let (Some(a), Some(b)) = (
            std::env::var("FROM").ok().and_then(|v| v.parse::<f64>().ok()),
            std::env::var("TO").ok().and_then(|v| v.parse::<f64>().ok()),
        ) {
            let i = (s.t_s * 1000.0).round() as u64;
            if s.t_s >= a
                && s.t_s <= b
                && i.is_multiple_of(
                    std::env::var("EVERY")
                        .ok()
                        .and_then(|v| v.parse().ok())
                        .unwrap_or(250),
                )
            {
                let r = cls.leak_size.rise_lpm(&e.leak);
                let base = cls.leak_size.baseline_lpm();
                println!(
                    "t {:7.2} x {:.3} p1 {:5.2} p2 {:5.2} rise {:7.3} {:7.3} {:7.3} base {:7.3} {:7.3} {:7.3} nis {:.1} flags {} sig {:.4} {:.4} {:.4}",
                    s.t_s, s.x_m, s.p1_pa / 1e6, s.p2_pa / 1e6, r[0], r[1], r[2], base[0], base[1], base[2], e.leak.nis, e.leak.flags,
                    e.leak.sigma[7] * 6e4, e.leak.sigma[8] * 6e4, e.leak.sigma[9] * 6e4
                );
            }
        }
        if thr.iter().zip(&last_thr).any(|(a, b)| (a - b).abs() > 0.01) {
            println!("t {:.1} thresholds {:.3?}", s.t_s, thr);
            last_thr = thr;
        }
        cls.on_stage(&e, |ev| {
            if ev.detector == "leak-size" {
                println!(
                    "EVENT t {:.3} onset {:.3} {:?} {} {}",
                    ev.t_detect_s,
                    ev.t_onset_s,
                    ev.phase,
                    ev.kind.name(),
                    ev.detail
                );
            }
        });
    }
}
