//! Debug trace: thresholds and rises over a run.
//! cargo run --release -p detect --example trace -- SCENARIO FAULT|none SEED [offnominal]
use detect::{Classifier, ClassifierConfig};
use filter::{Estimator, Tuning};
use model::{ActuatorParams, Fault, FaultSchedule, Scenario, Simulator};

fn main() {
    let a: Vec<String> = std::env::args().collect();
    let mut rig = ActuatorParams::default();
    if a.iter().any(|s| s == "offnominal") {
        rig = rig.off_nominal(0.8, 0.04);
    }
    let seed: u64 = a[3].parse().unwrap();
    let scenario = Scenario::by_name(&a[1], seed, 600.0).unwrap();
    let secs = scenario.default_seconds;
    let mut sched = FaultSchedule::default();
    if a[2] != "none" {
        sched.faults.push(Fault::parse(&a[2], &rig).unwrap());
    }
    let mut sim = Simulator::with_default_sensors(rig, scenario, sched, seed).unwrap();
    let mut tuning = Tuning::sensor_derived();
    let env = |k: &str| std::env::var(k).ok().and_then(|v| v.parse::<f64>().ok());
    if let Some(v) = env("QL") {
        tuning.q_leak_m6_s2 = v;
    }
    if let Some(v) = env("QB") {
        tuning.q_bias_m2 = v;
    }
    if let Some(v) = env("QFE") {
        tuning.q_f_e_n2 = v;
    }
    if let Some(v) = env("QP") {
        tuning.q_p_pa2 = v;
    }
    let mut est = Estimator::new(ActuatorParams::default(), tuning).unwrap();
    let mut cls = Classifier::new(ClassifierConfig::default()).unwrap();
    for k in 0..(secs * 1000.0) as usize {
        let s = sim.step();
        let e = est.on_sample(&s);
        cls.on_estimate(&e, |ev| println!("EVENT {ev:?}"));
        if k % 1000 == 0 {
            let r = cls.leak_size.rise_lpm(&e);
            println!(
                "t {:5.1} q {:7.4} {:7.4} {:7.4} rise {:7.4} {:7.4} {:7.4} thr {:?} leak {:.4}",
                s.t_s,
                e.state[7] * 6e4,
                e.state[8] * 6e4,
                e.state[9] * 6e4,
                r[0],
                r[1],
                r[2],
                cls.leak_size.thresholds_lpm(),
                s.q_leak_lpm
            );
        }
    }
}
