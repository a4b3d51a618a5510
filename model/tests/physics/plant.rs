//! The installation and the plant: line drop, offset, span and lag, the pump's ripple, warm oil.

use model::fault::FaultSchedule;
use model::leakage::{LeakLaw, LeakPath};
use model::params::ActuatorParams;
use model::scenario::Scenario;
use model::sensors::SensorParams;
use model::sim::{SimSettings, Simulator};

/// Transducers at the valve manifold read each chamber plus the line's laminar
/// drop (R·Q1 into chamber 1, −R·Q2 out of chamber 2), then their offset and
/// span error; a lagging transducer follows τ·ẏ = p − y between samples and
/// reads a ramp about τ late.
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
    // the lag: τ·ẏ = p − y, integrated here by Heun's method in 1000 steps a
    // sample over the pressure interpolated linearly between samples
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
    let (mut y, mut p_was) = (None::<f64>, 0.0);
    let (mut behind, mut moving) = (0.0, 0.0);
    for _ in 0..3000 {
        let s = sim.step();
        let p = sim.truth().state[1];
        let want = match y {
            None => p,
            Some(mut v) => {
                let n = 1000;
                let h = 1e-3 / n as f64;
                let at = |j: usize| p_was + (p - p_was) * j as f64 / n as f64;
                for j in 0..n {
                    let k1 = (at(j) - v) / tau;
                    let k2 = (at(j + 1) - (v + h * k1)) / tau;
                    v += 0.5 * h * (k1 + k2);
                }
                v
            }
        };
        assert!(
            (s.p1_pa - want).abs() <= 2.0 * lsb,
            "t {}: {} vs {want}",
            s.t_s,
            s.p1_pa
        );
        // a lag τ reads a ramp τ late: p − y ≈ τ·ṗ
        let rate = (p - p_was) / 1e-3;
        if y.is_some() && rate.abs() > 1e6 {
            behind += (p - want) * rate;
            moving += tau * rate * rate;
        }
        y = Some(want);
        p_was = p;
    }
    assert!(moving > 0.0, "the pressure never moved faster than 1 MPa/s");
    assert!(
        (behind / moving - 1.0).abs() < 0.3,
        "the lag reads {:.2} τ behind",
        behind / moving
    );
}

/// A DAQ that reads each sample at t + δ (δ normal, σ 50 µs) stamps it t:
/// the position reads x + v·δ and the pressures p + ṗ·δ, one δ for all
/// channels; without jitter nothing changes, bit for bit.
#[test]
fn a_jittering_daq_reads_each_value_moved_by_its_rate() {
    use model::dynamics::{derivative, LeakSet, I_P1, I_V, I_X};
    let rig = model::ActuatorParams::vertical_lift();
    let exact = SensorParams {
        encoder_resolution_m: 1e-9,
        pressure_noise_pa: 0.0,
        adc_bits: 24,
        pressure_full_scale_pa: 25e6,
        ..SensorParams::default()
    };
    let sigma = 50e-6;
    let sim = |sensors: SensorParams| {
        let sc = Scenario::by_name("lift", 3, 20.0).expect("scenario");
        Simulator::new(
            rig.clone(),
            sensors,
            SimSettings::default(),
            sc,
            FaultSchedule::default(),
            3,
        )
        .expect("rig")
    };
    let mut jittered = sim(SensorParams {
        sample_jitter_s: sigma,
        ..exact
    });
    let (mut n, mut sum2, mut worst) = (0usize, 0.0, 0.0_f64);
    for _ in 0..20_000 {
        let s = jittered.step();
        let t = jittered.truth().state;
        let (rate, _) = derivative(&rig, &t, 0.0, &LeakSet::from_params(&rig));
        // the δ this sample was read at, from the position; the pressure moved by its rate times it
        if t[I_V].abs() > 0.02 {
            let delta = (s.x_m - t[I_X]) / t[I_V];
            let p1 = t[I_P1] + rate[I_P1] * delta;
            worst = worst.max((s.p1_pa - p1).abs() / (rate[I_P1].abs() * sigma).max(1e3));
            sum2 += delta * delta;
            n += 1;
        }
    }
    assert!(n > 2000, "the rod moved in {n} samples only");
    let rms = (sum2 / n as f64).sqrt();
    assert!(
        (rms / sigma - 1.0).abs() < 0.1,
        "δ RMS {rms} s against σ {sigma} s"
    );
    assert!(worst < 0.01, "a pressure off its rate times δ by {worst} of σ·ṗ");
    // without jitter the readings are those of the default settings
    let (mut a, mut b) = (
        sim(exact),
        sim(SensorParams {
            sample_jitter_s: 0.0,
            ..exact
        }),
    );
    let bits = |s: model::Sample| s.columns().map(f64::to_bits);
    for _ in 0..2000 {
        assert_eq!(bits(a.step()), bits(b.step()));
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
/// sample: the bulk modulus linearly, the seals' viscous friction by √(ν/ν_ref),
/// their static and Coulomb friction linearly (−0.4 %/K), and the valve's null
/// leakage and a linear leak by ν_ref/ν (Walther's ν); the
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
            let dry = 1.0 - 0.004 * (temp - 25.0);
            assert!((r.friction.slip_n / rig.friction.slip_n - dry).abs() < 1e-12);
            assert!((r.friction.static_n / rig.friction.static_n - dry).abs() < 1e-12);
            assert_eq!(
                r.friction.stribeck_velocity_m_s,
                rig.friction.stribeck_velocity_m_s
            );
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
