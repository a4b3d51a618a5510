//! Exploration: run a scenario through the estimator and print figures.
#![allow(clippy::needless_range_loop)]
//! cargo run --release -p filter --example explore -- SCENARIO PRESET STATES [FAULT] [smooth]
use filter::{Estimator, Tuning};
use model::{ActuatorParams, Fault, FaultSchedule, FrictionPreset, Scenario, Simulator};

fn main() {
    let a: Vec<String> = std::env::args().collect();
    let scen = a.get(1).map(String::as_str).unwrap_or("open-loop-sine");
    let preset = a.get(2).map(String::as_str).unwrap_or("thesis");
    let states: u32 = a.get(3).and_then(|s| s.parse().ok()).unwrap_or(7);
    let fault = a.get(4).cloned().filter(|f| f != "none");
    let smooth = a.iter().any(|s| s == "smooth");
    let mut rig = ActuatorParams::default();
    if smooth {
        rig = rig.with_friction_preset(FrictionPreset::Smooth);
    }
    let envf = |k: &str| std::env::var(k).ok().and_then(|v| v.parse::<f64>().ok());
    if let Some(v) = envf("RIG_BETA") {
        rig.bulk_modulus_pa *= v;
    }
    if let Some(v) = envf("RIG_BIAS") {
        rig.spool_null_bias_m = v;
    }
    if let Some(v) = envf("RIG_FRIC") {
        let mut e = rig.friction.extend();
        e.static_n *= v;
        e.slip_n *= v;
        e.viscous_n_s_per_m *= v;
        rig.friction.set_extend(e);
    }
    let scenario = Scenario::by_name(scen, 1, 600.0).unwrap();
    let secs = scenario.default_seconds;
    let mut sched = FaultSchedule::default();
    let mut onset = f64::INFINITY;
    if let Some(f) = &fault {
        let f = Fault::parse(f, &rig).unwrap();
        onset = f.onset_s;
        sched.faults.push(f);
    }
    let mut sim = Simulator::with_default_sensors(rig.clone(), scenario, sched, 1).unwrap();
    let mut tuning = Tuning::preset(preset).unwrap();
    tuning.states = states;
    let env = |k: &str| std::env::var(k).ok().and_then(|v| v.parse::<f64>().ok());
    if let Some(v) = env("QW") {
        tuning.q_leak_m6_s2 = v;
    }
    if let Some(v) = env("QFE") {
        tuning.q_f_e_n2 = v;
    }
    if let Some(v) = env("QV") {
        tuning.q_v_m2_s2 = v;
    }
    if let Some(v) = env("QP") {
        tuning.q_p_pa2 = v;
    }
    if let Some(v) = env("QX") {
        tuning.q_x_m2 = v;
    }
    if let Some(v) = env("RP") {
        tuning.r_p_pa2 = v;
    }
    let mut model = ActuatorParams::default();
    if smooth {
        model = model.with_friction_preset(FrictionPreset::Smooth);
    }
    let mut est = Estimator::new(model, tuning).unwrap();
    let n = (secs * 1000.0) as usize;
    let t0 = std::time::Instant::now();
    let mut acc = [[0.0f64; 13]; 2]; // before/after: rms r x,p1,p2; mean innov p1,p2; mean |innov| p1 p2; fe err^2; nis; w1 w2; count
    let mut mae_at = [[0.0; 2]; 2];
    let mut min_eig = f64::INFINITY;
    for k in 0..n {
        let s = sim.step();
        let tr = *sim.truth();
        let e = est.on_sample(&s);
        if k % 1000 == 0 {
            min_eig = min_eig.min(est.min_scaled_eigenvalue());
        }
        if s.t_s < 5.0 {
            continue;
        }
        let i = if s.t_s < onset { 0 } else { 1 };
        if i == 1 && s.t_s < onset + 5.0 {
            continue;
        }
        let c = &mut acc[i];
        for j in 0..3 {
            c[j] += e.residual[j].powi(2);
        }
        c[3] += e.innovation[1];
        c[4] += e.innovation[2];
        c[5] += e.innovation[1].abs();
        c[6] += e.innovation[2].abs();
        let fe_true = tr.forces.friction_n + tr.forces.load_n - tr.forces.end_stop_n;
        if states >= 7 {
            c[7] += (e.state[6] - fe_true).powi(2);
        }
        c[8] += e.nis;
        if states == 10 {
            c[9] += e.state[7];
            c[10] += e.state[8];
            c[12] += e.state[9];
        }
        c[11] += 1.0;
        if i == 0 && s.t_s < onset {
            mae_at[0] = e.mae_pa;
        }
        mae_at[1] = e.mae_pa;
    }
    let el = t0.elapsed().as_secs_f64();
    println!("{scen} {preset} N={states} fault={fault:?} smooth={smooth}  wall {el:.2}s  counters {:?} min_eig {min_eig:e}", est.counters());
    for (i, c) in acc.iter().enumerate() {
        let m = c[11].max(1.0);
        println!("  {}: rms r x {:.3e} p1 {:.3e} p2 {:.3e} | mean inn p1 {:.3e} p2 {:.3e} | mean|inn| {:.3e} {:.3e} | Fe rms {:.1} | NIS {:.2} | qe1 {:.4} qe2 {:.4} qi {:.4} lpm | MAE {:.3e} {:.3e}",
          if i == 0 {"before"} else {"after "}, (c[0]/m).sqrt(), (c[1]/m).sqrt(), (c[2]/m).sqrt(), c[3]/m, c[4]/m, c[5]/m, c[6]/m, (c[7]/m).sqrt(), c[8]/m, c[9]/m*6e4, c[10]/m*6e4, c[12]/m*6e4, mae_at[i][0], mae_at[i][1]);
    }
}
