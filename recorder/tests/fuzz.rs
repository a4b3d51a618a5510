//! Property-test fuzz harness of the log reader: a small valid log written by
//! [`LogWriter`] (and the seeds in `tests/corpus/`), then damaged (byte flips,
//! insertions, deletions, truncation, record and chunk length fields set to
//! 0, 1, huge or random values), must be read by [`LogReader`], exported as
//! CSV and repaired without a panic or a hang: either it reads, or the error
//! names the file.
//!
//! Case counts are small by default (each test well under 30 s in debug mode);
//! `LEAKWATCH_FUZZ_CASES=20000 cargo test -p recorder --test fuzz` runs longer.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::mpsc;
use std::sync::OnceLock;
use std::time::Duration;

use frames::{HealthFrame, SensorFrame, Topic};
use proptest::prelude::*;
use proptest::test_runner::TestCaseError;
use recorder::{export_csv, repair, Entry, GapRecord, LogReader, LogWriter, WriterOptions};

/// Seed logs kept in the repository: a zstd log and an uncompressed one
/// written by this version's [`LogWriter`] with 2 KiB chunks (CDR messages),
/// and the same two as the version before wrote them (JSON messages).
const CORPUS: [&[u8]; 4] = [
    include_bytes!("corpus/small_zstd.mcap"),
    include_bytes!("corpus/small_plain.mcap"),
    include_bytes!("corpus/json_zstd.mcap"),
    include_bytes!("corpus/json_plain.mcap"),
];

fn cases(default: u32) -> u32 {
    std::env::var("LEAKWATCH_FUZZ_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

fn dir() -> &'static Path {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let d = std::env::temp_dir().join(format!("recorder-fuzz-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    })
}

/// A fresh file name in the test directory.
fn fresh(ext: &str) -> PathBuf {
    static N: AtomicU64 = AtomicU64::new(0);
    dir().join(format!("case{}.{ext}", N.fetch_add(1, Ordering::Relaxed)))
}

/// Writes a small log: `n` sensor frames, a health frame every 10, a gap.
fn write_log(path: &Path, n: u64, compression: Option<mcap::Compression>) {
    let options = WriterOptions {
        chunk_size: 2048,
        compression,
        ..WriterOptions::default()
    };
    let mut w = LogWriter::create(path, options).unwrap();
    for i in 0..n {
        let f = SensorFrame {
            seq: i,
            acq_mono_ns: 1_000_000 * i,
            t_s: i as f64 * 1e-3,
            u_v: 0.5,
            x_m: 0.3,
            p1_pa: 6.9e6,
            p2_pa: 6.8e6,
            x_sp_m: f64::NAN,
            f_load_n: f64::INFINITY,
            ref_m: -0.0,
            q_leak_lpm: 0.25,
            flags: 0,
            _pad: 0,
            temp_c: f64::NAN,
        };
        assert!(w.write(Entry::Frame(f, 10 + i)).unwrap());
        if i % 10 == 0 {
            let h = HealthFrame {
                seq: i / 10,
                mono_ns: i,
                t_s: i as f64 * 1e-3,
                status: 1,
                active_events: 0,
                leak_flow_lpm: [0.1, f64::NAN, -0.2],
                leak_flow_sigma_lpm: [0.01, 0.02, 0.03],
                leak_threshold_lpm: [0.05, 0.06, 0.07],
            };
            assert!(w.write(Entry::Health(h, 11 + i)).unwrap());
        }
    }
    let gap = GapRecord {
        topic: Topic::Frames,
        expected_seq: 3,
        got_seq: 5,
        missing: 2,
        recv_mono_ns: 7,
    };
    assert!(w.write(Entry::Gap(gap)).unwrap());
    w.finish().unwrap();
}

/// The seeds: a fresh log of this build (zstd) and the corpus files.
fn seeds() -> &'static [Vec<u8>] {
    static SEEDS: OnceLock<Vec<Vec<u8>>> = OnceLock::new();
    SEEDS.get_or_init(|| {
        let p = dir().join("seed.mcap");
        write_log(&p, 120, Some(mcap::Compression::Zstd));
        let mut v = vec![std::fs::read(&p).unwrap()];
        v.extend(CORPUS.iter().map(|c| c.to_vec()));
        v
    })
}

/// Byte offsets of the top-level records of an MCAP file.
fn record_offsets(bytes: &[u8]) -> Vec<usize> {
    let mut at = 8;
    let mut out = Vec::new();
    while at + 9 <= bytes.len() {
        out.push(at);
        let len = u64::from_le_bytes(bytes[at + 1..at + 9].try_into().unwrap());
        match usize::try_from(len)
            .ok()
            .and_then(|l| l.checked_add(9))
            .and_then(|l| at.checked_add(l))
        {
            Some(next) if next > at => at = next,
            _ => break,
        }
    }
    out
}

/// Values for length fields: 0, 1, huge, around the true value, random.
fn length_value(original: u64, pick: u8, random: u64) -> u64 {
    match pick % 8 {
        0 => 0,
        1 => 1,
        2 => u64::MAX,
        3 => 1 << 62,
        4 => original.wrapping_add(1),
        5 => original.wrapping_sub(1),
        6 => original.wrapping_mul(2),
        _ => random,
    }
}

/// One damage: (what, where, value pick, random value).
type Damage = (u8, usize, u8, u64);

fn damage(seed: &[u8], damages: &[Damage]) -> Vec<u8> {
    let mut b = seed.to_vec();
    for &(what, at, pick, random) in damages {
        let len = b.len();
        if len == 0 {
            break;
        }
        match what % 7 {
            0 => b[at % len] ^= 1 << (pick % 8),
            1 => b.insert(at % (len + 1), pick),
            2 => {
                b.remove(at % len);
            }
            3 => b.truncate(at % len),
            4 | 5 => {
                // a record's length field, or a field of a chunk header
                // (uncompressed size at +25, compressed size after the compression name)
                let records = record_offsets(&b);
                if records.is_empty() {
                    continue;
                }
                let r = records[at % records.len()];
                let field = if what % 7 == 4 || b[r] != 0x06 {
                    r + 1
                } else if pick & 0x80 == 0 {
                    r + 25
                } else {
                    // start, end, size (8 each), crc (4), compression string (4 + n)
                    let name_at = r + 9 + 28;
                    match b.get(name_at..name_at + 4) {
                        Some(n) => name_at + 4 + u32::from_le_bytes(n.try_into().unwrap()) as usize,
                        None => continue,
                    }
                };
                if let Some(f) = b.get_mut(field..field + 8) {
                    let original = u64::from_le_bytes((&*f).try_into().unwrap());
                    f.copy_from_slice(&length_value(original, pick, random).to_le_bytes());
                }
            }
            _ => {
                // a chunk's CRC set to a random value
                let records = record_offsets(&b);
                let chunks: Vec<usize> = records.into_iter().filter(|&r| b[r] == 0x06).collect();
                if let Some(&c) = chunks.get(at % chunks.len().max(1)) {
                    if let Some(f) = b.get_mut(c + 33..c + 37) {
                        f.copy_from_slice(&(random as u32).to_le_bytes());
                    }
                }
            }
        }
    }
    b
}

/// Runs `f` on its own thread; a panic or a run longer than `limit` fails the case.
fn within<F>(limit: Duration, f: F) -> Result<(), TestCaseError>
where
    F: FnOnce() -> Result<(), String> + Send + 'static,
{
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        let _ = tx.send(f());
    });
    match rx.recv_timeout(limit) {
        Ok(Ok(())) => Ok(()),
        Ok(Err(e)) => Err(TestCaseError::fail(e)),
        Err(mpsc::RecvTimeoutError::Timeout) => {
            Err(TestCaseError::fail(format!("did not finish in {limit:?}")))
        }
        Err(mpsc::RecvTimeoutError::Disconnected) => Err(TestCaseError::fail("panicked")),
    }
}

/// Reads, exports and repairs `bytes`; every error must name the file.
fn check_log(bytes: Vec<u8>) -> Result<(), String> {
    let path = fresh("mcap");
    std::fs::write(&path, &bytes).map_err(|e| e.to_string())?;
    let name = path.file_name().unwrap().to_string_lossy().to_string();
    let names = |e: &dyn std::fmt::Display, file: &str| {
        let msg = e.to_string();
        if msg.contains(file) {
            Ok(())
        } else {
            Err(format!("error without the file {file}: {msg}"))
        }
    };
    let read = LogReader::open(&path).map_err(|e| e.to_string())?.read();
    match &read {
        Ok(log) => {
            let out = fresh("csv");
            if let Err(e) = export_csv(log, &out, false) {
                names(&e, &out.to_string_lossy())?;
            }
            let _ = std::fs::remove_dir_all(&out);
        }
        Err(e) => names(e, &name)?,
    }
    let fixed = fresh("fixed.mcap");
    match repair(&path, &fixed, false) {
        Ok(summary) => {
            // the repaired file is complete and reads: the same messages as the damaged one
            let back = LogReader::open(&fixed)
                .and_then(|r| r.read())
                .map_err(|e| format!("the repaired file does not read: {e}"))?;
            if back.truncated.is_some() || !back.chunks_skipped.is_empty() {
                return Err(format!(
                    "the repaired file is damaged: {:?} {:?}",
                    back.truncated, back.chunks_skipped
                ));
            }
            if let Ok(log) = &read {
                if back.frames.len() != log.frames.len() || back.health.len() != log.health.len() {
                    return Err(format!(
                        "repaired {} frames {} health, read {} frames {} health ({summary:?})",
                        back.frames.len(),
                        back.health.len(),
                        log.frames.len(),
                        log.health.len()
                    ));
                }
            }
        }
        Err(e) => {
            let msg = e.to_string();
            if !msg.contains(&name) && !msg.contains("fixed.mcap") {
                return Err(format!("repair error without the file: {msg}"));
            }
            if fixed.exists() {
                return Err(format!("repair failed ({msg}) but left {}", fixed.display()));
            }
        }
    }
    let _ = std::fs::remove_file(&path);
    let _ = std::fs::remove_file(&fixed);
    Ok(())
}

fn damages() -> impl Strategy<Value = Vec<Damage>> {
    proptest::collection::vec((any::<u8>(), any::<usize>(), any::<u8>(), any::<u64>()), 1..6)
}

const LIMIT: Duration = Duration::from_secs(20);

proptest! {
    #![proptest_config(ProptestConfig { cases: cases(128), ..ProptestConfig::default() })]

    #[test]
    fn damaged_logs_read_or_fail_by_name_never_panic_or_hang(seed in 0..5usize, damages in damages()) {
        let bytes = damage(&seeds()[seed], &damages);
        within(LIMIT, move || check_log(bytes))?;
    }

    #[test]
    fn arbitrary_bytes_after_the_magic_never_panic_or_hang(
        tail in proptest::collection::vec(any::<u8>(), 0..400),
        header in any::<bool>(),
    ) {
        // the magic, maybe the seed's header record, then anything
        let seed = &seeds()[0];
        let keep = if header { record_offsets(seed).get(1).copied().unwrap_or(8) } else { 8 };
        let mut bytes = seed[..keep].to_vec();
        bytes.extend_from_slice(&tail);
        within(LIMIT, move || check_log(bytes))?;
    }
}

#[test]
fn the_corpus_reads_and_the_damage_oracle_rejects_what_it_must() {
    // the seeds are valid logs (a format change must update them): this version's
    // CDR ones and the JSON ones of the version before
    let encodings: Vec<String> = seeds()
        .iter()
        .map(|seed| {
            let p = fresh("mcap");
            std::fs::write(&p, seed).unwrap();
            let log = LogReader::open(&p).unwrap().read().unwrap();
            log.channels["frames"].message_encoding.clone()
        })
        .collect();
    assert_eq!(encodings, ["cdr", "cdr", "cdr", "json", "json"]);
    for (i, seed) in seeds().iter().enumerate() {
        let p = fresh("mcap");
        std::fs::write(&p, seed).unwrap();
        let log = LogReader::open(&p).unwrap().read().unwrap();
        assert_eq!(
            (log.frames.len(), log.health.len(), log.gaps.len()),
            (120, 12, 1),
            "seed {i}"
        );
        assert!(
            log.truncated.is_none() && log.chunks_skipped.is_empty(),
            "seed {i}"
        );
    }
    // a chunk declaring 2^62 bytes: skipped, named, quickly
    let b = damage(&seeds()[0], &[(5, 2, 3, 0)]);
    assert_ne!(b, seeds()[0]);
    check_log(b).unwrap();
    // not MCAP at all: both fail by name, nothing is written
    check_log(b"not a log".to_vec()).unwrap();
}

/// Writes this version's corpus files again (`cargo test -p recorder --test fuzz
/// -- --ignored`); the JSON ones stay as the version before wrote them.
#[test]
#[ignore]
fn write_corpus() {
    let d = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/corpus");
    std::fs::create_dir_all(&d).unwrap();
    for (name, c) in [
        ("small_zstd.mcap", Some(mcap::Compression::Zstd)),
        ("small_plain.mcap", None),
    ] {
        let _ = std::fs::remove_file(d.join(name));
        write_log(&d.join(name), 120, c);
    }
}
