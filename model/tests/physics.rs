//! Physics of the rig simulator asserted against references (docs/model.md, "Known behaviour").

use model::dynamics::{derivative, rk4_step, state_at_rest, LeakSet, I_P1, I_P2, I_V, I_X};
use model::fault::{Fault, FaultSchedule};
use model::leakage::{LeakLaw, LeakPath};
use model::params::{ActuatorParams, FrictionPreset};
use model::scenario::Scenario;
use model::sensors::SensorParams;
use model::sim::{advance, SimSettings, Simulator};
use model::units::m3_s_to_lpm;

fn sim(
    name: &str,
    rig: ActuatorParams,
    faults: Vec<Fault>,
    sensors: SensorParams,
    settings: SimSettings,
) -> Simulator {
    let sc = Scenario::by_name(name, 1, 60.0).unwrap();
    Simulator::new(rig, sensors, settings, sc, FaultSchedule { faults }, 1).unwrap()
}

/// Runs and returns the true states after each sample.
fn run_truth(s: &mut Simulator, seconds: f64) -> Vec<[f64; 6]> {
    let n = (seconds * 1000.0).round() as usize;
    (0..n)
        .map(|_| {
            s.step();
            s.truth().state
        })
        .collect()
}

#[test]
fn centred_valve_holds_pressures_and_position() {
    let p = ActuatorParams::default();
    let mut s = state_at_rest(0.25, 6.9e6);
    for _ in 0..2000 {
        s = advance(&p, &s, 0.0, &LeakSet::NONE, 1e-3, 40);
    }
    assert_eq!(s, state_at_rest(0.25, 6.9e6));
    // unequal pressures whose force is below stiction: sealed chambers, rod held
    let mut s = [0.0, 8.4e6, 5.4e6, 0.25, 0.0, 0.0]; // A·Δp = 1899 N < 2400 N
    for _ in 0..1000 {
        s = advance(&p, &s, 0.0, &LeakSet::NONE, 1e-3, 40);
    }
    assert!((s[I_X] - 0.25).abs() < 1e-9, "rod moved {} m", s[I_X] - 0.25);
    assert!((s[I_P1] - 8.4e6).abs() < 1.0 && (s[I_P2] - 5.4e6).abs() < 1.0);
}

#[test]
fn friction_holds_below_stiction_and_breaks_away_above() {
    let p = ActuatorParams::default();
    // valve open a little: drive ramps slowly; rod stays put until A·Δp reaches f_st
    let mut s = state_at_rest(0.3, 6.9e6);
    let mut moved_at_force = None;
    for k in 0..3000 {
        s = advance(&p, &s, 0.02, &LeakSet::NONE, 1e-3, 40);
        let force = p.piston_area_m2 * (s[I_P1] - s[I_P2]);
        if (s[I_X] - 0.3).abs() > 1e-6 && moved_at_force.is_none() {
            moved_at_force = Some((k, force));
        }
        if moved_at_force.is_none() {
            assert!(force < 2400.0 + 50.0, "held at {force} N");
        }
    }
    let (_, f) = moved_at_force.expect("the rod never broke away");
    assert!(
        (f - 2400.0).abs() < 150.0,
        "broke away at {f} N, expected about f_st = 2400 N"
    );
}

#[test]
fn mass_balance_over_a_run() {
    mass_balance(ActuatorParams::default().with_friction_preset(FrictionPreset::Smooth));
    // a vertical single-rod lift: the two chambers change volume at A1·v and A2·v
    mass_balance(ActuatorParams::vertical_lift());
}

fn mass_balance(mut p: ActuatorParams) {
    // Integrate, alongside the state, the reference-density oil volume that flowed
    // into each chamber: d/dt(V·e^{(p−p0)/β}) = e^{(p−p0)/β}·Q_net exactly for this model.
    p.leaks.push(model::params::BuiltInLeak {
        path: LeakPath::Internal,
        law: LeakLaw::SquareRoot,
        coefficient: 3e-9,
    });
    p.leaks.push(model::params::BuiltInLeak {
        path: LeakPath::External1,
        law: LeakLaw::Linear,
        coefficient: 1e-12,
    });
    let leaks = LeakSet::from_params(&p);
    let beta = p.bulk_modulus_pa;
    let p0 = 6.9e6;
    let mass = |s: &[f64; 8]| {
        let (v1, v2) = p.chamber_volumes_m3(s[I_X]);
        (
            v1 * ((s[I_P1] - p0) / beta).exp(),
            v2 * ((s[I_P2] - p0) / beta).exp(),
        )
    };
    let mut y = [0.0; 8];
    y[..6].copy_from_slice(&state_at_rest(0.3, p0));
    let (m1_0, m2_0) = mass(&y);
    let h = 25e-6;
    let mut inflow = (0.0f64, 0.0f64);
    for k in 0..(2.0 / h) as usize {
        let u = 3.0 * (2.0 * std::f64::consts::PI * (k as f64 * h) + 0.1).sin();
        y = rk4_step(&y, h, |z| {
            let s: [f64; 6] = z[..6].try_into().unwrap();
            let (d, f) = derivative(&p, &s, u, &leaks);
            let q1 = f.valve.q1_m3_s - f.leaks.int_m3_s - f.leaks.ext1_m3_s;
            let q2 = -f.valve.q2_m3_s + f.leaks.int_m3_s - f.leaks.ext2_m3_s;
            let mut out = [0.0; 8];
            out[..6].copy_from_slice(&d);
            out[6] = ((z[I_P1] - p0) / beta).exp() * q1;
            out[7] = ((z[I_P2] - p0) / beta).exp() * q2;
            out
        });
        inflow.0 = inflow.0.max(y[6].abs());
        inflow.1 = inflow.1.max(y[7].abs());
    }
    let (m1, m2) = mass(&y);
    // relative to the largest volume that flowed in or out during the run
    let e1 = ((m1 - m1_0) - y[6]).abs() / inflow.0;
    let e2 = ((m2 - m2_0) - y[7]).abs() / inflow.1;
    assert!(inflow.0 > 1e-5, "the run moved oil: {} m³", inflow.0);
    assert!(e1 < 1e-6 && e2 < 1e-6, "mass balance errors {e1:e}, {e2:e}");
}

/// Reference figures (docs/model.md#reference-figures) for the open-loop sine from x = 0.3 m.
#[test]
fn open_loop_sine_matches_reference_figures() {
    let mut s = sim(
        "open-loop-sine",
        ActuatorParams::default(),
        vec![],
        SensorParams::ideal(),
        SimSettings::default(),
    );
    let (mut xmin, mut xmax, mut p1, mut p2, mut n, mut qmax, mut vmax, mut stuck) =
        (f64::MAX, f64::MIN, 0.0, 0.0, 0.0, 0.0f64, 0.0f64, 0.0);
    let mut tail: Vec<[f64; 6]> = Vec::with_capacity(8000);
    for k in 0..10_000 {
        s.step();
        let tr = *s.truth();
        if k >= 2000 {
            tail.push(tr.state);
            xmin = xmin.min(tr.state[I_X]);
            xmax = xmax.max(tr.state[I_X]);
            p1 += tr.state[I_P1];
            p2 += tr.state[I_P2];
            n += 1.0;
            qmax = qmax.max(tr.forces.valve.q1_m3_s.abs());
            vmax = vmax.max(tr.state[I_V].abs());
            stuck += f64::from(tr.state[I_V].abs() <= 1e-3);
        }
    }
    let amp_mm = (xmax - xmin) / 2.0 * 1e3;
    assert!(
        (amp_mm - 30.6).abs() < 1.0,
        "rod amplitude {amp_mm} mm (reference 30.6)"
    );
    assert!((p1 / n - 6.93e6).abs() < 0.05e6, "mean p1 {}", p1 / n);
    assert!((p2 / n - 6.93e6).abs() < 0.05e6, "mean p2 {}", p2 / n);
    let q = m3_s_to_lpm(qmax);
    assert!((q - 8.2).abs() < 0.5, "peak valve flow {q} L/min (reference 8.2)");
    assert!((vmax - 0.5).abs() < 0.05, "peak speed {vmax} m/s (reference 0.5)");
    let stuck_frac = stuck / n;
    assert!(
        (0.35..0.65).contains(&stuck_frac),
        "stuck {stuck_frac} of the time (reference: about half)"
    );
    // Stick-slip (docs/model.md#stick-slip).
    // Measured here: 56 break-aways per second over the 8 s (the rod stuck 52 % of
    // the time), a median cycle of 15 ms (10-90 %: 14-21 ms, i.e. 48-71 Hz) and a
    // velocity spectrum peaking at 71 Hz; chatter 1.20 MPa (p1) and 1.42 MPa (p2).
    // The cycle's length: at the peak command, half a hydraulic
    // period π/ω_h (ω_h = √(βA²(1/V1 + 1/V2)/m) ≈ 508 rad/s: 6.2 ms) plus refilling
    // 2(f_st − f_sl)/A = 4.1 MPa of pressure difference at the valve's flow
    // (d(p1 − p2)/dt ≈ βQ(1/V1 + 1/V2) ≈ 0.86 GPa/s: 4.8 ms) gives about 11 ms, the
    // same order as the fastest cycles measured (14 ms); 25-33 ms cycles would need
    // the chambers to fill several times slower than the valve's flow allows.
    let ss = stick_slip_figures(&tail);
    eprintln!("open-loop sine, thesis friction: {ss:?}");
    assert!(
        (45.0..67.0).contains(&ss.breakaways_per_s),
        "{} stick -> slip transitions per second (measured 56)",
        ss.breakaways_per_s
    );
    assert!(
        (12.0..19.0).contains(&ss.median_cycle_ms),
        "median stick-slip cycle {} ms (measured 15)",
        ss.median_cycle_ms
    );
    assert!(
        (60.0..80.0).contains(&ss.v_peak_hz),
        "velocity spectrum peaks at {} Hz (measured 71)",
        ss.v_peak_hz
    );
    for (k, c) in ss.chatter_pa.iter().enumerate() {
        assert!(
            (1.0e6..1.8e6).contains(c),
            "p{} chatter ±{c} Pa (measured ±1.20 / ±1.42 MPa)",
            k + 1
        );
    }
}

/// Figures of the stick-slip cycle over a run of true states sampled at 1 kHz.
#[derive(Debug)]
struct StickSlip {
    /// Stick -> slip transitions (|v| leaving the 1 mm/s stick band) per second, 1/s.
    breakaways_per_s: f64,
    /// Median time between consecutive break-aways less than 100 ms apart, ms.
    median_cycle_ms: f64,
    /// Frequency of the largest peak of the velocity's spectrum in 10-100 Hz, Hz.
    v_peak_hz: f64,
    /// Chatter of p1 and p2, Pa: the median over 100 ms windows of half the
    /// peak-to-peak of the pressure minus its 51 ms centred mean.
    chatter_pa: [f64; 2],
}

/// Frequency (Hz) of the largest DFT magnitude of `y` (sampled at 1 kHz, mean removed)
/// between `lo_hz` and `hi_hz`, scanned in 0.125 Hz steps.
fn spectral_peak_hz(y: &[f64], lo_hz: f64, hi_hz: f64) -> f64 {
    let mean = y.iter().sum::<f64>() / y.len() as f64;
    let (mut best, mut best_f) = (0.0, f64::NAN);
    let mut f = lo_hz;
    while f <= hi_hz {
        let w = 2.0 * std::f64::consts::PI * f * 1e-3;
        let (mut re, mut im) = (0.0, 0.0);
        for (k, v) in y.iter().enumerate() {
            let (sn, cs) = (w * k as f64).sin_cos();
            re += (v - mean) * cs;
            im += (v - mean) * sn;
        }
        let mag = re * re + im * im;
        if mag > best {
            best = mag;
            best_f = f;
        }
        f += 0.125;
    }
    best_f
}

/// `y` minus its centred moving average over `2·half + 1` samples (ends dropped).
fn high_pass(y: &[f64], half: usize) -> Vec<f64> {
    (half..y.len() - half)
        .map(|k| y[k] - y[k - half..=k + half].iter().sum::<f64>() / (2 * half + 1) as f64)
        .collect()
}

fn stick_slip_figures(states: &[[f64; 6]]) -> StickSlip {
    let seconds = states.len() as f64 * 1e-3;
    let stuck: Vec<bool> = states.iter().map(|s| s[I_V].abs() <= 1e-3).collect();
    let breakaways: Vec<usize> = stuck
        .windows(2)
        .enumerate()
        .filter(|(_, w)| w[0] && !w[1])
        .map(|(k, _)| k)
        .collect();
    let mut cycles: Vec<usize> = breakaways
        .windows(2)
        .map(|w| w[1] - w[0])
        .filter(|c| *c < 100)
        .collect();
    cycles.sort_unstable();
    let v: Vec<f64> = states.iter().map(|s| s[I_V]).collect();
    let chatter = |i: usize| {
        let p: Vec<f64> = states.iter().map(|s| s[i]).collect();
        let mut halves: Vec<f64> = high_pass(&p, 25)
            .chunks(100)
            .map(|c| {
                let max = c.iter().copied().fold(f64::MIN, f64::max);
                let min = c.iter().copied().fold(f64::MAX, f64::min);
                (max - min) / 2.0
            })
            .collect();
        halves.sort_by(f64::total_cmp);
        halves[halves.len() / 2]
    };
    StickSlip {
        breakaways_per_s: breakaways.len() as f64 / seconds,
        median_cycle_ms: cycles.get(cycles.len() / 2).map_or(f64::NAN, |c| *c as f64),
        v_peak_hz: spectral_peak_hz(&v, 10.0, 100.0),
        chatter_pa: [chatter(I_P1), chatter(I_P2)],
    }
}

#[test]
fn smooth_rig_has_no_stick_slip_but_same_stroke() {
    let rig = ActuatorParams::default().with_friction_preset(FrictionPreset::Smooth);
    let mut s = sim(
        "open-loop-sine",
        rig,
        vec![],
        SensorParams::ideal(),
        SimSettings::default(),
    );
    let states = run_truth(&mut s, 10.0);
    let tail = &states[2000..];
    let xmin = tail.iter().map(|s| s[I_X]).fold(f64::MAX, f64::min);
    let xmax = tail.iter().map(|s| s[I_X]).fold(f64::MIN, f64::max);
    let vmax = tail.iter().map(|s| s[I_V].abs()).fold(0.0, f64::max);
    let stuck = tail.iter().filter(|s| s[I_V].abs() <= 1e-3).count() as f64 / tail.len() as f64;
    assert!(((xmax - xmin) / 2.0 * 1e3 - 30.8).abs() < 1.0);
    assert!(vmax < 0.25, "smooth peak speed {vmax} m/s");
    assert!(stuck < 0.15, "stuck {stuck}");
}

fn mean_position(name: &str, faults: Vec<Fault>, seconds: f64, from_s: f64) -> (f64, f64) {
    let mut s = sim(
        name,
        ActuatorParams::default(),
        faults,
        SensorParams::ideal(),
        SimSettings::default(),
    );
    let states = run_truth(&mut s, seconds);
    let tail = &states[(from_s * 1000.0) as usize..];
    let mean = tail.iter().map(|s| s[I_X]).sum::<f64>() / tail.len() as f64;
    let xmin = tail.iter().map(|s| s[I_X]).fold(f64::MAX, f64::min);
    let xmax = tail.iter().map(|s| s[I_X]).fold(f64::MIN, f64::max);
    (mean, (xmax - xmin) / 2.0)
}

#[test]
fn external_leaks_drift_the_rod_towards_the_leaking_chamber() {
    let p = ActuatorParams::default();
    let leak = |path| vec![Fault::from_lpm(path, LeakLaw::SquareRoot, 0.5, 1.0, &p)];
    let (healthy, _) = mean_position("open-loop-sine", vec![], 5.0, 3.0);
    let (ext1, _) = mean_position("open-loop-sine", leak(LeakPath::External1), 5.0, 3.0);
    let (ext2, _) = mean_position("open-loop-sine", leak(LeakPath::External2), 5.0, 3.0);
    // chamber 1 is on the retracted side: losing oil there retracts the rod
    assert!(ext1 < healthy - 5e-3, "ext1 {ext1} vs healthy {healthy}");
    assert!(ext2 > healthy + 5e-3, "ext2 {ext2} vs healthy {healthy}");
}

/// Half the rod's peak-to-peak travel after the first 3 s of an ideal-sensor
/// open-loop sine run of `seconds` on rig `p` with `faults`, m.
fn sine_amplitude(p: &ActuatorParams, faults: Vec<Fault>, seconds: f64) -> f64 {
    let mut s = sim(
        "open-loop-sine",
        p.clone(),
        faults,
        SensorParams::ideal(),
        SimSettings::default(),
    );
    let st = run_truth(&mut s, seconds);
    let tail = &st[3000..];
    let xmin = tail.iter().map(|s| s[I_X]).fold(f64::MAX, f64::min);
    let xmax = tail.iter().map(|s| s[I_X]).fold(f64::MIN, f64::max);
    (xmax - xmin) / 2.0
}

#[test]
fn internal_leak_shrinks_the_stroke() {
    let p = ActuatorParams::default().with_friction_preset(FrictionPreset::Smooth);
    let mk = |faults| sine_amplitude(&p, faults, 6.0);
    let healthy = mk(vec![]);
    let leaky = mk(vec![Fault::from_lpm(
        LeakPath::Internal,
        LeakLaw::SquareRoot,
        2.0,
        0.0,
        &p,
    )]);
    assert!(
        leaky < 0.97 * healthy,
        "internal leak amplitude {leaky} vs healthy {healthy}"
    );

    // The thesis friction (stick-slip), a 0.5 L/min internal leak.
    let thesis = ActuatorParams::default();
    let mk = |faults| sine_amplitude(&thesis, faults, 10.0);
    let healthy = mk(vec![]);
    let leaky = mk(vec![Fault::from_lpm(
        LeakPath::Internal,
        LeakLaw::SquareRoot,
        0.5,
        0.0,
        &thesis,
    )]);
    eprintln!(
        "thesis friction, 0.5 L/min internal leak: amplitude {:.3} mm vs healthy {:.3} mm ({:+.2} %)",
        leaky * 1e3,
        healthy * 1e3,
        (leaky / healthy - 1.0) * 100.0
    );
    // Measured: 28.89 mm against 30.61 mm, a 5.6 % shrink (2.0 % at 0.25 L/min,
    // 11.2 % at 1 L/min); the stick-slip cycle repeats exactly, so the figure is not noise.
    assert!(
        leaky < 0.97 * healthy && leaky > 0.90 * healthy,
        "thesis friction: internal leak amplitude {leaky} vs healthy {healthy} (measured -5.6 %)"
    );
}

#[test]
fn closed_loop_sine_tracks_the_reference() {
    let mut s = sim(
        "closed-loop-sine",
        ActuatorParams::default(),
        vec![],
        SensorParams::default(),
        SimSettings::default(),
    );
    let samples = s.run(10.0);
    let tail = &samples[2000..];
    let rms = (tail.iter().map(|s| (s.ref_m - s.x_m).powi(2)).sum::<f64>() / tail.len() as f64).sqrt();
    let max = tail.iter().map(|s| (s.ref_m - s.x_m).abs()).fold(0.0, f64::max);
    // The loop is first order with gain K = K_p·k_v, k_v = C_d·w·k_sp·sqrt((p_s/2)/ρ)/A
    // ≈ 0.0495 m/s/V, so K ≈ 2.48 1/s: a 0.5 Hz reference (ω = π) is tracked with an
    // error amplitude of 0.2·ω/sqrt(ω² + K²) ≈ 0.157 m, i.e. an RMS of ≈ 0.111 m.
    let p = ActuatorParams::default();
    let kv = p.discharge_coefficient
        * p.area_gradient_m2_per_m
        * p.spool_gain_m_per_v
        * (0.5 * p.supply_pressure_pa / p.oil_density_kg_m3).sqrt()
        / p.piston_area_m2;
    let k = 50.0 * kv;
    let w = std::f64::consts::PI;
    let predicted_rms = 0.2 * w / (w * w + k * k).sqrt() / 2f64.sqrt();
    assert!((predicted_rms - 0.111).abs() < 0.005, "{predicted_rms}");
    assert!(
        (rms - predicted_rms).abs() < 0.2 * predicted_rms,
        "tracking error rms {rms} m vs first-order prediction {predicted_rms} m (max {max} m)"
    );
}

#[test]
fn halving_the_step_changes_a_10s_run_little() {
    for preset in [FrictionPreset::Smooth, FrictionPreset::Thesis] {
        let rig = ActuatorParams::default().with_friction_preset(preset);
        let run = |n| {
            let settings = SimSettings {
                substeps_per_sample: n,
                ..SimSettings::default()
            };
            let mut s = sim(
                "closed-loop-sine",
                rig.clone(),
                vec![],
                SensorParams::ideal(),
                settings,
            );
            run_truth(&mut s, 10.0)
        };
        let a = run(40);
        let b = run(80);
        let dx = a
            .iter()
            .zip(&b)
            .map(|(a, b)| (a[I_X] - b[I_X]).abs())
            .fold(0.0, f64::max);
        let dp = a
            .iter()
            .zip(&b)
            .map(|(a, b)| (a[I_P1] - b[I_P1]).abs().max((a[I_P2] - b[I_P2]).abs()))
            .fold(0.0, f64::max);
        eprintln!("{preset:?}: max |Δx| {dx:e} m, max |Δp| {dp:e} Pa");
        let (tol_x, tol_p) = match preset {
            FrictionPreset::Smooth => (1e-8, 20.0),
            FrictionPreset::Thesis => (1e-4, 1e5),
        };
        assert!(dx < tol_x && dp < tol_p, "{preset:?}: Δx {dx} m, Δp {dp} Pa");
    }
}

#[test]
fn loaded_scenario_engages_the_spring_and_reports_its_force() {
    let mut s = sim(
        "loaded-sine",
        ActuatorParams::default(),
        vec![],
        SensorParams::default(),
        SimSettings::default(),
    );
    let samples = s.run(6.0);
    let engaged: Vec<_> = samples.iter().filter(|s| s.x_m > 0.23).collect();
    assert!(!engaged.is_empty());
    for smp in engaged {
        let expect = 2e4 * (smp.x_m - 0.22);
        assert!(
            (smp.f_load_n - expect).abs() < 40.0,
            "{} vs {expect}",
            smp.f_load_n
        );
    }
}

#[test]
fn leak_flow_column_reports_the_delivered_flow() {
    let p = ActuatorParams::default();
    let f = Fault::from_lpm(LeakPath::External1, LeakLaw::SquareRoot, 0.5, 1.0, &p);
    let mut s = sim(
        "closed-loop-sine",
        p,
        vec![f],
        SensorParams::ideal(),
        SimSettings::default(),
    );
    let samples = s.run(3.0);
    assert!(samples[..1000].iter().all(|s| s.q_leak_lpm == 0.0));
    for smp in &samples[1000..] {
        let expect = m3_s_to_lpm(f.coefficient * smp.p1_pa.sqrt());
        assert!((smp.q_leak_lpm - expect).abs() < 1e-9);
    }
    // delivered flow: 0.56..1.25 of the nominal 0.5 L/min (docs/model.md#delivered-leak-flow)
    let mean = samples[1000..].iter().map(|s| s.q_leak_lpm).sum::<f64>() / 2000.0;
    assert!((0.28..0.63).contains(&mean), "{mean}");
}

/// A vertical single-rod lift held by its sealed chambers: the rod stands still
/// where A1·p1 − A2·p2 carries the load's weight m·g, and falls when the cap
/// side cannot (the force balance of a cylinder with two areas and gravity).
#[test]
fn a_vertical_lift_holds_its_weight_on_the_cap_side() {
    let p = ActuatorParams::vertical_lift();
    let (a1, a2) = p.areas_m2();
    assert!(
        (a1 - 1.9635e-3).abs() < 1e-7 && (a2 - 1.1593e-3).abs() < 1e-7,
        "{a1} {a2}"
    );
    let weight = 200.0 * 9.80665;
    assert!((p.gravity_force_n() - weight).abs() < 1e-9);
    // p2 = 5 MPa; the cap pressure that carries the weight and the rod side's push
    let p2 = 5.0e6;
    let p1 = (weight + a2 * p2) / a1;
    let mut s = [0.0, p1, p2, 0.2, 0.0, 0.0];
    for _ in 0..1000 {
        s = advance(&p, &s, 0.0, &LeakSet::NONE, 1e-3, 40);
    }
    assert!((s[I_X] - 0.2).abs() < 1e-9, "rod moved {} m", s[I_X] - 0.2);
    // cap side short of the weight by more than stiction: the load comes down
    let mut s = [0.0, p1 - 1.6e3 / a1, p2, 0.2, 0.0, 0.0];
    for _ in 0..200 {
        s = advance(&p, &s, 0.0, &LeakSet::NONE, 1e-3, 40);
    }
    assert!(s[I_X] < 0.2 - 1e-6, "the load did not come down: x = {}", s[I_X]);
    // at rest the chambers' forces balance the weight: equal pressures would lift
    // only (A1 − A2)·p, which at p_s/2 (8.4 kN) is well above 1.96 kN
    // ((A1 − A2)·p − m·g = 6.48 kN at p_s/2, past stiction: it rises)
    let (d, _) = derivative(&p, &state_at_rest(0.2, 10.5e6), 0.0, &LeakSet::NONE);
    let expected = ((a1 - a2) * 10.5e6 - weight - 1.5e3) / 200.0;
    assert!(
        (d[I_V] - expected).abs() < 1e-9,
        "{} against {expected} m/s²",
        d[I_V]
    );
}

/// The in-repo lift in closed loop: it follows the reference and, where it
/// dwells, its chambers carry the weight: mean A1·p1 − A2·p2 within the
/// friction band of m·g.
#[test]
fn a_vertical_lift_in_closed_loop_carries_its_weight() {
    let p = ActuatorParams::vertical_lift();
    let (a1, a2) = p.areas_m2();
    let mut s = sim(
        "lift",
        p.clone(),
        vec![],
        SensorParams::ideal(),
        SimSettings::default(),
    );
    let truth = run_truth(&mut s, 20.0);
    let weight = 200.0 * 9.80665;
    let (mut sum, mut n, mut stuck, mut stuck_err) = (0.0, 0usize, 0usize, 0.0f64);
    for (k, st) in truth.iter().enumerate().skip(5000) {
        let f = a1 * st[I_P1] - a2 * st[I_P2];
        sum += f;
        n += 1;
        let still = |j: usize| truth.get(j).is_some_and(|s| s[I_V].abs() < 1e-4);
        if (k - 20..=k + 20).all(still) {
            // standing still: stiction takes what the chambers do not carry
            stuck += 1;
            stuck_err = stuck_err.max((f - weight).abs());
        }
    }
    let mean = sum / n as f64;
    assert!(
        (mean - weight).abs() < 300.0,
        "mean rod force {mean} N, weight {weight} N"
    );
    assert!(stuck > 100, "{stuck} samples at rest");
    eprintln!("{stuck} samples at rest, within {stuck_err:.0} N of the weight; mean force {mean:.0} N");
    // (the stick law also stops a residual creep of under 0.1 mm/s: 1 % more)
    assert!(
        stuck_err <= 1.01 * 1.5e3,
        "at rest the chambers miss the weight by {stuck_err} N (f_st 1.5 kN)"
    );
    let xs: Vec<f64> = truth.iter().map(|st| st[I_X]).collect();
    let (lo, hi) = xs[5000..]
        .iter()
        .fold((f64::MAX, f64::MIN), |(a, b), &x| (a.min(x), b.max(x)));
    assert!(hi - lo > 0.05, "the lift moved {} m", hi - lo);
}

/// Transducers at the valve manifold read each chamber plus the line's laminar
/// drop (R·Q1 into chamber 1, −R·Q2 out of chamber 2), then their offset and
/// span error; a lagging transducer follows y += (1 − e^(−T/τ))·(p − y) per sample.
#[test]
fn an_installation_reads_the_line_drop_offset_span_and_lag() {
    use model::{FaultSchedule, Scenario, SensorParams, SimSettings, Simulator};
    let rig = model::ActuatorParams::vertical_lift();
    let quiet = SensorParams {
        pressure_noise_pa: 0.0,
        adc_bits: 24,
        pressure_full_scale_pa: 25e6,
        ..SensorParams::default()
    };
    let r = 2.0e8; // 0.2 MPa at 1 L/s
    let installed = SensorParams {
        line_resistance_pa_s_per_m3: r,
        pressure_offset_pa: [30e3, -20e3],
        pressure_gain_error: [0.004, -0.003],
        ..quiet
    };
    let sc = Scenario::by_name("lift", 3, 5.0).expect("scenario");
    let mut sim = Simulator::new(
        rig.clone(),
        installed,
        SimSettings::default(),
        sc.clone(),
        FaultSchedule::default(),
        3,
    )
    .expect("rig");
    let lsb = quiet.pressure_lsb_pa();
    let mut moved = 0;
    for _ in 0..5000 {
        let s = sim.step();
        let t = sim.truth();
        let q = t.forces.valve;
        // the ADC reads 0 to its full scale
        let p1 = ((t.state[1] + r * q.q1_m3_s) * 1.004 + 30e3).clamp(0.0, 25e6);
        let p2 = ((t.state[2] - r * q.q2_m3_s) * 0.997 - 20e3).clamp(0.0, 25e6);
        assert!((s.p1_pa - p1).abs() <= lsb, "t {}: {} vs {p1}", s.t_s, s.p1_pa);
        assert!((s.p2_pa - p2).abs() <= lsb, "t {}: {} vs {p2}", s.t_s, s.p2_pa);
        if (r * q.q1_m3_s).abs() > 50e3 {
            moved += 1;
        }
    }
    assert!(
        moved > 100,
        "the line drop was above 50 kPa in {moved} samples only"
    );
    // the lag: each reading moves by a = 1 − e^(−T/τ) of the way to the pressure
    let tau = 2.0e-3;
    let lagging = SensorParams {
        pressure_lag_s: tau,
        ..quiet
    };
    let mut sim = Simulator::new(
        rig,
        lagging,
        SimSettings::default(),
        sc,
        FaultSchedule::default(),
        3,
    )
    .expect("rig");
    let a = 1.0 - (-1e-3 / tau).exp();
    let mut y = None::<f64>;
    for _ in 0..3000 {
        let s = sim.step();
        let p = sim.truth().state[1];
        let want = match y {
            None => p,
            Some(prev) => prev + a * (p - prev),
        };
        assert!(
            (s.p1_pa - want).abs() <= lsb,
            "t {}: {} vs {want}",
            s.t_s,
            s.p1_pa
        );
        y = Some(want);
    }
}

/// The simulated pump's ripple (±0.4 % of p_s at 250 Hz): the valve sees
/// p_s·(1 + 0.004·sin(2π·250·t)) at each sample; through the open valve the
/// chambers carry more of 250 Hz than without it; with no ripple a run is the
/// one with the default settings, bit for bit.
#[test]
fn the_pumps_ripple_reaches_the_chambers() {
    let rig = ActuatorParams::default();
    let quiet = SensorParams {
        pressure_noise_pa: 0.0,
        adc_bits: 24,
        pressure_full_scale_pa: 20.7e6,
        ..SensorParams::default()
    };
    let run = |ripple: f64| {
        let settings = SimSettings {
            supply_ripple_fraction: ripple,
            ..SimSettings::default()
        };
        let sc = Scenario::by_name("open-loop-sine", 3, 4.0).expect("scenario");
        let mut sim =
            Simulator::new(rig.clone(), quiet, settings, sc, FaultSchedule::default(), 3).expect("rig");
        let mut samples = Vec::new();
        for _ in 0..4000 {
            let x = sim.step();
            if ripple > 0.0 {
                let want = rig.supply_pressure_pa
                    * (1.0 + ripple * (2.0 * std::f64::consts::PI * 250.0 * x.t_s).sin());
                let seen = sim.truth().forces.valve.supply_pa;
                assert!((seen - want).abs() < 1e-6 * want, "t {}: {seen} vs {want}", x.t_s);
            }
            samples.push(x);
        }
        samples
    };
    // amplitude of the 250 Hz component of p1 over the last 2 s, Pa
    let at_250 = |samples: &[model::Sample]| {
        let tail = &samples[2000..4000];
        let (mut c, mut s) = (0.0, 0.0);
        for x in tail {
            let w = 2.0 * std::f64::consts::PI * 250.0 * x.t_s;
            c += x.p1_pa * w.cos();
            s += x.p1_pa * w.sin();
        }
        2.0 * (c * c + s * s).sqrt() / tail.len() as f64
    };
    let (with, without) = (run(0.004), run(0.0));
    let (a, b) = (at_250(&with), at_250(&without));
    assert!(a > b, "250 Hz in p1: {a} Pa with ripple, {b} Pa without");
    let sc = Scenario::by_name("open-loop-sine", 3, 4.0).expect("scenario");
    let mut plain = Simulator::new(
        rig.clone(),
        quiet,
        SimSettings::default(),
        sc,
        FaultSchedule::default(),
        3,
    )
    .expect("rig");
    let reference = plain.run(4.0);
    assert!(
        without
            .iter()
            .zip(&reference)
            .all(|(x, y)| x.p1_pa.to_bits() == y.p1_pa.to_bits()),
        "no ripple changes nothing"
    );
}

/// A warm-up (25 → 55 °C, τ = 10 s) scales the rig by the oil's laws at every
/// sample: the bulk modulus linearly, the seals' viscous friction by √(ν/ν_ref)
/// and the valve's null leakage and a linear leak by ν_ref/ν (Walther's ν); the
/// measured channel reads the temperature to 0.1 °C, an unmeasured one NaN; the
/// rest of the rig is untouched.
#[test]
fn a_warming_oil_scales_stiffness_friction_and_laminar_flows_by_its_laws() {
    let mut rig = ActuatorParams::vertical_lift();
    rig.oil_temperature.reference_c = 25.0;
    rig.valve_null_leakage_m3_s_pa = 3e-13;
    rig.leaks.push(model::params::BuiltInLeak {
        path: LeakPath::Internal,
        law: LeakLaw::Linear,
        coefficient: 1e-12,
    });
    for measured in [true, false] {
        let oil = model::OilWarmUp {
            start_c: 25.0,
            end_c: 55.0,
            time_constant_s: 10.0,
            measured,
        };
        let settings = SimSettings {
            oil: Some(oil),
            ..SimSettings::default()
        };
        let sc = Scenario::by_name("closed-loop-random", 3, 30.0).unwrap();
        let mut s = Simulator::new(
            rig.clone(),
            SensorParams::default(),
            settings,
            sc,
            FaultSchedule::default(),
            3,
        )
        .unwrap();
        for k in 0..20_000u32 {
            let sample = s.step();
            if k % 5000 != 4999 {
                continue;
            }
            let temp = oil.at(sample.t_s);
            let nu = |t: f64| rig.oil_temperature.viscosity_mm2_s(t);
            let ratio = nu(temp) / nu(25.0);
            let r = s.rig();
            assert!((r.bulk_modulus_pa / rig.bulk_modulus_pa - (1.0 - 0.0045 * (temp - 25.0))).abs() < 1e-12);
            let viscous = r.friction.viscous_n_s_per_m / rig.friction.viscous_n_s_per_m;
            assert!((viscous - ratio.sqrt()).abs() < 1e-12);
            assert!((r.valve_null_leakage_m3_s_pa / 3e-13 * ratio - 1.0).abs() < 1e-12);
            assert!((r.leaks[0].coefficient / 1e-12 * ratio - 1.0).abs() < 1e-12);
            assert_eq!(r.friction.slip_n, rig.friction.slip_n);
            assert_eq!(r.mass_kg, rig.mass_kg);
            if measured {
                assert!(
                    (sample.temp_c - temp).abs() <= 0.05 + 1e-9,
                    "{} vs {temp}",
                    sample.temp_c
                );
            } else {
                assert!(sample.temp_c.is_nan());
            }
        }
        // 20 s into a 10-s time constant: 30·(1 − e^−2) = 25.9 K warmer; an HLP 46
        // (VI 100) goes from about 95 to 28 mm²/s there (ISO 3448 charts): 0.29×
        let temp = oil.at(19.999);
        assert!((temp - 50.94).abs() < 0.01, "{temp}");
        let ratio = rig.oil_temperature.viscosity_mm2_s(temp) / rig.oil_temperature.viscosity_mm2_s(25.0);
        assert!((0.25..0.35).contains(&ratio), "{ratio}");
    }
}
