//! Commissioning reads the DAQ's timing jitter from the recording and puts
//! it into the leak filter's measurement noise (docs/identification.md).

use std::fs::File;
use std::io::BufWriter;

use config::Config;
use model::params::ActuatorParams;
use model::scenario::Scenario;
use model::sim::{SimSettings, Simulator};
use model::{FaultSchedule, SensorParams};

/// The jitter `identify_rig` puts into `[leak_filter] sample_jitter_s` for a
/// 60 s lift recording whose DAQ reads each sample `jitter_s` (RMS) off its stamp.
fn commissioned_jitter_s(jitter_s: f64) -> f64 {
    let rig = ActuatorParams::vertical_lift();
    let sensors = SensorParams {
        sample_jitter_s: jitter_s,
        ..SensorParams::plant()
    };
    let scenario = Scenario::by_name("lift", 3, 60.0).expect("scenario");
    let mut sim = Simulator::new(
        rig.clone(),
        sensors,
        SimSettings::default(),
        scenario,
        FaultSchedule::default(),
        7,
    )
    .expect("rig");
    let samples = sim.run(60.0);
    let dir = scratch::ScratchDir::new("jitter");
    let csv = dir.join("lift.csv");
    let mut w = BufWriter::new(File::create(&csv).expect("csv"));
    pipeline::simulate::write_csv(&mut w, &samples).expect("written");
    drop(w);
    let cfg = Config {
        model: rig,
        sensors: SensorParams {
            sample_jitter_s: 0.0,
            ..sensors
        },
        ..Config::default()
    };
    let out = pipeline::commission::identify_rig(&csv, &cfg).expect("identified");
    out.leak_filter.sample_jitter_s
}

/// 30 µs simulated: read within 15 %. None simulated: none put in.
#[test]
fn commissioning_puts_the_jitter_it_reads_into_the_leak_filter() {
    let read = commissioned_jitter_s(30e-6);
    assert!((read / 30e-6 - 1.0).abs() < 0.15, "read {read} s");
    assert_eq!(commissioned_jitter_s(0.0), 0.0);
}
