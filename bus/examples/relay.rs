//! A pass-through stage on [`bus::run_stage`]: each sensor frame becomes an
//! estimate carrying its seq and time stamps (a template for the estimator
//! shell, and a way to measure the hops without an EKF).
//!
//! ```text
//! acquisition --rig r1 --seconds 12 &
//! cargo run -p bus --example relay -- r1 event &
//! cargo run -p bus --example hop -- r1 event 10 estimates
//! ```

use bus::{run_stage, Bus, BusConfig, StageOptions, WaitMode};
use frames::{EstimateFrame, SensorFrame};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let rig = args.get(1).map(String::as_str).unwrap_or("r1");
    let mode = WaitMode::parse(args.get(2).map(String::as_str).unwrap_or("event"))?;
    let stop = bus::stop_on_signals();
    let bus = Bus::open(rig, BusConfig::from_env()?)?;
    let mut opts = StageOptions::new(frames::stage::ESTIMATOR, mode);
    opts.exit_on_end_of_stream = true;
    let report = run_stage::<SensorFrame, EstimateFrame>(&bus, &opts, stop, |input, out| {
        out.seq = input.seq;
        out.acq_mono_ns = input.acq_mono_ns;
        out.est_recv_mono_ns = input.recv_mono_ns;
        out.t_s = input.t_s;
        out.state[1] = input.p1_pa;
        out.state[2] = input.p2_pa;
        out.est_done_mono_ns = bus::monotonic_ns();
        true
    })?;
    eprintln!("relay: {report}");
    Ok(())
}
