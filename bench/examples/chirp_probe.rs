//! Probe: the leak filter's leak estimates (L/min at p_s/2) and spool bias (µm)
//! over a suite case, as 1-s means ± spreads, with the mean NIS. From the
//! environment: Q_FE, Q_LEAK, Q_V override the sensor tuning; TRUE_BETA,
//! NOMINAL_RIG simulates the model's own parameters; SUBSTEPS sets the leak filter's Euler sub-steps; TRUE_FRICTION, TRUE_BIAS give the filter the rig's own value; KIND, SIZE,
//! ONSET add a step leak.
//! cargo run --release -p bench --example chirp_probe -- SCENARIO SEED [SECONDS]
use bench::detection::{simulator_for, Case};
use filter::{EstimatorStage, Tuning};
use model::ActuatorParams;

fn main() {
    let a: Vec<String> = std::env::args().collect();
    let seconds: f64 = a.get(3).map(|s| s.parse().expect("seconds")).unwrap_or(40.0);
    let case = Case {
        scenario: a[1].clone(),
        kind: std::env::var("KIND").unwrap_or("none".into()),
        size_lpm: std::env::var("SIZE")
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(0.0),
        onset_s: std::env::var("ONSET")
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(f64::NAN),
        ramp_s: 0.0,
        seed: a[2].parse().expect("seed"),
        seconds,
        variant: String::new(),
    };
    let mut sim = if std::env::var("NOMINAL_RIG").is_ok() {
        let scenario = model::Scenario::by_name(&case.scenario, case.seed, seconds).expect("scenario");
        model::Simulator::with_default_sensors(
            ActuatorParams::default(),
            scenario,
            Default::default(),
            case.seed,
        )
        .expect("sim")
    } else {
        simulator_for(&case).expect("sim")
    };
    let mut t = Tuning::sensor_derived();
    if let Some(v) = std::env::var("Q_FE").ok().and_then(|v| v.parse().ok()) {
        t.q_f_e_n2 = v;
    }
    if let Some(v) = std::env::var("Q_LEAK").ok().and_then(|v| v.parse().ok()) {
        t.q_leak_m6_s2 = v;
    }
    if let Some(v) = std::env::var("Q_V").ok().and_then(|v| v.parse().ok()) {
        t.q_v_m2_s2 = v;
    }
    if let Some(v) = std::env::var("SUBSTEPS").ok().and_then(|v| v.parse().ok()) {
        t.substeps = v;
    }
    let mut model = ActuatorParams::default();
    if std::env::var("TRUE_BETA").is_ok() {
        model.bulk_modulus_pa = sim.rig().bulk_modulus_pa;
    }
    if std::env::var("TRUE_FRICTION").is_ok() {
        model.friction = sim.rig().friction;
    }
    if std::env::var("TRUE_BIAS").is_ok() {
        model.spool_null_bias_m = sim.rig().spool_null_bias_m;
    }
    let mut stage = EstimatorStage::new(model, t, Tuning::thesis()).expect("stage");
    let (mut sum, mut sq, mut n) = ([0.0; 4], [0.0; 4], 0.0);
    let mut nis = 0.0;
    for _ in 0..(seconds * 1000.0) as usize {
        let s = sim.step();
        let e = stage.on_sample(&s).leak;
        let v = [
            e.state[7] * 6e4,
            e.state[8] * 6e4,
            e.state[9] * 6e4,
            e.state[10] * 1e6,
        ];
        for k in 0..4 {
            sum[k] += v[k];
            sq[k] += v[k] * v[k];
        }
        nis += e.nis.min(1e4);
        n += 1.0;
        if n >= 1000.0 {
            let m: Vec<String> = (0..4)
                .map(|k| {
                    let mu = sum[k] / n;
                    format!("{:7.3}±{:5.3}", mu, (sq[k] / n - mu * mu).max(0.0).sqrt())
                })
                .collect();
            println!(
                "t {:5.1} q1 {} q2 {} qi {} bias_um {} nis {:6.1} x {:.3} leak {:.3}",
                s.t_s,
                m[0],
                m[1],
                m[2],
                m[3],
                nis / n,
                s.x_m,
                s.q_leak_lpm
            );
            (sum, sq, n, nis) = ([0.0; 4], [0.0; 4], 0.0, 0.0);
        }
    }
}
