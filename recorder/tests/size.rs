//! The log's size per hour for a simulated rig stream (1 kHz frames, estimates
//! at 10 Hz, health at 10 Hz, four stages' stats at 1 Hz), written by the
//! writer the recorder uses, and read back bit for bit.

use frames::{EstimateFrame, HealthFrame, SensorFrame, StatsFrame};
use model::{ActuatorParams, FaultSchedule, Scenario, Simulator};
use recorder::{Entry, LogReader, LogWriter, WriterOptions};

/// Simulated seconds written; the size per hour is scaled from them.
const SECONDS: f64 = 60.0;

/// A deterministic pseudo-random number in [0, 1) from `i` (splitmix64).
fn noise(i: u64) -> f64 {
    let mut z = i.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    (z ^ (z >> 31)) as f64 / 2f64.powi(64)
}

/// The stream of `seconds` of `leakwatch run`'s default rig (`loaded-sine`,
/// seed 1) as the recorder receives it: frames published every 1 ms with
/// 0-50 µs of jitter, an estimate every 100th frame (the rest left out by
/// `--estimates-every 100`) holding incompressible numbers, health at 10 Hz,
/// four stats frames a second. `rig_like`: a real rig's UDP stream instead:
/// the command quantised to 16 bits over ±10 V, and no spool, load,
/// reference or leak-truth channel.
fn rig_stream(seconds: f64, rig_like: bool) -> Vec<Entry> {
    let scenario = Scenario::by_name("loaded-sine", 1, seconds).unwrap();
    let mut sim =
        Simulator::with_default_sensors(ActuatorParams::default(), scenario, FaultSchedule::default(), 1)
            .unwrap();
    let n = (seconds * 1000.0).round() as u64;
    let start_ns = 5_000_000_000_000u64;
    let mut out = Vec::with_capacity(n as usize * 11 / 10);
    for i in 0..n {
        let mut f = SensorFrame::from(&sim.step());
        f.seq = i;
        f.acq_mono_ns = start_ns + i * 1_000_000 + (noise(i) * 50_000.0) as u64;
        if rig_like {
            let step = 20.0 / 65_535.0;
            f.u_v = (f.u_v.clamp(-10.0, 10.0) / step).round() * step;
            f.x_sp_m = f64::NAN;
            f.f_load_n = f64::NAN;
            f.ref_m = f64::NAN;
            f.q_leak_lpm = f64::NAN;
        }
        let recv = f.acq_mono_ns + 200_000;
        out.push(Entry::Frame(f, recv));
        if i % 100 == 0 {
            let mut e = EstimateFrame {
                seq: i,
                acq_mono_ns: f.acq_mono_ns,
                est_recv_mono_ns: f.acq_mono_ns + 20_000,
                est_done_mono_ns: f.acq_mono_ns + 60_000,
                t_s: f.t_s,
                n_states: 11,
                ..EstimateFrame::default()
            };
            let mut k = i * 1_000;
            let mut r = || {
                k += 1;
                noise(k)
            };
            e.state.iter_mut().for_each(|x| *x = r());
            e.state_sigma.iter_mut().for_each(|x| *x = r());
            e.residual.iter_mut().for_each(|x| *x = r());
            e.innovation.iter_mut().for_each(|x| *x = r());
            e.innovation_sigma.iter_mut().for_each(|x| *x = r());
            e.measured = [f.x_m, f.p1_pa, f.p2_pa];
            e.u_v = f.u_v;
            e.nis = r();
            e.mae_pa.iter_mut().for_each(|x| *x = r());
            e.th_state.iter_mut().for_each(|x| *x = r());
            e.th_residual.iter_mut().for_each(|x| *x = r());
            e.th_innovation.iter_mut().for_each(|x| *x = r());
            e.th_mae_pa.iter_mut().for_each(|x| *x = r());
            e.th_nis = r();
            out.push(Entry::Estimate(e, recv + 100_000));
            let h = HealthFrame {
                seq: i / 100,
                mono_ns: recv + 150_000,
                t_s: f.t_s,
                status: 1,
                active_events: 0,
                leak_flow_lpm: [r(), r(), r()],
                leak_flow_sigma_lpm: [r(), r(), r()],
                leak_threshold_lpm: [0.05, 0.06, 0.07],
            };
            out.push(Entry::Health(h, recv + 160_000));
        }
        if i % 1000 == 999 {
            for stage in 0..4 {
                let s = StatsFrame {
                    mono_ns: recv + stage,
                    pid: 1000 + stage as u32,
                    stage: stage as u32,
                    frames_in: i,
                    frames_out: i,
                    proc_ns_p50: (r_u(i, stage) * 1e4) as u64,
                    proc_ns_p99: (r_u(i, stage + 10) * 1e5) as u64,
                    proc_ns_max: (r_u(i, stage + 20) * 1e6) as u64,
                    lat_ns_p50: (r_u(i, stage + 30) * 1e4) as u64,
                    lat_ns_p99: (r_u(i, stage + 40) * 1e5) as u64,
                    lat_ns_max: (r_u(i, stage + 50) * 1e6) as u64,
                    cpu_fraction: r_u(i, stage + 60),
                    rss_bytes: 20_000_000 + (r_u(i, stage + 70) * 1e5) as u64,
                    ..StatsFrame::default()
                };
                out.push(Entry::Stats(s, recv + stage));
            }
        }
    }
    out
}

fn r_u(i: u64, salt: u64) -> f64 {
    noise(i.wrapping_mul(131).wrapping_add(salt))
}

/// Writes `entries` into `path` (waiting whenever the writer's queue is full:
/// nothing is dropped); returns the file's size, bytes.
fn write(path: &std::path::Path, entries: &[Entry], options: WriterOptions) -> u64 {
    let mut w = LogWriter::create(path, options).unwrap();
    for e in entries {
        while !w.write(*e).unwrap() {
            std::thread::sleep(std::time::Duration::from_millis(1));
        }
    }
    w.finish().unwrap().bytes
}

/// MB (10⁶ bytes) per hour of `bytes` written for `seconds` of stream.
fn mb_per_hour(bytes: u64, seconds: f64) -> f64 {
    bytes as f64 / seconds * 3600.0 / 1e6
}

/// The reference: a rig's stream (no truth channels) at 1 kHz, with the
/// estimates and health at 10 Hz, in at most 100 MB per hour: 86.5 MB/h when
/// written (± 5 % allowed), 226 MB/h with every frame a message.
#[test]
fn a_rig_stream_takes_at_most_100_mb_an_hour_and_reads_back_bit_for_bit() {
    let dir = scratch::ScratchDir::new("recorder-size");
    let entries = rig_stream(SECONDS, true);
    let path = dir.join("run.mcap");
    let bytes = write(&path, &entries, WriterOptions::default());
    let mbh = mb_per_hour(bytes, SECONDS);
    assert!((82.0..=91.0).contains(&mbh), "{mbh:.1} MB/h");
    let log = LogReader::open(&path).unwrap().read().unwrap();
    let written: Vec<[u64; 13]> = entries
        .iter()
        .filter_map(|e| match e {
            Entry::Frame(f, _) => Some(bits(f)),
            _ => None,
        })
        .collect();
    assert_eq!(written.len(), 60_000);
    assert_eq!(log.frames.iter().map(bits).collect::<Vec<_>>(), written);
    // 10 Hz estimates and health, 25 Hz of frames to plot, 100-frame batches
    // (cut short where a chunk closes, every 2 s: 15 times)
    let messages = |c: &str| log.channels[c].messages;
    assert_eq!(
        (
            messages("frames"),
            messages("frame_batches"),
            messages("estimates"),
            messages("health")
        ),
        (1_500, 615, 600, 600)
    );
}

/// The simulated rig of `leakwatch run` (unquantised command, reference and
/// leak-truth channels, which do not compress) writes more: 137.9 MB/h when
/// written (± 5 %), 269 MB/h with every frame a message.
#[test]
fn the_simulated_rig_takes_about_150_mb_an_hour() {
    let dir = scratch::ScratchDir::new("recorder-size-sim");
    let entries = rig_stream(SECONDS, false);
    let path = dir.join("run.mcap");
    let mbh = mb_per_hour(write(&path, &entries, WriterOptions::default()), SECONDS);
    assert!((131.0..=145.0).contains(&mbh), "{mbh:.1} MB/h");
}

/// Every field of a frame as its bits.
fn bits(f: &SensorFrame) -> [u64; 13] {
    [
        f.seq,
        f.acq_mono_ns,
        f.t_s.to_bits(),
        f.u_v.to_bits(),
        f.x_m.to_bits(),
        f.p1_pa.to_bits(),
        f.p2_pa.to_bits(),
        f.x_sp_m.to_bits(),
        f.f_load_n.to_bits(),
        f.ref_m.to_bits(),
        f.q_leak_lpm.to_bits(),
        u64::from(f.flags),
        f.temp_c.to_bits(),
    ]
}

#[test]
#[ignore = "a measurement: prints the size per hour of each stream and setting"]
fn report_the_size_per_hour() {
    let dir = scratch::ScratchDir::new("recorder-size-report");
    let path = dir.join("run.mcap");
    for rig_like in [false, true] {
        let entries = rig_stream(SECONDS, rig_like);
        eprintln!("{}:", if rig_like { "rig-like" } else { "simulated rig" });
        let k = |o: WriterOptions| {
            let c0 = cpu_s();
            let b = write(&path, &entries, WriterOptions { overwrite: true, ..o });
            (mb_per_hour(b, SECONDS), (cpu_s() - c0) / SECONDS * 100.0)
        };
        let settings = [
            ("every frame a message, 1 s chunks, level 9 (before)", 0, 1, 1, 9),
            ("batches, 50 Hz frames, 1 s chunks, level 9", 100, 20, 1, 9),
            ("batches, 25 Hz frames, 2 s chunks, level 9", 100, 40, 2, 9),
            (
                "batches, 25 Hz frames, 2 s chunks, level 18 (default)",
                100,
                40,
                2,
                18,
            ),
        ];
        for (name, batch, every, age_s, level) in settings {
            let (mbh, cpu) = k(WriterOptions {
                frame_batch_len: batch,
                frames_every: every,
                max_chunk_age_ns: age_s * 1_000_000_000,
                compression_level: level,
                ..WriterOptions::default()
            });
            eprintln!("  {name}: {mbh:.1} MB/h, writing took {cpu:.2} % of a core");
        }
    }
}

/// The CPU time this process has used, s (user + system, from /proc/self/stat).
fn cpu_s() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap();
    let after = &stat[stat.rfind(')').unwrap() + 2..];
    let f: Vec<&str> = after.split_whitespace().collect();
    let ticks: f64 = f[11].parse::<f64>().unwrap() + f[12].parse::<f64>().unwrap();
    ticks / 100.0
}
