//! Debug a healthy detection-suite run: prints the 4 s leading up to each raised leak event.
//! cargo run --release -p bench --example false_alarm -- SCENARIO SEED [SECONDS]
use bench::detection::{simulator_for, Case};
use detect::{Classifier, ClassifierConfig};
use filter::{EstimatorStage, Tuning};
use model::ActuatorParams;
use std::collections::VecDeque;

fn main() {
    let a: Vec<String> = std::env::args().collect();
    let scenario = a[1].clone();
    let seed: u64 = a[2].parse().expect("seed");
    let seconds: f64 = a.get(3).map(|s| s.parse().expect("seconds")).unwrap_or(300.0);
    let case = Case {
        seed,
        scenario,
        kind: "none".into(),
        size_lpm: 0.0,
        onset_s: f64::NAN,
        ramp_s: 0.0,
        seconds,
        variant: String::new(),
    };
    let mut sim = simulator_for(&case).expect("sim");
    let rig = sim.rig().clone();
    println!(
        "rig bias {:e} beta {:e} fric ext {:?} ret {:?}",
        rig.spool_null_bias_m,
        rig.bulk_modulus_pa,
        rig.friction.extend().static_n,
        rig.friction.retract.map(|r| r.static_n)
    );
    let mut stage = EstimatorStage::new(
        ActuatorParams::default(),
        Tuning::sensor_derived(),
        Tuning::thesis(),
    )
    .expect("stage");
    let mut cls = Classifier::new(ClassifierConfig::default()).expect("cls");
    let mut hist: VecDeque<String> = VecDeque::new();
    for k in 0..(seconds * 1000.0) as usize {
        let s = sim.step();
        let e = stage.on_sample(&s);
        if k % 100 == 0 {
            let r = cls.leak_size.rise_lpm(&e.leak);
            hist.push_back(format!(
                "t {:7.2} x {:.4} xh {:.4} v {:6.3} u {:6.2} p1 {:5.2} p2 {:5.2} rise {:7.3} {:7.3} {:7.3} sig {:.3} {:.3} {:.3} bias {:.2e} Fe {:6.0} nis {:.1}",
                s.t_s,
                s.x_m,
                e.leak.state[3],
                e.leak.state[4],
                s.u_v,
                s.p1_pa / 1e6,
                s.p2_pa / 1e6,
                r[0],
                r[1],
                r[2],
                e.leak.sigma[7] * 6e4,
                e.leak.sigma[8] * 6e4,
                e.leak.sigma[9] * 6e4,
                e.leak.state[10],
                e.leak.state[6],
                e.leak.nis,
            ));
            if std::env::var("FULL").is_ok()
                && (k % 1000 == 0 || (s.t_s > 17.5 && s.t_s < 19.5 && k % 100 == 0))
            {
                println!("{}", hist.back().map(String::as_str).unwrap_or(""));
            }
            if hist.len() > 40 {
                hist.pop_front();
            }
        }
        let mut raised = false;
        cls.on_stage(&e, |ev| {
            if ev.detector == "leak-size" {
                println!(
                    "EVENT t {:.3} {:?} {} size {:.3} conf {:.2} {}",
                    ev.t_detect_s,
                    ev.phase,
                    ev.kind.name(),
                    ev.size_lpm,
                    ev.confidence,
                    ev.detail
                );
                raised |= ev.phase == detect::Phase::Raised;
            }
        });
        if raised {
            println!("thresholds {:?}", cls.leak_size.thresholds_lpm());
            for h in &hist {
                println!("  {h}");
            }
        }
    }
}
