//! Writes the samples of a dataset CSV as the sensor frames of a log, as the
//! recorder of a run would (CDR, frames in batches of 100, a health frame at
//! 10 Hz; sequence numbers from 0, receive times 1 ms apart): the input of the
//! log-replay benchmark (docs/performance.md).
//!
//! ```sh
//! cargo run --release -p recorder --example log_of_csv -- run.csv run.mcap
//! ```

use std::path::PathBuf;

fn main() {
    if let Err(e) = run() {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
}

fn run() -> Result<(), String> {
    let args: Vec<PathBuf> = std::env::args_os().skip(1).map(PathBuf::from).collect();
    let [csv, log] = args.as_slice() else {
        return Err("usage: log_of_csv INPUT.csv OUTPUT.mcap".into());
    };
    if log.exists() {
        return Err(format!("{}: exists: not overwritten", log.display()));
    }
    let ds = dataset::read_csv(csv, dataset::Limits::default()).map_err(|e| e.to_string())?;
    let options = recorder::WriterOptions {
        queue_len: 1 << 16,
        ..recorder::WriterOptions::default()
    };
    let io = |e: recorder::RecorderError| format!("{}: {e}", log.display());
    let mut w = recorder::LogWriter::create(log, options).map_err(io)?;
    for (i, s) in ds.samples.iter().enumerate() {
        // receive times 1 ms apart from 1 s on, nanoseconds
        let t_ns = 1_000_000_000 + i as u64 * 1_000_000;
        let frame = frames::SensorFrame {
            seq: i as u64,
            acq_mono_ns: t_ns,
            ..frames::SensorFrame::from(s)
        };
        put(&mut w, recorder::Entry::Frame(frame, t_ns)).map_err(io)?;
        if i % 100 == 0 {
            let h = frames::HealthFrame {
                seq: i as u64 / 100,
                mono_ns: t_ns,
                t_s: s.t_s,
                ..frames::HealthFrame::default()
            };
            put(&mut w, recorder::Entry::Health(h, t_ns)).map_err(io)?;
        }
    }
    w.finish().map_err(io)?;
    eprintln!("wrote {} ({} frames)", log.display(), ds.samples.len());
    Ok(())
}

/// Queues `entry`, waiting while the writer's queue is full (none is dropped).
fn put(w: &mut recorder::LogWriter, entry: recorder::Entry) -> Result<(), recorder::RecorderError> {
    while !w.write(entry)? {
        std::thread::sleep(std::time::Duration::from_millis(1));
    }
    Ok(())
}
