//! `leakwatch bench latency`: the pipeline at 1 kHz over iceoryx2 (event and
//! low-latency modes, real processes; and in event mode with the estimator and
//! the classifier in one process), and the same stages as threads over
//! Unix domain sockets and over crossbeam channels, side by side in one run.

use std::os::unix::net::UnixDatagram;
use std::path::Path;

use pipeline::out::outln;
use std::time::{Duration, Instant};

use hdrhistogram::Histogram;
use model::Sample;
use serde::Serialize;

/// One transport's figures.
#[derive(Debug, Clone, Serialize)]
pub struct Row {
    /// Transport and wait mode.
    pub transport: String,
    /// Acquisition → estimator input, µs: p50, p99, max.
    pub hop_us: [f64; 3],
    /// Acquisition → classifier decision, µs: p50, p99, p99.9, max.
    pub end_to_end_us: [f64; 4],
    /// Frames published and received by the classifier.
    pub frames: [u64; 2],
    /// CPU of the estimator stage, fraction of a core (of the estimator and the
    /// classifier where they share a process).
    pub estimator_cpu: f64,
    /// Lateness of the acquisition's publish instants against its 1 kHz schedule
    /// over the whole run, µs: p50, p99, p99.9, max (NaN for the thread rows).
    pub pacer_whole_run_us: [f64; 4],
}

/// The whole-run schedule lateness (p50, p99, p99.9, max, µs) from an acquisition's
/// closing line `schedule lateness: n=… p50=…µs p99=…µs p99.9=…µs max=…µs`.
pub fn pacer_lateness_us(acquisition_log: &str) -> Option<[f64; 4]> {
    let line = acquisition_log
        .lines()
        .rev()
        .find(|l| l.contains("schedule lateness:"))?;
    let value = |key: &str| -> Option<f64> {
        let rest = line.split(' ').find_map(|w| w.strip_prefix(key))?;
        rest.trim_end_matches("µs").parse().ok()
    };
    Some([value("p50=")?, value("p99=")?, value("p99.9=")?, value("max=")?])
}

fn q(h: &Histogram<u64>, p: f64) -> f64 {
    h.value_at_quantile(p) as f64 / 1e3
}

fn now_ns(t0: Instant) -> u64 {
    t0.elapsed().as_nanos() as u64
}

/// The three stages as threads; `T` moves (acquisition time, sample) between them.
fn threads_run<S: Send + 'static, R: Send + 'static>(
    name: &str,
    samples: Vec<Sample>,
    mut make: impl FnMut() -> (S, R),
    send: fn(&S, u64, &Sample) -> bool,
    recv: fn(&R) -> Option<(u64, Sample)>,
) -> Row {
    let t0 = Instant::now();
    let (s1, r1) = make();
    let (s2, r2) = make();
    let n = samples.len() as u64;
    let acq = std::thread::spawn(move || {
        let period = Duration::from_millis(1);
        let start = Instant::now() + Duration::from_millis(50);
        for (k, s) in samples.iter().enumerate() {
            let due = start + period * k as u32;
            let now = Instant::now();
            if due > now {
                std::thread::sleep(due - now);
            }
            if !send(&s1, now_ns(t0), s) {
                break;
            }
        }
        // end marker
        let mut end = Sample::new(f64::NAN, 0.0, 0.0, 0.0, 0.0);
        end.u_v = f64::NAN;
        send(&s1, 0, &end);
    });
    let est = std::thread::spawn(move || {
        let mut stage = pipeline::ChainSettings::default()
            .leak_stage()
            .expect("default tuning is valid");
        let mut hop = Histogram::<u64>::new_with_bounds(1, 60_000_000_000, 3).expect("histogram bounds");
        let cpu0 = bus::stats::process_cpu_ns();
        let w0 = Instant::now();
        while let Some((stamp, s)) = recv(&r1) {
            if s.t_s.is_nan() {
                send(&s2, 0, &s);
                break;
            }
            let _ = hop.record(now_ns(t0).saturating_sub(stamp).max(1));
            let e = stage.on_sample(&s);
            let mut out = s;
            out.x_sp_m = e.leak.state[0];
            send(&s2, stamp, &out);
        }
        let cpu = (bus::stats::process_cpu_ns() - cpu0) as f64 / w0.elapsed().as_nanos().max(1) as f64;
        (hop, cpu)
    });
    let mut e2e = Histogram::<u64>::new_with_bounds(1, 60_000_000_000, 3).expect("histogram bounds");
    let mut got = 0;
    let mut chain =
        pipeline::Chain::new(&pipeline::ChainSettings::default()).expect("default config is valid");
    while let Some((stamp, s)) = recv(&r2) {
        if s.t_s.is_nan() {
            break;
        }
        // The classifier's own work on an estimate (the estimate is recomputed here
        // only to have one to classify; its cost is not part of the latency below).
        chain.step(&s, |_| {});
        let _ = e2e.record(now_ns(t0).saturating_sub(stamp).max(1));
        got += 1;
    }
    let _ = acq.join();
    let (hop, cpu) = est
        .join()
        .unwrap_or_else(|_| (Histogram::new(3).expect("histogram"), f64::NAN));
    Row {
        transport: name.into(),
        hop_us: [q(&hop, 0.5), q(&hop, 0.99), hop.max() as f64 / 1e3],
        end_to_end_us: [
            q(&e2e, 0.5),
            q(&e2e, 0.99),
            q(&e2e, 0.999),
            e2e.max() as f64 / 1e3,
        ],
        frames: [n, got],
        estimator_cpu: cpu / 2.0, // two threads in the process: report per stage roughly
        pacer_whole_run_us: [f64::NAN; 4],
    }
}

const WIRE: usize = 8 + 5 * 8;

fn encode(stamp: u64, s: &Sample) -> [u8; WIRE] {
    let mut b = [0u8; WIRE];
    b[..8].copy_from_slice(&stamp.to_le_bytes());
    for (i, v) in [s.t_s, s.u_v, s.x_m, s.p1_pa, s.p2_pa].iter().enumerate() {
        b[8 + 8 * i..16 + 8 * i].copy_from_slice(&v.to_le_bytes());
    }
    b
}

fn decode(b: &[u8; WIRE]) -> (u64, Sample) {
    let f = |i: usize| f64::from_le_bytes(b[8 + 8 * i..16 + 8 * i].try_into().unwrap_or([0; 8]));
    let stamp = u64::from_le_bytes(b[..8].try_into().unwrap_or([0; 8]));
    (stamp, Sample::new(f(0), f(1), f(2), f(3), f(4)))
}

/// Runs the benchmark and prints the table; writes DIR/latency.json.
pub fn bench(seconds: f64, out: &Path, force: bool) -> Result<(), String> {
    if !(seconds > 0.0 && seconds.is_finite()) {
        return Err(format!("--seconds {seconds}: must be a positive number"));
    }
    pipeline::out::dir(out)?;
    pipeline::out::check(&out.join("latency.json"), force, &[])?;
    // the machine's floors first, on an otherwise idle machine
    let floors = crate::commands::floors::measure(seconds.min(10.0))?;
    let mut rows = Vec::new();
    for (mode, placement, pinned) in process_runs() {
        rows.push(process_row(seconds, out, force, mode, placement, pinned)?);
    }
    let samples = crate::commands::samples(seconds);
    eprintln!("threads over Unix datagram sockets: {seconds} s ...");
    rows.push(threads_run(
        "threads, Unix datagram sockets",
        samples.clone(),
        || UnixDatagram::pair().expect("socketpair"),
        |s, stamp, x| s.send(&encode(stamp, x)).is_ok(),
        |r| {
            let mut b = [0u8; WIRE];
            match r.recv(&mut b) {
                Ok(WIRE) => Some(decode(&b)),
                _ => None,
            }
        },
    ));
    eprintln!("threads over crossbeam channels: {seconds} s ...");
    rows.push(threads_run(
        "threads, crossbeam channels",
        samples,
        || crossbeam_channel::bounded::<(u64, Sample)>(1024),
        |s, stamp, x| s.send((stamp, *x)).is_ok(),
        |r| r.recv().ok(),
    ));
    print_rows(&rows)?;
    crate::commands::floors::print(&floors)?;
    let p = out.join("latency.json");
    let json = serde_json::json!({ "pipeline": rows, "floors": floors });
    let text = serde_json::to_string_pretty(&json).map_err(|e| e.to_string())? + "\n";
    pipeline::out::write(&p, text.as_bytes(), force, &[])?;
    eprintln!("wrote {}", p.display());
    Ok(())
}

/// The iceoryx2 runs as (wait mode, placement, pinned): the estimator and
/// classifier as two processes, and as one; with two CPUs or more, the
/// low-latency configuration also pinned.
fn process_runs() -> Vec<(&'static str, Option<&'static str>, bool)> {
    // (wait mode, placement, pinned): the estimator and classifier as two processes,
    // and as one; the low-latency configuration pins the acquisition alone to
    // one CPU and the fused estimator+classifier with the recorder to the other ([run] cpus).
    let cpus = pipeline::batch::cores();
    let mut runs = vec![
        ("event", None, false),
        ("low-latency", None, false),
        ("event", Some("estimator+classifier"), false),
        ("low-latency", Some("estimator+classifier"), false),
    ];
    if cpus >= 2 {
        runs.push(("low-latency", Some("estimator+classifier"), true));
    }
    runs
}

/// Runs the pipeline as iceoryx2 processes for `seconds` s in wait `mode`
/// with the stages' `placement` (and `pinned` to CPUs) under `out`; its row.
fn process_row(
    seconds: f64,
    out: &Path,
    force: bool,
    mode: &str,
    placement: Option<&str>,
    pinned: bool,
) -> Result<Row, String> {
    let label = match placement {
        None => mode.to_string(),
        Some(p) => format!("{mode}, {p} in one process"),
    } + if pinned {
        ", pinned (acquisition CPU 0, the fused stage and the recorder CPU 1)"
    } else {
        ""
    };
    let dir = match placement {
        None => format!("run-{mode}"),
        Some(_) => format!("run-{mode}-fused"),
    } + if pinned { "-pinned" } else { "" };
    let config = if pinned {
        pipeline::out::dir(out)?;
        let p = out.join("pinned.toml");
        // (the recorder's bursts beside the spinning pacer cost it 60-140 µs at p99:
        // the pacer gets CPU 0 alone)
        let text = "[run]\ncpus = { acquisition = 0, recorder = 1, \"estimator+classifier\" = 1 }\n";
        pipeline::out::write(&p, text.as_bytes(), true, &[])?;
        Some(p)
    } else {
        None
    };
    let args = runtime::RunArgs {
        seconds: Some(seconds),
        scenario: Some("loaded-sine".into()),
        faults: Vec::new(),
        rig: format!(
            "bench-{}{}{}",
            mode.replace('-', ""),
            if placement.is_some() { "-fused" } else { "" },
            if pinned { "-pin" } else { "" }
        ),
        config,
        mode: mode.into(),
        out: Some(out.join(&dir)),
        thesis_baseline: false,
        force,
        source: None,
        udp_idle_timeout_s: None,
        placement: placement.map(String::from),
        live_view: None,
        zenoh: false,
        zenoh_connect: Vec::new(),
        runs_dir: None,
        keep_days: None,
        keep_gib: None,
        opcua: None,
    };
    eprintln!("iceoryx2, {label}: {seconds} s ...");
    let o = runtime::run_pipeline(&args, true)?;
    let log = std::fs::read_to_string(out.join(&dir).join("acquisition.log")).unwrap_or_default();
    let pacer_whole_run_us = pacer_lateness_us(&log).unwrap_or([f64::NAN; 4]);
    let st = &o.latency.stages;
    let get = |s: &str| st.get(s).cloned().unwrap_or_default();
    let (e, c, a) = (get("estimator"), get("classifier"), get("acquisition"));
    Ok(Row {
        transport: format!("iceoryx2 processes, {label}"),
        hop_us: [e.latency_p50_us, e.latency_worst_1s_p99_us, e.latency_max_us],
        // classifier input latency + its processing: the decision time
        end_to_end_us: [
            c.latency_p50_us + c.proc_p50_us,
            c.latency_worst_1s_p99_us,
            f64::NAN,
            c.latency_max_us,
        ],
        frames: [a.frames_out, c.frames_in],
        // (in one process with the classifier: the CPU of both)
        estimator_cpu: e.cpu_fraction,
        pacer_whole_run_us,
    })
}

/// A table cell of µs or %: one decimal, or a dash when not measured.
fn cell(v: f64) -> String {
    if v.is_finite() {
        format!("{v:.1}")
    } else {
        "–".into()
    }
}

/// Prints the transports' table (latencies µs, CPU %) and the acquisition
/// pacer's lateness (µs) of the process rows.
fn print_rows(rows: &[Row]) -> Result<(), String> {
    outln!("(thread rows: whole-run percentiles; process rows: p50 = median of the 1-s p50s, p99 = the worst 1-s p99, from the stages' stats frames)");
    outln!("| transport | hop p50 µs | hop p99 µs | hop max µs | end-to-end p50 µs | p99 µs | p99.9 µs | max µs | frames sent / classified | estimator CPU % |");
    outln!("|---|---|---|---|---|---|---|---|---|---|");
    for r in rows {
        outln!(
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} / {} | {} |",
            r.transport,
            cell(r.hop_us[0]),
            cell(r.hop_us[1]),
            cell(r.hop_us[2]),
            cell(r.end_to_end_us[0]),
            cell(r.end_to_end_us[1]),
            cell(r.end_to_end_us[2]),
            cell(r.end_to_end_us[3]),
            r.frames[0],
            r.frames[1],
            cell(r.estimator_cpu * 100.0)
        );
    }
    outln!("");
    outln!("Acquisition pacer: lateness of the publish instants against the 1 kHz schedule, whole run");
    outln!("| run | p50 µs | p99 µs | p99.9 µs | max µs |");
    outln!("|---|---|---|---|---|");
    for r in rows.iter().filter(|r| r.pacer_whole_run_us[0].is_finite()) {
        let p = r.pacer_whole_run_us;
        outln!(
            "| {} | {} | {} | {} | {} |",
            r.transport,
            cell(p[0]),
            cell(p[1]),
            cell(p[2]),
            cell(p[3])
        );
    }
    outln!("");
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::pacer_lateness_us;

    #[test]
    fn the_whole_run_pacer_lateness_is_read_from_the_acquisition_log() {
        let log = "acquisition: simulated rig, scenario loaded-sine, 15 s on rig r at 1000 Hz\n\
                   acquisition: 15000 frames, 0 unusable rows skipped, 0 samples missing, 23 deadline misses\n  \
                   schedule lateness: n=15000 p50=0.0µs p99=5.1µs p99.9=1539.1µs max=3641.3µs\n  \
                   sample production: n=15000 p50=5.8µs p99=7.3µs p99.9=19.1µs max=26.6µs\n";
        assert_eq!(pacer_lateness_us(log), Some([0.0, 5.1, 1539.1, 3641.3]));
        assert_eq!(pacer_lateness_us("acquisition: error: no rig\n"), None);
    }
}
