//! The command lines of the stages a run starts, and of their restarts.

use std::net::SocketAddr;
use std::path::Path;

use frames::SensorFrame;

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
    pub(super) samples: Samples,
}

/// Subscribers of the frames topic the acquisition waits for before it
/// publishes: the estimator, the recorder and the supervisor.
pub(super) const FRAME_SUBSCRIBERS: usize = 3;

impl StageArgs {
    /// The arguments of `stage`'s `restart`-th restart (0: the first start). A
    /// restarted recorder writes `run-N.mcap`; a restarted acquisition continues
    /// the stream after `last_frame` (the last frame the supervisor received).
    pub(super) fn of(&self, stage: &str, restart: u32, last_frame: Option<&SensorFrame>) -> Vec<String> {
        let s = |v: &str| v.to_string();
        let mut a = vec![s("--rig"), self.rig.clone()];
        match stage {
            "recorder" => {
                let log = if restart == 0 {
                    s("run.mcap")
                } else {
                    format!("run-{restart}.mcap")
                };
                let log = Path::new(&self.out_dir).join(log).display().to_string();
                a.extend([s("--out"), log, s("--grace-ms"), s("1500")]);
                if self.force {
                    a.push(s("--force"));
                }
            }
            "classifier" | "estimator" => {
                a.extend([s("--config"), self.config.clone(), s("--mode"), self.mode.clone()]);
            }
            "liveview" | "gateway" => a.extend([s("--config"), self.config.clone()]),
            _ => {
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
                    FRAME_SUBSCRIBERS.to_string(),
                ]);
                if let Some(f) = last_frame.filter(|_| restart > 0) {
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
            samples: Samples::Sim {
                scenario: "loaded-sine".into(),
                seconds: 20.0,
                faults: vec!["ext1:0.5lpm@12s".into()],
            },
        };
        let f = SensorFrame {
            seq: 6123,
            t_s: 6.123,
            acq_mono_ns: 987_654_321,
            ..SensorFrame::default()
        };
        let first = args.of("acquisition", 0, Some(&f));
        assert!(!first.iter().any(|a| a.starts_with("--resume")), "{first:?}");
        let again = args.of("acquisition", 1, Some(&f)).join(" ");
        assert!(
            again.ends_with(
                "--wait-subscribers 3 --resume-seq 6123 --resume-t-s 6.123 --resume-mono-ns 987654321"
            ),
            "{again}"
        );
        assert!(again.contains("--fault ext1:0.5lpm@12s"), "{again}");
        let rec = args.of("recorder", 2, None).join(" ");
        assert!(rec.contains("--out out/run-2.mcap"), "{rec}");
    }
}
