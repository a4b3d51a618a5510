//! The command lines of the stages a run starts, and of their restarts.

use std::net::SocketAddr;

use frames::SensorFrame;

use crate::stages::Stage;

/// Where the acquisition's samples come from.
#[derive(Debug, Clone)]
pub(super) enum Samples {
    /// The simulated rig: scenario, run length in s, fault specs.
    Sim {
        scenario: String,
        seconds: f64,
        faults: Vec<String>,
    },
    /// A UDP sensor stream on this address, ending after this many s without a datagram.
    Udp { addr: SocketAddr, idle_s: f64 },
}

/// What every stage of one run is started with.
#[derive(Debug, Clone)]
pub(super) struct StageArgs {
    pub(super) rig: String,
    /// The config every stage reads (the run's config.toml).
    pub(super) config: String,
    /// The wait mode of the estimator and classifier.
    pub(super) mode: String,
    /// The output directory (the recorder's log goes there).
    pub(super) out_dir: std::path::PathBuf,
    /// Replace an earlier run's log (`--force`).
    pub(super) force: bool,
    /// Subscribers of the frames topic a (re)started acquisition waits for:
    /// [`FRAME_SUBSCRIBERS`], one fewer once the recorder is given up.
    pub(super) frame_subscribers: usize,
    pub(super) samples: Samples,
    /// The acquisition pacer's spin before each deadline, µs (0: sleep only).
    pub(super) spin_us: u64,
}

/// Subscribers of the frames topic the acquisition waits for before it
/// publishes: the estimator, the recorder and the supervisor.
pub(super) const FRAME_SUBSCRIBERS: usize = 3;

/// Whether `name` is a further part of a run's log (`run-N.mcap`, N ≥ 1).
pub(super) fn is_log_part(name: &str) -> bool {
    name.strip_prefix("run-")
        .and_then(|n| n.strip_suffix(".mcap"))
        .is_some_and(|n| !n.is_empty() && n.bytes().all(|b| b.is_ascii_digit()))
}

/// Where a restarted stage takes over.
#[derive(Debug, Clone, Default)]
pub(super) struct Resume {
    /// The last sensor frame the supervisor received (a restarted acquisition goes on after it).
    pub(super) last_frame: Option<SensorFrame>,
    /// The last estimate the stage's previous process handled, as far as the
    /// supervisor knows (a restarted estimator or classifier counts the estimates
    /// after it as a gap).
    pub(super) after_estimate: Option<u64>,
}

impl StageArgs {
    /// The log part the recorder's `restart`-th process writes: `run.mcap`, then
    /// `run-1.mcap`, `run-2.mcap`, ...
    pub(super) fn log_part(&self, restart: u32) -> std::path::PathBuf {
        self.out_dir.join(pipeline::logs::part_name("run", restart))
    }

    /// The arguments of `stage`'s `restart`-th restart (0: the first start). A
    /// restarted recorder writes `run-N.mcap`, continuing the earlier parts; a
    /// restarted acquisition continues the stream after `resume.last_frame` (the
    /// last frame the supervisor received); a restarted estimator or classifier
    /// takes over after the estimate `resume.after_estimate` (its predecessor's
    /// last, as the supervisor saw it), so what it missed is a gap.
    pub(super) fn of(&self, stage: Stage, restart: u32, resume: &Resume) -> Vec<String> {
        let s = |v: &str| v.to_string();
        let mut a = vec![s("--rig"), self.rig.clone()];
        match stage {
            Stage::Recorder => {
                let log = self.log_part(restart).display().to_string();
                a.extend([s("--out"), log, s("--grace-ms"), s("1500")]);
                for part in 0..restart {
                    a.push(s("--continues"));
                    a.push(self.log_part(part).display().to_string());
                }
                if self.force {
                    a.push(s("--force"));
                }
            }
            Stage::Classifier | Stage::Estimator | Stage::EstimatorClassifier => {
                a.extend([s("--config"), self.config.clone(), s("--mode"), self.mode.clone()]);
                if let Some(seq) = resume.after_estimate.filter(|_| restart > 0) {
                    a.extend([s("--resume-after-seq"), seq.to_string()]);
                }
            }
            Stage::LiveView | Stage::Gateway | Stage::Opcua => a.extend([s("--config"), self.config.clone()]),
            Stage::Acquisition => {
                match &self.samples {
                    Samples::Udp { addr, idle_s } => a.extend([
                        s("--udp"),
                        addr.to_string(),
                        s("--udp-idle-timeout-s"),
                        idle_s.to_string(),
                    ]),
                    Samples::Sim {
                        scenario,
                        seconds,
                        faults,
                    } => {
                        a.extend([
                            s("--scenario"),
                            scenario.clone(),
                            s("--seconds"),
                            seconds.to_string(),
                        ]);
                        for f in faults {
                            a.extend([s("--fault"), f.clone()]);
                        }
                    }
                }
                a.extend([
                    s("--config"),
                    self.config.clone(),
                    s("--wait-subscribers"),
                    self.frame_subscribers.to_string(),
                ]);
                if self.spin_us > 0 {
                    a.extend([s("--spin-us"), self.spin_us.to_string()]);
                }
                if let Some(f) = resume.last_frame.as_ref().filter(|_| restart > 0) {
                    // f64 and u64 print in a form that parses back to the same value
                    a.extend([
                        s("--resume-seq"),
                        f.seq.to_string(),
                        s("--resume-t-s"),
                        f.t_s.to_string(),
                        s("--resume-mono-ns"),
                        f.acq_mono_ns.to_string(),
                    ]);
                }
            }
        }
        a
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_restarted_acquisition_resumes_after_the_last_frame() {
        let args = StageArgs {
            rig: "r".into(),
            config: "c.toml".into(),
            mode: "event".into(),
            out_dir: "out".into(),
            force: false,
            frame_subscribers: FRAME_SUBSCRIBERS,
            samples: Samples::Sim {
                scenario: "loaded-sine".into(),
                seconds: 20.0,
                faults: vec!["ext1:0.5lpm@12s".into()],
            },
            spin_us: 60,
        };
        // the acquisition's pacer spins (low-latency mode); no other stage has a pacer
        assert!(args
            .of(Stage::Acquisition, 0, &Resume::default())
            .join(" ")
            .contains("--spin-us 60"));
        assert!(!args
            .of(Stage::Estimator, 0, &Resume::default())
            .join(" ")
            .contains("--spin-us"));
        let f = SensorFrame {
            seq: 6123,
            t_s: 6.123,
            acq_mono_ns: 987_654_321,
            ..SensorFrame::default()
        };
        let resume = Resume {
            last_frame: Some(f),
            after_estimate: Some(6100),
        };
        let first = args.of(Stage::Acquisition, 0, &resume);
        assert!(!first.iter().any(|a| a.starts_with("--resume")), "{first:?}");
        let again = args.of(Stage::Acquisition, 1, &resume).join(" ");
        assert!(
            again.ends_with(
                "--wait-subscribers 3 --spin-us 60 --resume-seq 6123 --resume-t-s 6.123 --resume-mono-ns 987654321"
            ),
            "{again}"
        );
        assert!(again.contains("--fault ext1:0.5lpm@12s"), "{again}");
        let rec = args.of(Stage::Recorder, 2, &resume).join(" ");
        assert!(
            rec.contains("--out out/run-2.mcap")
                && rec.ends_with("--continues out/run.mcap --continues out/run-1.mcap"),
            "{rec}"
        );
        assert!(is_log_part("run-1.mcap") && is_log_part("run-12.mcap"));
        assert!(!is_log_part("run.mcap") && !is_log_part("run-.mcap") && !is_log_part("run-1a.mcap"));
        for stage in [Stage::Estimator, Stage::Classifier] {
            assert!(!args.of(stage, 0, &resume).join(" ").contains("--resume"));
            let again = args.of(stage, 1, &resume).join(" ");
            assert!(again.ends_with("--resume-after-seq 6100"), "{again}");
        }
    }
}
