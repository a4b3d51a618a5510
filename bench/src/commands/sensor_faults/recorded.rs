//! `bench sensor-faults --data DIR`: the faults drawn onto a plant-style
//! folder's healthy recordings instead of simulated runs.
//!
//! The folder is laid out like plant_dev: `commission_cold.csv[.gz]`,
//! `datasheet.toml` (or `--config`) and `run_*/` with `measured.csv[.gz]` and
//! `truth.json`. The chain is commissioned as `bench detection --data` does
//! (the README's workflow; without a recording, each run learns its healthy
//! state in its first seconds). Each run whose truth has no fault is a healthy
//! recording; instance i takes recording i mod R (R recordings) and draws its
//! own faults. Each fault is laid onto the recorded readings as the simulator
//! lays it onto its own ([`SensorFaultRun`]): a drift's offset and a span's
//! gain on the reading (its noise included), a stuck reading frozen, outliers
//! added. The recordings' own healthy run is watched once per recording.

use std::path::{Path, PathBuf};

use config::Config;
use model::rng::Rng;
use model::sample::Sample;
use model::sensor_fault::{Channel, SensorFaultRun, SensorFaultSchedule};

use super::{draw_fault, score, FaultRunOutcome, Misreading, RunKind, SensorFaultsArgs, ONSET_S, RUN_KINDS};

/// The run kinds a recording carries: every kind but the leak (a recorded run
/// cannot be given one).
const RECORDED_KINDS: [RunKind; 6] = [
    RunKind::Healthy,
    RunKind::PressureDrift,
    RunKind::Span,
    RunKind::Stuck,
    RunKind::Spikes,
    RunKind::PositionDrift,
];

/// A folder's commissioned chain and its healthy recordings.
pub(super) struct RecordedRig {
    /// The commissioned config.
    rig: Config,
    /// What commissioning said it names on each transducer (None: the config
    /// came commissioned, and did not say).
    reach: Option<pipeline::commission::SensorReach>,
    /// The healthy recordings: run folder name, duty cycle and samples.
    recordings: Vec<(String, String, Vec<Sample>)>,
}

impl RecordedRig {
    /// Commissions the chain of folder `dir` (config `config`, else the
    /// folder's `datasheet.toml`) and reads its healthy recordings.
    pub(super) fn load(dir: &Path, config: Option<&Path>) -> Result<RecordedRig, String> {
        let (sheet, recording) = crate::commands::rig_files(dir);
        let config_path = config.map(Path::to_path_buf).or(sheet);
        let cfg = Config::load_or_default(config_path.as_deref())?;
        match &config_path {
            Some(p) => eprintln!("config: {}", p.display()),
            None => Config::note_builtin_rig(&format!("datasheet.toml in {}", dir.display())),
        }
        let (rig, reach) = match (&recording, cfg.classifier.commissioning.is_some()) {
            (_, true) => (cfg, None),
            (Some(rec), false) => {
                eprintln!("commissioning on {}", rec.display());
                let (rig, record) = pipeline::commission::commission_recorded(rec, &cfg)?;
                (rig, Some(record.learned.sensor_reach))
            }
            (None, false) => {
                eprintln!(
                    "{}: no commissioning recording (commission_cold.csv[.gz]): each run's healthy state is learned \
                     in its first seconds, as `bench detection --data` does",
                    dir.display()
                );
                (cfg, None)
            }
        };
        let recordings = healthy_runs(dir)?
            .into_iter()
            .map(|run| read_recording(&run, &rig).map(|(scenario, s)| (folder_name(&run), scenario, s)))
            .collect::<Result<Vec<_>, String>>()?;
        if recordings.is_empty() {
            return Err(format!(
                "{}: no healthy run (run_*/ whose truth.json has no fault)",
                dir.display()
            ));
        }
        Ok(RecordedRig {
            rig,
            reach,
            recordings,
        })
    }

    /// The jobs: (instance, kind) for every instance and recorded kind, the
    /// healthy run once per recording.
    pub(super) fn jobs(&self, instances: usize) -> Vec<(usize, RunKind)> {
        let n = self.recordings.len();
        (0..instances)
            .flat_map(|i| RECORDED_KINDS.iter().map(move |&k| (i, k)))
            .filter(|&(i, k)| k != RunKind::Healthy || i < n)
            .collect()
    }

    /// Lays a drawn fault of `kind` onto instance `index`'s recording and watches it.
    pub(super) fn watch(
        &self,
        args: &SensorFaultsArgs,
        index: usize,
        kind: RunKind,
    ) -> Result<FaultRunOutcome, String> {
        let (run, scenario, healthy) = &self.recordings[index % self.recordings.len()];
        let k = RUN_KINDS.iter().position(|&r| r == kind).unwrap_or(0);
        let mut rng = Rng::new(args.seed ^ 0x5E_45_0F_A1 ^ ((index as u64) << 20) ^ ((k as u64 + 1) << 40));
        let onset_s = crate::commands::instances::on_grid(rng.uniform_in(ONSET_S.0, ONSET_S.1));
        let (sensor, _) = draw_fault(kind, onset_s, &mut rng);
        let schedule = SensorFaultSchedule {
            faults: sensor.iter().copied().collect(),
        };
        let samples = with_faults(healthy, schedule, rng.next_u64());
        if args.keep {
            super::keep_recording(args, index, kind, &samples)?;
        }
        let misreading = sensor.map_or(Misreading::NONE, |f| {
            let m = Misreading::of(
                &f,
                &samples,
                self.rig.classifier.pressure_full_scale_pa,
                [
                    self.rig.classifier.pressure_zero_offset_max_pa,
                    self.rig.classifier.pressure_span_error_max,
                ],
            );
            match &self.reach {
                Some(reach) => m.stated_by(f.channel, reach),
                None => m,
            }
        });
        let mut chain = pipeline::Chain::new(&pipeline::ChainSettings::from(&self.rig))?;
        let mut events = Vec::new();
        for s in &samples {
            chain.step(s, |e| events.push(e));
        }
        chain.finish(samples.last().map_or(0.0, |s| s.t_s), |e| events.push(e));
        let onset = if kind == RunKind::Healthy {
            f64::NAN
        } else {
            onset_s
        };
        let channel = sensor.map(|f| f.channel.name().to_string()).unwrap_or_default();
        let spec = sensor.map(|f| f.to_string()).unwrap_or_default();
        let mut outcome = score(
            index,
            kind,
            spec,
            channel,
            onset,
            &format!("{run} {scenario}"),
            &events,
        );
        outcome.misreading = misreading;
        Ok(outcome)
    }
}

/// `bench sensor-faults --data DIR`: commissions the folder's chain, lays
/// the drawn faults onto its healthy recordings, prints the table and writes
/// sensor_faults.md and .json into `args.out`.
pub(super) fn command(args: &SensorFaultsArgs, dir: &Path, force: bool) -> Result<(), String> {
    if args.instances == 0 {
        return Err("--instances 0: nothing to run".into());
    }
    super::prepare_out(args, force)?;
    let threads = args.threads.unwrap_or_else(pipeline::batch::cores).max(1);
    let t0 = std::time::Instant::now();
    let rig = RecordedRig::load(dir, args.config.as_deref())?;
    let jobs = rig.jobs(args.instances);
    if args.keep {
        let text = toml::to_string(&rig.rig).map_err(|e| format!("the commissioned config: {e}"))?;
        pipeline::out::write(&args.out.join("rig.toml"), text.as_bytes(), force, &[])?;
    }
    eprintln!(
        "watching {} runs on {} healthy recordings of {} on {threads} threads",
        jobs.len(),
        rig.recordings.len(),
        dir.display()
    );
    let runs = super::parallel(jobs.len(), threads, |j| rig.watch(args, jobs[j].0, jobs[j].1))?;
    let set = serde_json::json!({
        "data": dir.display().to_string(),
        "recordings": rig.recordings.iter().map(|(run, scenario, _)| format!("{run} {scenario}")).collect::<Vec<_>>(),
        "instances": args.instances,
        "seed": args.seed,
    });
    super::report(args, force, set, &runs, t0)
}

/// The run folders of `dir` (`run_*`, sorted) whose truth has no fault.
fn healthy_runs(dir: &Path) -> Result<Vec<PathBuf>, String> {
    let entries = std::fs::read_dir(dir).map_err(|e| format!("cannot read {}: {e}", dir.display()))?;
    let mut runs: Vec<PathBuf> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_dir() && folder_name(p).starts_with("run_"))
        .collect();
    runs.sort();
    let mut healthy = Vec::new();
    for run in runs {
        if crate::detection_data::read_truth(&run)?.kind == "none" {
            healthy.push(run);
        }
    }
    Ok(healthy)
}

/// The last component of `p`.
fn folder_name(p: &Path) -> String {
    p.file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default()
}

/// The duty cycle and the samples of run folder `run` (`measured.csv[.gz]`),
/// read with the limits of `rig`'s model; skipped rows are left out, gaps kept.
fn read_recording(run: &Path, rig: &Config) -> Result<(String, Vec<Sample>), String> {
    let scenario = crate::detection_data::read_truth(run)?.scenario;
    let path = ["measured.csv.gz", "measured.csv"]
        .iter()
        .map(|n| run.join(n))
        .find(|p| p.is_file())
        .ok_or_else(|| format!("{}: no measured.csv or measured.csv.gz", run.display()))?;
    let limits = dataset::Limits::for_model(&rig.model, rig.leak_filter.sample_period_s);
    let mut reader = dataset::CsvReader::open(&path, limits).map_err(|e| e.to_string())?;
    let mut samples = Vec::new();
    while let Some(row) = reader.next_row() {
        match row {
            dataset::Row::Sample(s) | dataset::Row::AfterGap(s, _) => samples.push(s),
            dataset::Row::Skipped(_) => {}
        }
    }
    dataset::check_bad_fraction(reader.rows, reader.skipped, dataset::DEFAULT_MAX_BAD_FRACTION)
        .map_err(|e| format!("{}: {e}", path.display()))?;
    Ok((scenario, samples))
}

/// `healthy` with the faults of `schedule` laid onto its readings (outliers
/// drawn from `seed`).
fn with_faults(healthy: &[Sample], schedule: SensorFaultSchedule, seed: u64) -> Vec<Sample> {
    let mut run = SensorFaultRun::new(schedule, seed);
    let mut last_t_s = f64::NAN;
    healthy
        .iter()
        .map(|s| {
            let dt_s = if last_t_s.is_finite() {
                s.t_s - last_t_s
            } else {
                0.0
            };
            last_t_s = s.t_s;
            let mut read =
                |ch: Channel, v: f64| run.read(ch, s.t_s, dt_s, |d| d.before_noise(v) + d.spike_si);
            Sample {
                x_m: read(Channel::X, s.x_m),
                p1_pa: read(Channel::P1, s.p1_pa),
                p2_pa: read(Channel::P2, s.p2_pa),
                ..*s
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use model::sensor_fault::{SensorFault, SensorFaultKind};

    fn recording() -> Vec<Sample> {
        (0..3000)
            .map(|i| Sample::new(i as f64 * 1e-3, 0.0, 0.1, 1.0e7, 5.0e6))
            .collect()
    }

    #[test]
    fn a_fault_is_laid_onto_the_recorded_readings_from_its_onset() {
        let healthy = recording();
        let drift = SensorFault {
            channel: Channel::P2,
            kind: SensorFaultKind::Drift {
                rate_si_per_s: -2e5,
                max_abs_si: 3e5,
            },
            onset_s: 1.0,
        };
        let out = with_faults(&healthy, SensorFaultSchedule { faults: vec![drift] }, 1);
        // before the onset the readings are the recording's, bit for bit
        let channels = |s: &Sample| [s.t_s, s.x_m, s.p1_pa, s.p2_pa];
        assert!(out[..1000]
            .iter()
            .zip(&healthy)
            .all(|(a, b)| channels(a) == channels(b)));
        // 1.5 s after it: -300 kPa on p2 (-200 kPa/s held at 300 kPa), p1 and x as recorded
        let s = &out[2500];
        assert!((s.p2_pa - (5.0e6 - 3.0e5)).abs() < 1e-6, "{}", s.p2_pa);
        assert_eq!((s.p1_pa, s.x_m), (1.0e7, 0.1));
        // a span error of +2 % grown over 1 s: half of it at 0.5 s after the onset
        let span = SensorFault {
            channel: Channel::P1,
            kind: SensorFaultKind::Span {
                gain_error: 0.02,
                ramp_s: 1.0,
            },
            onset_s: 1.0,
        };
        let out = with_faults(&healthy, SensorFaultSchedule { faults: vec![span] }, 1);
        assert!(
            (out[1500].p1_pa - 1.0e7 * 1.01).abs() < 1e-6,
            "{}",
            out[1500].p1_pa
        );
        assert!((out[2999].p1_pa - 1.0e7 * 1.02).abs() < 1e-6);
    }

    #[test]
    fn each_instance_watches_every_fault_and_each_recording_its_healthy_run_once() {
        let rig = RecordedRig {
            rig: Config::default(),
            reach: None,
            recordings: vec![
                ("run_000".into(), "lift".into(), recording()),
                ("run_001".into(), "lift".into(), recording()),
            ],
        };
        let jobs = rig.jobs(5);
        assert_eq!(jobs.iter().filter(|j| j.1 == RunKind::Healthy).count(), 2);
        assert_eq!(jobs.iter().filter(|j| j.1 == RunKind::Span).count(), 5);
        assert!(!jobs.iter().any(|j| j.1 == RunKind::Leak));
        assert_eq!(jobs.len(), 2 + 5 * 5);
    }
}
