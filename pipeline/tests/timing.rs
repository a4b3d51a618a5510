//! Commissioning reads the recording's timing from it and puts it into the
//! leak filter: the DAQ's jitter into its measurement noise, each pressure
//! transducer's lag into its NIS, up to the longest lag the datasheet's
//! response time allows (docs/identification.md), and the transducers'
//! delay, fitted to the leak sizes' swings, into what it takes off them.

mod common;

use config::Config;
use model::params::ActuatorParams;
use model::scenario::Scenario;
use model::{Datasheet, SensorParams};

/// What `identify_rig` makes of a 60 s lift recording taken by `sensors`,
/// with a model that knows the sensors but neither their jitter nor their
/// lag, and `datasheet` (if any).
fn identified_on_lift(sensors: SensorParams, datasheet: Option<Datasheet>) -> Config {
    let (_dir, csv, cfg) = lift_recording(sensors, datasheet);
    pipeline::commission::identify_rig(&csv, &cfg).expect("identified")
}

/// A 60 s lift recording taken by `sensors` (in a scratch folder, kept while
/// it lives), and a config whose model knows the sensors but neither their
/// jitter nor their lag, with `datasheet` (if any).
fn lift_recording(
    sensors: SensorParams,
    datasheet: Option<Datasheet>,
) -> (scratch::ScratchDir, std::path::PathBuf, Config) {
    let rig = ActuatorParams::vertical_lift();
    let scenario = Scenario::by_name("lift", 3, 60.0).expect("scenario");
    let dir = scratch::ScratchDir::new("timing");
    let csv = dir.join("lift.csv");
    common::record(&rig, sensors, scenario, 7, &csv);
    let cfg = Config {
        model: rig,
        sensors: SensorParams {
            sample_jitter_s: 0.0,
            pressure_lag_s: 0.0,
            ..sensors
        },
        datasheet,
        ..Config::default()
    };
    (dir, csv, cfg)
}

/// The jitter put into `[leak_filter] sample_jitter_s` for a DAQ that reads
/// each sample `jitter_s` (RMS) off its stamp.
fn commissioned_jitter_s(jitter_s: f64) -> f64 {
    let sensors = SensorParams {
        sample_jitter_s: jitter_s,
        ..SensorParams::plant()
    };
    identified_on_lift(sensors, None).leak_filter.sample_jitter_s
}

/// 30 µs simulated: read within 15 %. None simulated: none put in.
#[test]
fn commissioning_puts_the_jitter_it_reads_into_the_leak_filter() {
    let read = commissioned_jitter_s(30e-6);
    assert!((read / 30e-6 - 1.0).abs() < 0.15, "read {read} s");
    assert_eq!(commissioned_jitter_s(0.0), 0.0);
}

/// The lags put into `[leak_filter] pressure_lag_s` for transducers lagging
/// by `lag_s`, with a datasheet whose transducers respond within
/// `response_time_s` (10-90 %; `None`: no datasheet).
fn commissioned_lag_s(lag_s: f64, response_time_s: Option<f64>) -> [f64; 2] {
    let sensors = SensorParams {
        pressure_lag_s: lag_s,
        ..SensorParams::plant()
    };
    let datasheet = response_time_s.map(|t| {
        let mut d = config::init::example(true);
        d.pressure_transducers.response_time_s = t;
        d
    });
    identified_on_lift(sensors, datasheet).leak_filter.pressure_lag_s
}

/// 0.8 ms simulated: read within 20 % on each channel. None simulated: none put in. A datasheet's 0.6 ms response time
/// allows 0.6 ms / ln 9 = 0.27 ms: the lag put in stops there.
#[test]
fn commissioning_puts_the_lag_it_reads_into_the_leak_filter() {
    let lag_s = 0.8e-3;
    let read = commissioned_lag_s(lag_s, None);
    for lag in read {
        assert!(
            (lag / lag_s - 1.0).abs() < 0.2,
            "read {read:?} s against {lag_s} s"
        );
    }
    assert_eq!(commissioned_lag_s(0.0, None), [0.0; 2]);
    let bound = 0.6e-3 / 9f64.ln();
    assert_eq!(commissioned_lag_s(0.8e-3, Some(0.6e-3)), [bound; 2]);
}

/// The delay `commission` takes off the leak sizes for transducers lagging
/// by `lag_s`, s.
fn commissioned_delay_s(lag_s: f64) -> f64 {
    let sensors = SensorParams {
        pressure_lag_s: lag_s,
        ..SensorParams::plant()
    };
    let (_dir, csv, cfg) = lift_recording(sensors, None);
    pipeline::commission::commission(&csv, &cfg)
        .expect("commissioned")
        .leak_filter
        .lag_correction_s
}

/// 0.8 ms simulated: the delay fitted to the leak sizes' swings is taken,
/// within 30 % of the lag (a first-order lag delays a swing by less than τ
/// and damps its fast part). None simulated: none taken.
#[test]
fn commissioning_takes_the_transducers_delay_off_the_leak_sizes() {
    let lag_s = 0.8e-3;
    let taken = commissioned_delay_s(lag_s);
    assert!(
        (taken / lag_s - 1.0).abs() < 0.3,
        "took {taken} s against {lag_s} s"
    );
    assert_eq!(commissioned_delay_s(0.0), 0.0);
}
