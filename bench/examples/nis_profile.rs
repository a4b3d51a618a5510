//! Healthy NIS of the leak filter by scenario: 5 s averages, p50 / p95 / max.
//! cargo run --release -p bench --example nis_profile -- SECONDS SEEDS SCENARIO...
use bench::detection::{simulator_for, Case};
use filter::{EstimatorStage, Tuning};
use model::ActuatorParams;

fn main() {
    let a: Vec<String> = std::env::args().collect();
    let seconds: f64 = a[1].parse().expect("seconds");
    let seeds: u64 = a[2].parse().expect("seeds");
    for scenario in &a[3..] {
        for seed in 1..=seeds {
            let case = Case {
                seed: seed * 7919,
                scenario: scenario.clone(),
                kind: "none".into(),
                size_lpm: 0.0,
                onset_s: f64::NAN,
                ramp_s: 0.0,
                seconds,
                variant: String::new(),
            };
            let mut sim = simulator_for(&case).expect("sim");
            let mut stage = EstimatorStage::new(
                ActuatorParams::default(),
                Tuning::sensor_derived(),
                Tuning::thesis(),
            )
            .expect("stage");
            let mut avg = Vec::new();
            let (mut s5, mut n5) = (0.0, 0.0);
            for k in 0..(seconds * 1000.0) as usize {
                let s = sim.step();
                let e = stage.on_sample(&s);
                if s.t_s > 10.0 && e.leak.nis.is_finite() {
                    s5 += e.leak.nis.min(1e6);
                    n5 += 1.0;
                }
                if k % 5000 == 4999 && n5 > 0.0 {
                    avg.push(s5 / n5);
                    s5 = 0.0;
                    n5 = 0.0;
                }
            }
            avg.sort_by(|a, b| a.total_cmp(b));
            let q = |p: f64| avg[((avg.len() - 1) as f64 * p) as usize];
            println!(
                "{scenario:22} seed {seed}: NIS 5 s mean p50 {:7.1} p95 {:7.1} max {:7.1}",
                q(0.5),
                q(0.95),
                q(1.0)
            );
        }
    }
}
