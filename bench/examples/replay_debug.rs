//! Prints the leak-size detector's view of a recorded run every 0.5 s from T0:
//! cargo run --release -p bench --example replay_debug -- FILE.csv[.gz] T0 (env EVERY: samples between lines, 500)
use detect::{misfits, Classifier, ClassifierConfig};
use filter::{EstimatorStage, Tuning};
use model::ActuatorParams;

fn main() {
    let a: Vec<String> = std::env::args().collect();
    let t0: f64 = a[2].parse().expect("T0");
    let ds = dataset::read_csv(std::path::Path::new(&a[1]), dataset::Limits::default()).expect("csv");
    let mut stage = EstimatorStage::new(
        ActuatorParams::default(),
        Tuning::sensor_derived(),
        Tuning::thesis(),
    )
    .expect("stage");
    let mut cls = Classifier::new(ClassifierConfig::default()).expect("cls");
    for (k, s) in ds.samples.iter().enumerate() {
        let e = stage.on_sample(s);
        cls.on_stage(&e, |ev| {
            println!(
                "EVENT t {:.3} {:?} {} size {:.3}",
                ev.t_detect_s,
                ev.phase,
                ev.kind.name(),
                ev.size_lpm
            )
        });
        let every: usize = std::env::var("EVERY")
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(500);
        if s.t_s >= t0 && k % every == 0 {
            let r = cls.leak_size.rise_lpm(&e.leak);
            let m = misfits(r);
            println!(
                "t {:6.2} rise {:7.3} {:7.3} {:7.3} misfit {:6.3} {:6.3} {:6.3} thr {:?} g {:.2?} q_leak {:.3}",
                s.t_s,
                r[0],
                r[1],
                r[2],
                m[0],
                m[1],
                m[2],
                cls.leak_size.thresholds_lpm(),
                cls.leak_size.flow_factors(),
                s.q_leak_lpm
            );
        }
    }
}
