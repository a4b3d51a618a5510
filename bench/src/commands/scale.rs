//! `leakwatch bench scale`: N rigs side by side on this host, each a whole
//! `leakwatch run` (four stage processes and a supervisor, its own rig id and
//! iceoryx2 prefix), for N in a list; per N: CPU per rig, latency medians and
//! tails across the rigs, frames lost, and the capacity that implies.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Instant;

use serde::Serialize;
use serde_json::Value;

use pipeline::out::outln;

/// The figures of one N.
#[derive(Debug, Clone, Serialize)]
pub struct ScaleRow {
    /// Rigs run side by side.
    pub rigs: usize,
    /// CPU of one rig's four stages, % of a core (mean over the rigs, from the stages' stats).
    pub stage_cpu_per_rig_pct: f64,
    /// The whole host's busy CPU during the runs, % of one core (all cores: up to
    /// 100 × cores; includes anything else running on the host).
    pub host_cpu_pct: f64,
    /// CPU of one rig's whole process tree (supervisor and four stages), % of a
    /// core: the runs' children CPU time (getrusage) over the wall time, per rig.
    pub tree_cpu_per_rig_pct: f64,
    /// Acquisition → estimator hop, median over rigs of each rig's p50, µs.
    pub hop_p50_us: f64,
    /// Acquisition → estimator hop, worst one-second p99 over all rigs, µs.
    pub hop_worst_p99_us: f64,
    /// Acquisition → classifier decision, median over rigs, µs.
    pub end_to_end_p50_us: f64,
    /// Frames published by the acquisitions and not classified, all rigs.
    pub frames_lost: u64,
    /// Frames published, all rigs.
    pub frames_sent: u64,
    /// Acquisition deadlines missed (ticks over a period late), all rigs.
    pub deadline_misses: u64,
}

/// Busy and total jiffies of all CPUs (/proc/stat's first line).
fn cpu_jiffies() -> Option<(u64, u64)> {
    let text = std::fs::read_to_string("/proc/stat").ok()?;
    let line = text.lines().next()?;
    let v: Vec<u64> = line
        .split_whitespace()
        .skip(1)
        .filter_map(|s| s.parse().ok())
        .collect();
    if v.len() < 5 {
        return None;
    }
    let total: u64 = v.iter().sum();
    let idle = v[3] + v[4]; // idle + iowait
    Some((total - idle, total))
}

fn stage<'a>(lat: &'a Value, name: &str) -> &'a Value {
    &lat["stages"][name]
}

fn f(v: &Value) -> f64 {
    v.as_f64().unwrap_or(f64::NAN)
}

fn median(mut v: Vec<f64>) -> f64 {
    v.retain(|x| x.is_finite());
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Runs `rigs` pipelines at once for `seconds` and gathers their latency.json.
fn run_rigs(exe: &Path, rigs: usize, seconds: f64, out: &Path, force: bool) -> Result<ScaleRow, String> {
    let cores = pipeline::batch::cores() as f64;
    let before = cpu_jiffies();
    let tree_before = bus::stats::children_cpu_s();
    let started = Instant::now();
    let mut children = Vec::new();
    let mut dirs: Vec<PathBuf> = Vec::new();
    for i in 0..rigs {
        let dir = out.join(format!("rigs-{rigs}")).join(format!("rig{i}"));
        let mut cmd = Command::new(exe);
        cmd.args(["run", "--seconds", &seconds.to_string(), "--fault", "none"])
            .args(["--rig", &format!("scale{rigs}r{i}")])
            .arg("--out")
            .arg(&dir)
            .env(bus::PREFIX_ENV, format!("lws{}n{rigs}r{i}_", std::process::id()))
            .stdout(Stdio::null())
            .stderr(Stdio::piped());
        if force {
            cmd.arg("--force");
        }
        children.push(
            cmd.spawn()
                .map_err(|e| format!("cannot start {}: {e}", exe.display()))?,
        );
        dirs.push(dir);
    }
    let mut failures = Vec::new();
    for (i, c) in children.into_iter().enumerate() {
        let o = c.wait_with_output().map_err(|e| format!("rig {i}: {e}"))?;
        // 3: the run worked, but its detector never armed (a short run): not a failure here
        let code = o.status.code();
        if code != Some(0) && code != Some(i32::from(pipeline::status::NOT_WATCHED)) {
            let err = String::from_utf8_lossy(&o.stderr);
            failures.push(format!("rig {i}: {}", err.lines().last().unwrap_or("failed")));
        }
    }
    let wall = started.elapsed().as_secs_f64();
    if !failures.is_empty() {
        return Err(format!("{rigs} rigs: {}", failures.join("; ")));
    }
    let host_cpu_pct = match (before, cpu_jiffies()) {
        (Some((b0, t0)), Some((b1, t1))) if t1 > t0 => (b1 - b0) as f64 / (t1 - t0) as f64 * cores * 100.0,
        _ => f64::NAN,
    };
    let tree_cpu_per_rig_pct = (bus::stats::children_cpu_s() - tree_before) / wall / rigs as f64 * 100.0;
    let mut cpu = Vec::new();
    let (mut hop50, mut e2e50) = (Vec::new(), Vec::new());
    let mut hop99: f64 = 0.0;
    let (mut sent, mut lost, mut misses) = (0u64, 0u64, 0u64);
    for dir in &dirs {
        let p = dir.join("latency.json");
        let text = std::fs::read_to_string(&p).map_err(|e| format!("{}: {e}", p.display()))?;
        let lat: Value = serde_json::from_str(&text).map_err(|e| format!("{}: {e}", p.display()))?;
        let rig_cpu: f64 = ["acquisition", "estimator", "classifier", "recorder"]
            .iter()
            .map(|s| f(&stage(&lat, s)["cpu_fraction"]))
            .filter(|v| v.is_finite())
            .sum();
        cpu.push(rig_cpu * 100.0);
        let (e, c, a) = (
            stage(&lat, "estimator"),
            stage(&lat, "classifier"),
            stage(&lat, "acquisition"),
        );
        hop50.push(f(&e["latency_p50_us"]));
        hop99 = hop99.max(f(&e["latency_worst_1s_p99_us"]));
        e2e50.push(f(&c["latency_p50_us"]) + f(&c["proc_p50_us"]));
        let out_frames = a["frames_out"].as_u64().unwrap_or(0);
        let classified = c["frames_in"].as_u64().unwrap_or(0);
        sent += out_frames;
        lost += out_frames.saturating_sub(classified);
        misses += a["deadline_misses"].as_u64().unwrap_or(0);
    }
    Ok(ScaleRow {
        rigs,
        stage_cpu_per_rig_pct: cpu.iter().sum::<f64>() / cpu.len().max(1) as f64,
        host_cpu_pct,
        tree_cpu_per_rig_pct,
        hop_p50_us: median(hop50),
        hop_worst_p99_us: hop99,
        end_to_end_p50_us: median(e2e50),
        frames_lost: lost,
        frames_sent: sent,
        deadline_misses: misses,
    })
}

/// Rigs a host of `cores` cores carries at `per_rig_pct` % of a core each,
/// keeping 30 % of the host free.
fn capacity(cores: f64, per_rig_pct: f64) -> f64 {
    if per_rig_pct > 0.0 {
        (0.7 * cores * 100.0 / per_rig_pct).floor()
    } else {
        f64::NAN
    }
}

/// Runs the scale benchmark and prints its table; writes DIR/scale.json.
pub fn bench(rigs: &[usize], seconds: f64, out: &Path, force: bool) -> Result<(), String> {
    if !(seconds >= 5.0 && seconds.is_finite()) {
        return Err(format!("--seconds {seconds}: must be at least 5 s"));
    }
    if rigs.is_empty() || rigs.iter().any(|&n| n == 0 || n > 64) {
        return Err(format!("--rigs {rigs:?}: each from 1 to 64"));
    }
    pipeline::out::dir(out)?;
    pipeline::out::check(&out.join("scale.json"), force, &[])?;
    let exe = std::env::current_exe().map_err(|e| format!("cannot find the leakwatch binary: {e}"))?;
    let mut rows = Vec::new();
    for &n in rigs {
        eprintln!("{n} rig(s) side by side, {seconds} s ...");
        rows.push(run_rigs(&exe, n, seconds, out, force)?);
    }
    let cores = pipeline::batch::cores() as f64;
    outln!("| rigs | stage CPU per rig % | host CPU % (all cores) | process-tree CPU per rig % | hop p50 µs | hop worst 1-s p99 µs | end-to-end p50 µs | frames lost / sent | deadline misses |");
    outln!("|---|---|---|---|---|---|---|---|---|");
    for r in &rows {
        outln!(
            "| {} | {:.1} | {:.1} | {:.1} | {:.1} | {:.1} | {:.1} | {} / {} | {} |",
            r.rigs,
            r.stage_cpu_per_rig_pct,
            r.host_cpu_pct,
            r.tree_cpu_per_rig_pct,
            r.hop_p50_us,
            r.hop_worst_p99_us,
            r.end_to_end_p50_us,
            r.frames_lost,
            r.frames_sent,
            r.deadline_misses
        );
    }
    // capacity from the largest N that lost nothing: its process-tree CPU per rig
    let basis = rows
        .iter()
        .filter(|r| r.frames_lost == 0 && r.tree_cpu_per_rig_pct.is_finite())
        .max_by_key(|r| r.rigs);
    let (here, pc16) = match basis {
        Some(r) => (
            capacity(cores, r.tree_cpu_per_rig_pct),
            capacity(16.0, r.tree_cpu_per_rig_pct),
        ),
        None => (f64::NAN, f64::NAN),
    };
    outln!(
        "capacity at {:.1} % of a core per rig, keeping 30 % of the host free: {here} rigs on this {cores}-core host; {pc16} on a 16-core rig PC (an estimate: same per-rig CPU, no contention counted)",
        basis.map(|r| r.tree_cpu_per_rig_pct).unwrap_or(f64::NAN)
    );
    let json = serde_json::json!({
        "seconds": seconds,
        "cores": cores,
        "rows": rows,
        "capacity_this_host": here,
        "capacity_16_cores_estimate": pc16,
    });
    let p = out.join("scale.json");
    let text = serde_json::to_string_pretty(&json).map_err(|e| e.to_string())? + "\n";
    pipeline::out::write(&p, text.as_bytes(), force, &[])?;
    eprintln!("wrote {}", p.display());
    Ok(())
}
