//! The `estimator` process: sensor frames in, estimate frames out, over
//! iceoryx2 (a thin shell around [`filter::EstimatorStage`]).
//!
//! ```text
//! estimator --rig rig1 [--config leakwatch.toml] [--mode event|low-latency|busy-poll]
//! ```

use std::path::Path;
use std::process::ExitCode;

use crate::wire::EstimateWire;
use bus::{run_stage_with, Received, StageOptions};
use clap::Parser;
use filter::{EstimatorStage, StageEstimate, FLAG_AFTER_GAP, FLAG_RESET};
use frames::{sensor_flags, EstimateFrame, SensorFrame};
use model::Sample;

#[derive(Parser)]
#[command(
    name = "estimator",
    about = "leakwatch estimator stage: sensor frames -> EKF estimates over iceoryx2"
)]
struct Args {
    #[command(flatten)]
    stage: bus::StageArgs,
}

/// The estimator stage the configuration file `path` describes (`[model]`,
/// `[estimator]`, `[leak_filter]`; the defaults without a file). The thesis
/// filter runs only with the thesis' baseline (`[classifier] thesis_baseline`,
/// `leakwatch run --thesis-baseline`): nothing else reads it, and it is a
/// third of the stage's work. Without it the estimates' thesis fields are NaN.
pub fn load_stage(path: Option<&Path>) -> Result<EstimatorStage, String> {
    let cfg = config::Config::load_or_default(path)?;
    Ok(EstimatorStage::new(cfg.model, cfg.leak_filter, cfg.estimator)?
        .with_thesis(cfg.classifier.thesis_baseline))
}

/// Where an estimator process joins its sensor stream.
#[derive(Debug, Clone, Copy)]
pub struct Join {
    /// No frame estimated yet.
    first: bool,
    /// The frame the stage's previous process handled last (a restart).
    resumed_after: Option<u64>,
}

impl Join {
    /// A process that takes over after frame `resumed_after` (a restart), or
    /// starts afresh (`None`).
    pub fn new(resumed_after: Option<u64>) -> Join {
        Join {
            first: true,
            resumed_after,
        }
    }
}

/// The estimator's work on one sensor frame, whichever process runs it: the
/// estimate of `input` written into `out` (sequence number, clocks, both filters).
/// The frame's after-gap flag goes to the stage with the sample
/// ([`EstimatorStage::on_sample_flagged`]): a sensor stream that restarted (its
/// time went back, or a flagged gap its time does not show: a sender's reboot)
/// re-anchors both filters and is said on stderr, one line per restart.
/// The first estimate of a process that joins a stream already running (a
/// restart, `join` resumed; or a first frame after frame 0: a stage swapped by
/// hand) is marked reset and after-gap, as its filter starts again without the
/// frames before (said so on stderr, once).
#[inline]
pub fn estimate_frame(
    stage: &mut EstimatorStage,
    input: &Received<SensorFrame>,
    out: &mut EstimateFrame,
    join: &mut Join,
) {
    let after_gap = input.frame.flags & sensor_flags::AFTER_GAP != 0;
    let restarts = stage.stream_restarts();
    let mut e = stage.on_sample_flagged(&Sample::from(&input.frame), after_gap);
    if stage.stream_restarts() != restarts {
        if let Some(restart) = stage.last_restart() {
            bus::say!("estimator: {restart}");
        }
    }
    if std::mem::take(&mut join.first) && (join.resumed_after.is_some() || input.seq > 0) {
        mark_restart(&mut e);
        match join.resumed_after {
            Some(last) => bus::say!(
                "estimator: restarted after frame {last}: {} frames not estimated before frame {} (a gap); its \
                 estimate is marked reset and after-gap",
                input.missing_before, input.seq
            ),
            None => bus::say!(
                "estimator: joined the stream at frame {}: its estimate is marked reset and after-gap",
                input.seq
            ),
        }
    }
    out.seq = input.seq;
    out.acq_mono_ns = input.acq_mono_ns;
    out.est_recv_mono_ns = input.recv_mono_ns;
    e.write_frame(out);
    out.est_done_mono_ns = bus::monotonic_ns();
}

/// What the leak filter of `stage` makes of the oil's stiffness now, as a line for
/// the process log (printed at exit); `None` if it does not estimate it.
pub fn oil_stiffness(stage: &EstimatorStage) -> Option<String> {
    let leak = stage.leak();
    let (theta, sigma) = leak.bulk_scale()?;
    filter::oil_stiffness_line(theta, sigma, leak.model().params.bulk_modulus_pa)
}

/// How often the sensor stream of `stage` restarted, as a line for the process
/// log (printed at exit); `None` if it never did.
pub fn restarts_line(stage: &EstimatorStage) -> Option<String> {
    match stage.stream_restarts() {
        0 => None,
        1 => Some("sensor stream restarted once: filters re-anchored".to_string()),
        n => Some(format!(
            "sensor stream restarted {n} times: filters re-anchored each time"
        )),
    }
}

fn run(args: Args) -> Result<(), String> {
    let mut stage = load_stage(args.stage.config.as_deref())?;
    let mode = args.stage.wait_mode()?;
    let stop = bus::stop_on_signals();
    let bus = args.stage.open_bus()?;
    let mut opts = StageOptions::new(frames::stage::ESTIMATOR, mode);
    opts.exit_on_end_of_stream = args.stage.exit_at_end;
    opts.resume_after_seq = args.stage.resume_after_seq;
    // the first estimate of one that joins a running stream says that its filter started again
    let mut join = Join::new(args.stage.resume_after_seq);
    // (in low-latency mode both filters take a throw-away step after each sleep,
    // just before the frame is due: the frame's own step finds them in the caches)
    let report = run_stage_with::<SensorFrame, EstimateFrame, _>(
        &bus,
        &opts,
        stop,
        &mut stage,
        |stage, input, out| {
            estimate_frame(stage, input, out, &mut join);
            true
        },
        EstimatorStage::warm_up,
    )
    .map_err(|e| e.to_string())?;
    bus::say!("estimator: {report}");
    if let Some(line) = restarts_line(&stage) {
        bus::say!("estimator: {line}");
    }
    if let Some(line) = oil_stiffness(&stage) {
        bus::say!("estimator: {line}");
    }
    Ok(())
}

/// Marks the first estimate of a restarted estimator: both filters started
/// again (reset) after frames they did not see (after-gap).
fn mark_restart(e: &mut StageEstimate) {
    for f in [&mut e.leak, &mut e.thesis] {
        f.flags |= FLAG_RESET | FLAG_AFTER_GAP;
    }
}

/// Runs the estimator process with command-line arguments `args` (the first is the
/// program name, as from `std::env::args_os`); the exit code says whether it succeeded.
pub fn main(args: impl IntoIterator<Item = std::ffi::OsString>) -> ExitCode {
    match run(Args::parse_from(args)) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            bus::say!("estimator: error: {e}");
            ExitCode::FAILURE
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use filter::FLAG_REANCHORED;
    use frames::estimate_flags;
    use model::{FaultSchedule, Scenario, Simulator};

    /// `seconds` of the closed-loop sine on the default rig (seed `seed`), times from 0 s.
    fn record(seconds: f64, seed: u64) -> Vec<Sample> {
        let sc = Scenario::by_name("closed-loop-sine", 3, seconds).expect("scenario");
        let mut sim = Simulator::with_default_sensors(
            model::ActuatorParams::default(),
            sc,
            FaultSchedule::default(),
            seed,
        )
        .expect("rig");
        sim.run(seconds)
    }

    /// Frame `seq` with sample `s` and sensor flags `flags`, as the subscriber hands it on.
    fn received(seq: u64, s: &Sample, flags: u32) -> Received<SensorFrame> {
        Received {
            frame: SensorFrame {
                seq,
                flags,
                ..SensorFrame::from(s)
            },
            recv_mono_ns: 0,
            missing_before: 0,
            restarted: false,
            publisher_pid: 0,
        }
    }

    /// The thesis filter runs with the thesis' baseline only: a configuration
    /// without it (and no configuration) gives frames whose thesis fields are
    /// NaN and flagged skipped, and the leak filter's fields are the same bits.
    #[test]
    fn the_thesis_filter_runs_with_its_baseline_only() {
        let dir = std::env::temp_dir().join(format!("leakwatch-shell-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        let path = |name: &str, text: &str| {
            let p = dir.join(name);
            std::fs::write(&p, text).expect("config written");
            p
        };
        let on = path(
            "on.toml",
            "[classifier]\nthesis_baseline = true\nwarmup_s = 3.0\n",
        );
        let off = path("off.toml", "[classifier]\nthesis_baseline = false\n");
        let mut stages = [
            load_stage(None).expect("stage"),
            load_stage(Some(&off)).expect("stage"),
            load_stage(Some(&on)).expect("stage"),
        ];
        assert_eq!(stages.each_ref().map(|s| s.thesis_runs()), [false, false, true]);
        let mut joins = [Join::new(None), Join::new(None), Join::new(None)];
        let mut out = [EstimateFrame::default(); 3];
        for (seq, s) in record(0.5, 3).iter().enumerate() {
            for k in 0..3 {
                estimate_frame(
                    &mut stages[k],
                    &received(seq as u64, s, 0),
                    &mut out[k],
                    &mut joins[k],
                );
            }
            for o in &out[..2] {
                assert!(o.th_state.iter().all(|v| v.is_nan()), "{:?}", o.th_state);
                assert_ne!(o.th_flags & estimate_flags::SKIPPED, 0);
            }
            assert!(out[2].th_state.iter().all(|v| v.is_finite()));
            assert_eq!(out[2].th_flags & estimate_flags::SKIPPED, 0);
            let bits = |o: &EstimateFrame| o.state.map(f64::to_bits);
            assert_eq!(bits(&out[0]), bits(&out[2]));
            assert_eq!(bits(&out[1]), bits(&out[2]));
        }
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// A stage process started on a config with a `[datasheet]` and a partial
    /// `[leak_filter]` believes the rig `leakwatch` derives from it: the model
    /// from the datasheet, the rest of the leak filter's tuning its own defaults.
    #[test]
    fn a_stage_on_a_datasheet_config_models_the_derived_rig() {
        let dir = std::env::temp_dir().join(format!("leakwatch-shell-ds-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        let text =
            config::init::template(&config::init::example(true)) + "\n[leak_filter]\nq_leak_m6_s2 = 3e-18\n";
        let path = dir.join("lift.toml");
        std::fs::write(&path, &text).expect("config written");
        let cfg = config::Config::parse(&text).expect("valid");
        let stage = load_stage(Some(&path)).expect("stage");
        assert_eq!(stage.leak().model().params, cfg.model);
        assert!(cfg.model.rod_side_area_m2.is_some());
        // the leak filter: 12 states (its own default, not the thesis' 7), R from the datasheet
        let tuning = stage.leak().tuning();
        assert_eq!((tuning.states, tuning.q_leak_m6_s2), (12, 3e-18));
        assert_eq!(tuning, &cfg.leak_filter);
        assert_ne!(cfg.model, model::ActuatorParams::default());
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// A rebooted UDP sender as the acquisition publishes it (sequence on by
    /// one, time back to 0 s, the frame flagged after a gap): the estimate frame
    /// of its first sample says re-anchored and after-gap, and so does the
    /// estimate the classifier reads back from the wire.
    #[test]
    fn a_sensor_stream_that_restarts_reanchors_and_the_wire_says_so() {
        // both filters: the thesis filter re-anchors too
        let mut stage = load_stage(None).expect("stage").with_thesis(true);
        let mut join = Join::new(None);
        let mut out = EstimateFrame::default();
        let mut seq = 0;
        for s in &record(2.5, 7) {
            estimate_frame(&mut stage, &received(seq, s, 0), &mut out, &mut join);
            assert_eq!(
                out.flags & (estimate_flags::REANCHORED | estimate_flags::RESET),
                0
            );
            seq += 1;
        }
        assert_eq!(restarts_line(&stage), None);
        let new = record(0.5, 11);
        estimate_frame(
            &mut stage,
            &received(seq, &new[0], sensor_flags::AFTER_GAP),
            &mut out,
            &mut join,
        );
        let reanchored = estimate_flags::REANCHORED | estimate_flags::AFTER_GAP;
        assert_eq!((out.seq, out.t_s), (seq, 0.0));
        assert_eq!(out.flags & reanchored, reanchored, "{:#x}", out.flags);
        assert_eq!(out.th_flags & reanchored, reanchored, "{:#x}", out.th_flags);
        assert_eq!(out.flags & (estimate_flags::RESET | estimate_flags::SKIPPED), 0);
        assert!(
            (out.state[3] - new[0].x_m).abs() < 5e-6,
            "x {} m vs {} m",
            out.state[3],
            new[0].x_m
        );
        let back = StageEstimate::from_frame(&out, 0);
        assert_ne!(
            back.leak.flags & FLAG_REANCHORED,
            0,
            "the detector's input is flagged"
        );
        assert_eq!(stage.stream_restarts(), 1);
        assert_eq!(
            restarts_line(&stage).as_deref(),
            Some("sensor stream restarted once: filters re-anchored")
        );
        for s in &new[1..] {
            seq += 1;
            estimate_frame(&mut stage, &received(seq, s, 0), &mut out, &mut join);
            assert_eq!(out.flags & reanchored, 0);
            assert!(out.nis.is_finite());
        }
        assert_eq!(stage.stream_restarts(), 1);
    }
}
