//! Sensor faults in the simulated rig: each reading against its equation, nothing
//! before the onset, and the rig's physics untouched (docs/model.md#sensor-faults).

use model::dynamics::{I_P1, I_P2, I_X};
use model::fault::FaultSchedule;
use model::params::ActuatorParams;
use model::scenario::Scenario;
use model::sensor_fault::{Channel, Distortion, SensorFault, SensorFaultRun, SensorFaultSchedule};
use model::sensors::SensorParams;
use model::sim::{SimSettings, Simulator};
use model::{Sample, State};

/// One run's samples and true states.
struct Run {
    samples: Vec<Sample>,
    truth: Vec<State>,
}

fn run(scenario: &str, sensors: SensorParams, specs: &[&str], seconds: f64) -> Run {
    let scenario = Scenario::by_name(scenario, 3, seconds).unwrap();
    let sim = Simulator::new(
        ActuatorParams::default(),
        sensors,
        SimSettings::default(),
        scenario,
        FaultSchedule::default(),
        3,
    )
    .unwrap();
    let mut sim = sim
        .with_sensor_faults(SensorFaultSchedule::parse_all(specs).unwrap())
        .unwrap();
    let n = (seconds / sim.sample_period_s()).round() as usize;
    let (mut samples, mut truth) = (Vec::new(), Vec::new());
    for _ in 0..n {
        samples.push(sim.step());
        truth.push(sim.truth().state);
    }
    Run { samples, truth }
}

/// Whether two runs' samples are the same, bit for bit (NaN channels included).
fn same(a: &[Sample], b: &[Sample]) -> bool {
    let bits = |s: &Sample| s.columns().map(f64::to_bits);
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| bits(x) == bits(y))
}

/// The index of the sample at time `t_s` (1 kHz).
fn at(t_s: f64) -> usize {
    (t_s * 1000.0).round() as usize
}

#[test]
fn a_drift_reads_its_slope_then_saturates() {
    // ideal sensors: the reading is the true pressure plus the offset, to rounding
    let f = run(
        "loaded-sine",
        SensorParams::ideal(),
        &["p1:drift=6MPa/min,max=500kPa@2s"],
        8.0,
    );
    let offset = |i: usize| f.samples[i].p1_pa - f.truth[i][I_P1];
    for i in 0..at(2.0) {
        assert_eq!(offset(i), 0.0, "t = {}", f.samples[i].t_s);
    }
    // 100 kPa/s from 2 s, at most 500 kPa (reached at 7 s)
    for (t, want) in [
        (2.0, 0.0),
        (3.0, 100e3),
        (4.5, 250e3),
        (6.9, 490e3),
        (7.0, 500e3),
        (7.9, 500e3),
    ] {
        assert!(
            (offset(at(t)) - want).abs() < 1e-6,
            "t = {t}: {} Pa",
            offset(at(t))
        );
    }
    let slope = (offset(at(6.0)) - offset(at(3.0))) / 3.0;
    assert!((slope - 1e5).abs() < 1e-6, "{slope} Pa/s");
    // p2 and x read true
    assert!(f
        .samples
        .iter()
        .zip(&f.truth)
        .all(|(s, y)| s.p2_pa == y[I_P2] && s.x_m == y[I_X]));
}

#[test]
fn faults_on_real_sensors_read_their_equations_to_one_adc_step() {
    let sensors = SensorParams::default();
    let lsb = sensors.pressure_lsb_pa();
    let specs = ["p1:drift=-200kPa/min,max=50kPa@2s", "p2:span=+2%@1s"];
    let (h, f) = (
        run("loaded-sine", sensors, &[], 20.0),
        run("loaded-sine", sensors, &specs, 20.0),
    );
    // the same noise: before the onsets the readings are the healthy ones, bit for bit
    assert!(same(&f.samples[..at(1.0)], &h.samples[..at(1.0)]));
    for i in at(1.0)..f.samples.len() {
        let t = f.samples[i].t_s;
        let drift = -(200e3 / 60.0 * (t - 2.0)).clamp(0.0, 50e3);
        let dp1 = f.samples[i].p1_pa - h.samples[i].p1_pa;
        assert!(
            (dp1 - drift).abs() <= lsb + 1e-6,
            "t = {t}: p1 {dp1} Pa against {drift}"
        );
        let dp2 = f.samples[i].p2_pa - h.samples[i].p2_pa;
        let span = 0.02 * h.truth[i][I_P2];
        assert!(
            (dp2 - span).abs() <= lsb + 1e-6,
            "t = {t}: p2 {dp2} Pa against {span}"
        );
        assert_eq!(f.samples[i].x_m, h.samples[i].x_m);
    }
    // the drift has reached its 50 kPa at 17 s: the last 3 s read 50 kPa low on average
    let tail = &f.samples[at(17.5)..];
    let mean = tail
        .iter()
        .zip(&h.samples[at(17.5)..])
        .map(|(a, b)| a.p1_pa - b.p1_pa)
        .sum::<f64>()
        / tail.len() as f64;
    assert!((mean + 50e3).abs() < 0.5 * lsb, "{mean} Pa");
}

#[test]
fn a_stuck_transducer_repeats_its_reading_at_the_onset() {
    let sensors = SensorParams::default();
    let (h, f) = (
        run("loaded-sine", sensors, &[], 6.0),
        run("loaded-sine", sensors, &["p1:stuck@2s"], 6.0),
    );
    let k = at(2.0);
    assert!(same(&f.samples[..k], &h.samples[..k]));
    assert_eq!(f.samples[k].p1_pa, h.samples[k].p1_pa);
    assert!(f.samples[k..].iter().all(|s| s.p1_pa == f.samples[k].p1_pa));
    // the healthy reading moves by megapascals meanwhile
    let (lo, hi) = h.samples[k..].iter().fold((f64::MAX, f64::MIN), |(lo, hi), s| {
        (lo.min(s.p1_pa), hi.max(s.p1_pa))
    });
    assert!(hi - lo > 1e6, "{lo}..{hi}");
    // the other channels' noise is drawn as before
    assert!(f
        .samples
        .iter()
        .zip(&h.samples)
        .all(|(a, b)| a.p2_pa == b.p2_pa && a.x_m == b.x_m));
}

#[test]
fn spikes_come_at_their_rate_with_their_amplitude() {
    // 0.5 per second over 20000 s: 10000 expected, σ = 100; within ±5σ
    let schedule = SensorFaultSchedule::parse_all(&["p2:spikes=2MPa,rate=0.5/s@0s"]).unwrap();
    let mut run_ = SensorFaultRun::new(schedule, 11);
    let (mut up, mut down) = (0u32, 0u32);
    for k in 0..20_000_000u64 {
        let s = run_.read(Channel::P2, k as f64 * 1e-3, 1e-3, |d: Distortion| d.spike_si);
        match s {
            0.0 => {}
            2e6 => up += 1,
            -2e6 => down += 1,
            other => panic!("spike {other} Pa"),
        }
    }
    assert!((up + down).abs_diff(10_000) <= 500, "{up} + {down}");
    // the sign at random: 5000 each, σ ≈ 71
    assert!(up.abs_diff(down) <= 700, "{up} up, {down} down");
    // in the simulator: 5 per second over 20 s from 10 s (100 expected, σ = 10), ±2 MPa each
    let sensors = SensorParams::default();
    let spec = ["p2:spikes=2MPa,rate=5/s@10s"];
    let (h, f) = (
        run("loaded-sine", sensors, &[], 30.0),
        run("loaded-sine", sensors, &spec, 30.0),
    );
    assert!(same(&f.samples[..at(10.0)], &h.samples[..at(10.0)]));
    let spikes: Vec<(f64, f64)> = f
        .samples
        .iter()
        .zip(&h.samples)
        .map(|(a, b)| (a.p2_pa, a.p2_pa - b.p2_pa))
        .filter(|(_, d)| *d != 0.0)
        .collect();
    assert!((60..=140).contains(&spikes.len()), "{} spikes", spikes.len());
    // each ±2 MPa to one ADC step, or clipped by the ADC at 0 or its full scale
    let lsb = sensors.pressure_lsb_pa();
    let clipped = |p: f64| p == 0.0 || p == sensors.pressure_full_scale_pa;
    for (p, d) in &spikes {
        assert!(
            (d.abs() - 2e6).abs() <= lsb || clipped(*p),
            "a spike of {d} Pa to {p} Pa"
        );
    }
    assert!(spikes.iter().filter(|(p, _)| clipped(*p)).count() < 10);
}

#[test]
fn a_position_drift_reads_to_one_count_and_a_closed_loop_follows_it() {
    let sensors = SensorParams::default();
    let count = sensors.encoder_resolution_m;
    // open loop: the command does not read x, so the rig moves as without the fault
    let spec = ["x:drift=6mm/min@1s"];
    let (h, f) = (
        run("open-loop-sine", sensors, &[], 10.0),
        run("open-loop-sine", sensors, &spec, 10.0),
    );
    assert!(f.truth == h.truth);
    for i in 0..f.samples.len() {
        let t = f.samples[i].t_s;
        let drift = (1e-4 * (t - 1.0)).max(0.0);
        let dx = f.samples[i].x_m - h.samples[i].x_m;
        assert!(
            (dx - drift).abs() <= count + 1e-12,
            "t = {t}: {dx} m against {drift}"
        );
    }
    // closed loop: the controller reads the faulty x, so the rod moves by −offset
    let (h, f) = (
        run("loaded-sine", sensors, &[], 10.0),
        run("loaded-sine", sensors, &spec, 10.0),
    );
    assert!(f.truth[..=at(1.0)] == h.truth[..=at(1.0)]);
    let shift = (at(9.0)..at(10.0))
        .map(|i| f.truth[i][I_X] - h.truth[i][I_X])
        .sum::<f64>()
        / 1000.0;
    // offset 0.8 to 0.9 mm over the last second, its mean 0.85 mm
    assert!((shift + 0.85e-3).abs() < 0.1e-3, "{shift} m");
}

#[test]
fn pressure_faults_leave_the_rig_as_it_was() {
    let specs = [
        "p1:drift=300kPa/min,max=500kPa@1s",
        "p1:span=-3%@2s",
        "p2:stuck@3s",
        "p1:spikes=2MPa,rate=2/s@0s",
    ];
    for scenario in ["loaded-sine", "closed-loop-random", "open-loop-sine"] {
        let (h, f) = (
            run(scenario, SensorParams::default(), &[], 6.0),
            run(scenario, SensorParams::default(), &specs, 6.0),
        );
        assert!(f.truth == h.truth, "{scenario}");
        assert!(f
            .samples
            .iter()
            .zip(&h.samples)
            .all(|(a, b)| a.x_m == b.x_m && a.u_v == b.u_v));
        assert!(f.samples.iter().zip(&h.samples).any(|(a, b)| a.p1_pa != b.p1_pa));
    }
    // faults yet to come: the healthy simulator's readings, bit for bit
    let later = [
        "p1:stuck@100s",
        "x:drift=1mm/min@100s",
        "p2:spikes=2MPa,rate=100/s@100s",
        "none",
    ];
    let f = run("loaded-sine", SensorParams::default(), &later, 2.0);
    let h = run("loaded-sine", SensorParams::default(), &[], 2.0);
    assert!(same(&f.samples, &h.samples));
    assert_eq!(SensorFaultSchedule::parse_all(&later).unwrap().faults.len(), 3);
    assert_eq!(SensorFault::parse("p1:stuck@0s").unwrap().onset_s, 0.0);
}
