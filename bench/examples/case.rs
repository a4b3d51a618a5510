//! Debug one detection-suite case: cargo run --release -p bench --example case -- SCENARIO KIND SIZE ONSET RAMP SEED
use bench::detection::{simulator_for, Case};
use detect::{Classifier, ClassifierConfig};
use filter::{EstimatorStage, Tuning};
use model::ActuatorParams;

fn main() {
    let a: Vec<String> = std::env::args().collect();
    let case = Case {
        scenario: a[1].clone(),
        kind: a[2].clone(),
        size_lpm: a[3].parse().unwrap(),
        onset_s: a[4].parse().unwrap(),
        ramp_s: a[5].parse().unwrap(),
        seed: a[6].parse().unwrap(),
        seconds: 0.0,
        variant: String::new(),
    };
    let mut case = case;
    let seconds = if case.kind == "none" {
        300.0
    } else {
        case.onset_s + case.ramp_s + 10.0
    };
    case.seconds = seconds;
    let mut sim = simulator_for(&case).unwrap();
    let rig = sim.rig().clone();
    println!(
        "rig bias {:e} beta {:e} fric ext {:?} ret {:?}",
        rig.spool_null_bias_m,
        rig.bulk_modulus_pa,
        rig.friction.extend().static_n,
        rig.friction.retract.map(|r| r.static_n)
    );
    let mut lt = Tuning::sensor_derived();
    if let Ok(v) = std::env::var("SUBSTEPS") {
        lt.substeps = v.parse().unwrap();
    }
    let mut stage = EstimatorStage::new(ActuatorParams::default(), lt, Tuning::thesis()).unwrap();
    let mut cls = Classifier::new(ClassifierConfig::default()).unwrap();
    // the printed window and stride (T_FROM, T_TO s; EVERY samples)
    let env = |k: &str| std::env::var(k).ok().and_then(|v| v.parse::<f64>().ok());
    let t_from = env("T_FROM").unwrap_or(case.onset_s.min(10.0) - 3.0);
    let t_to = env("T_TO").unwrap_or(30.0);
    let every = env("EVERY").map(|v| v as usize).unwrap_or(500).max(1);
    for k in 0..(seconds * 1000.0) as usize {
        let s = sim.step();
        let e = stage.on_sample(&s);
        cls.on_stage(&e, |ev| {
            println!(
                "EVENT t {:.3} {} {:?} {} size {:.3}",
                ev.t_detect_s,
                ev.detector,
                ev.phase,
                ev.kind.name(),
                ev.size_lpm
            )
        });
        if k % every == 0 && s.t_s > t_from && s.t_s < t_to {
            let r = cls.leak_size.rise_lpm(&e.leak);
            println!(
                "t {:6.2} q {:7.3} {:7.3} {:7.3} rise {:7.3} {:7.3} {:7.3} thr {:?} bias {:.2e} leak {:.3} x {:.3} p1 {:.2} p2 {:.2}",
                s.t_s,
                e.leak.state[7] * 6e4,
                e.leak.state[8] * 6e4,
                e.leak.state[9] * 6e4,
                r[0],
                r[1],
                r[2],
                cls.leak_size
                    .thresholds_lpm()
                    .map(|v| (v * 1000.0).round() / 1000.0),
                e.leak.state[10],
                s.q_leak_lpm,
                s.x_m,
                s.p1_pa / 1e6,
                s.p2_pa / 1e6
            );
        }
    }
}
