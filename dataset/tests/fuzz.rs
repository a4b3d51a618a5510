//! Property-test fuzz harness of the CSV reader: arbitrary bytes and mutated
//! valid files (seeds in `tests/corpus/`) must never panic or hang, and every
//! row must either give a sample whose values are finite (optional ones may be
//! absent) and within the [`Limits`], or be reported as an issue with a line
//! number.
//!
//! Case counts are small by default (each test well under 30 s in debug mode);
//! `LEAKWATCH_FUZZ_CASES=20000 cargo test -p dataset --test fuzz` runs longer.

use std::io::{Cursor, Write};
use std::path::Path;
use std::sync::mpsc;
use std::time::Duration;

use dataset::{CsvReader, IssueKind, Limits, Row, COLUMNS, REQUIRED};
use proptest::prelude::*;
use proptest::test_runner::TestCaseError;

/// The seed files: small valid (or mostly valid) CSV files.
const SEEDS: [&[u8]; 4] = [
    include_bytes!("corpus/minimal.csv"),
    include_bytes!("corpus/all_columns.csv"),
    include_bytes!("corpus/reordered_crlf.csv"),
    include_bytes!("corpus/bad_rows.csv"),
];

/// Cells swapped in by the mutator: non-finite, huge, tiny, empty, not numbers,
/// separators, a byte-order mark, multi-byte text.
const TOKENS: [&str; 24] = [
    "NaN",
    "nan",
    "inf",
    "-inf",
    "+inf",
    "infinity",
    "1e308",
    "-1e308",
    "1e309",
    "5e-324",
    "",
    " ",
    "-0",
    "0x10",
    "1_000",
    "1e",
    ".",
    "\u{feff}",
    "\r",
    ",",
    "\n",
    "t",
    "é\u{1F4A7}",
    "9999999999999999999999",
];

fn cases(default: u32) -> u32 {
    std::env::var("LEAKWATCH_FUZZ_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
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

/// One mutation: (what, where, byte, token).
type Mutation = (u8, usize, u8, usize);

/// Applies byte flips, insertions, deletions and cell replacements to `seed`.
fn mutate(seed: &[u8], mutations: &[Mutation]) -> Vec<u8> {
    let mut b = seed.to_vec();
    for &(what, at, byte, token) in mutations {
        let len = b.len();
        match what % 5 {
            0 if len > 0 => b[at % len] ^= 1 << (byte % 8),
            1 => b.insert(at % (len + 1), byte),
            2 if len > 0 => {
                b.remove(at % len);
            }
            3 | 4 => {
                // replace the cell around `at` (between separators) by a token
                if len == 0 {
                    b.extend_from_slice(TOKENS[token % TOKENS.len()].as_bytes());
                    continue;
                }
                let at = at % len;
                let sep = |c: &u8| *c == b',' || *c == b'\n';
                let start = b[..at].iter().rposition(sep).map(|i| i + 1).unwrap_or(0);
                let end = b[at..].iter().position(sep).map(|i| at + i).unwrap_or(len);
                b.splice(start..end, TOKENS[token % TOKENS.len()].bytes());
            }
            _ => {}
        }
    }
    b
}

/// Reads every row of `bytes` and checks what came out.
fn check_rows(bytes: &[u8], limits: Limits) -> Result<(), String> {
    let lines = bytes.iter().filter(|&&c| c == b'\n').count() as u64 + 1;
    let mut reader = match CsvReader::new(Cursor::new(bytes), Path::new("fuzz.csv"), limits) {
        Ok(r) => r,
        Err(e) => {
            // a bad header is an error naming the file and line 1
            let msg = e.to_string();
            return if msg.starts_with("fuzz.csv: ") {
                Ok(())
            } else {
                Err(format!("header error without the file: {msg}"))
            };
        }
    };
    check_reader(&mut reader, lines, limits)
}

/// Drains `reader` (which has at most `lines` lines), checking every row.
fn check_reader<R: std::io::BufRead>(
    reader: &mut CsvReader<R>,
    lines: u64,
    limits: Limits,
) -> Result<(), String> {
    let (mut returned, mut skipped) = (0u64, 0u64);
    let mut last_line = 1u64;
    let mut last_t: Option<f64> = None;
    while let Some(row) = reader.next_row() {
        returned += 1;
        if returned > lines {
            return Err(format!(
                "more rows ({returned}) than lines ({lines}): does not terminate"
            ));
        }
        let sample = match &row {
            Row::Sample(s) => Some(s),
            Row::AfterGap(s, issue) => {
                if !matches!(issue.kind, IssueKind::Gap { .. }) || issue.skipped {
                    return Err(format!("a kept row with a non-gap issue: {issue:?}"));
                }
                Some(s)
            }
            Row::Skipped(issue) => {
                skipped += 1;
                if !issue.skipped || issue.message.is_empty() {
                    return Err(format!("skipped row reported as {issue:?}"));
                }
                if let Some(c) = &issue.column {
                    if !COLUMNS.contains(&c.as_str()) {
                        return Err(format!("issue names an unknown column: {issue:?}"));
                    }
                }
                None
            }
        };
        let line = match &row {
            Row::Sample(_) => None,
            Row::AfterGap(_, i) | Row::Skipped(i) => Some(i.line),
        };
        if let Some(line) = line {
            if line <= last_line || line > lines {
                return Err(format!(
                    "issue line {line} (previous {last_line}, file has {lines} lines)"
                ));
            }
            last_line = line;
        }
        if let Some(s) = sample {
            let values = s.columns();
            for (j, v) in values.iter().enumerate() {
                let absent = j >= REQUIRED.len() && v.is_nan();
                if !absent && !v.is_finite() {
                    return Err(format!("sample with {} = {v}: {s:?}", COLUMNS[j]));
                }
            }
            if let Some(problem) = limits.check(s) {
                return Err(format!("sample outside the limits: {problem:?}: {s:?}"));
            }
            if last_t.is_some_and(|t| s.t_s <= t) {
                return Err(format!("time {} s after {last_t:?} s", s.t_s));
            }
            last_t = Some(s.t_s);
        }
    }
    if reader.rows != returned || reader.skipped != skipped {
        return Err(format!(
            "counters rows {} skipped {}, rows returned {returned} skipped {skipped}",
            reader.rows, reader.skipped
        ));
    }
    Ok(())
}

fn limits_strategy() -> impl Strategy<Value = Limits> {
    prop_oneof![
        Just(Limits::default()),
        // the sample period learned from the first two rows
        Just(Limits {
            sample_period_s: None,
            ..Limits::default()
        }),
        Just(Limits::for_supply(21.0e6)),
    ]
}

fn mutations() -> impl Strategy<Value = Vec<Mutation>> {
    proptest::collection::vec((any::<u8>(), any::<usize>(), any::<u8>(), any::<usize>()), 1..12)
}

const LIMIT: Duration = Duration::from_secs(10);

proptest! {
    #![proptest_config(ProptestConfig { cases: cases(256), ..ProptestConfig::default() })]

    #[test]
    fn arbitrary_bytes_never_panic_and_every_row_is_a_valid_sample_or_an_issue(
        bytes in proptest::collection::vec(any::<u8>(), 0..600),
        limits in limits_strategy(),
    ) {
        within(LIMIT, move || check_rows(&bytes, limits))?;
    }

    #[test]
    fn arbitrary_rows_under_a_valid_header_are_valid_samples_or_issues(
        rows in proptest::collection::vec(any::<u8>(), 0..600),
        limits in limits_strategy(),
    ) {
        let mut bytes = b"t,u,x,p1,p2,x_sp,f_load,ref,q_leak\n".to_vec();
        bytes.extend_from_slice(&rows);
        within(LIMIT, move || check_rows(&bytes, limits))?;
    }

    #[test]
    fn mutated_valid_files_never_panic_and_every_row_is_a_valid_sample_or_an_issue(
        seed in 0..SEEDS.len(),
        mutations in mutations(),
        limits in limits_strategy(),
    ) {
        let bytes = mutate(SEEDS[seed], &mutations);
        within(LIMIT, move || check_rows(&bytes, limits))?;
    }

    #[test]
    fn mutated_gzip_files_never_panic_or_hang(
        seed in 0..SEEDS.len(),
        mutations in mutations(),
        corrupt in proptest::collection::vec((any::<usize>(), any::<u8>()), 0..4),
        cut in any::<usize>(),
    ) {
        // a valid gzip of a mutated file, then its compressed bytes damaged and maybe cut short
        let text = mutate(SEEDS[seed], &mutations);
        let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
        gz.write_all(&text).unwrap();
        let mut gz = gz.finish().unwrap();
        for (at, x) in corrupt {
            let n = gz.len();
            gz[at % n] ^= x;
        }
        gz.truncate(gz.len() - cut % (gz.len() / 2 + 1));
        let dir = scratch::ScratchDir::new("fuzz-gz");
        let path = dir.join("case.csv.gz");
        std::fs::write(&path, &gz).unwrap();
        // damaged deflate data decodes to anything: at most 1032 bytes per
        // compressed byte (deflate's largest expansion), so at most that many lines
        let lines = gz.len() as u64 * 1032 + 2;
        within(LIMIT, move || {
            let limits = Limits::default();
            match CsvReader::open(&path, limits) {
                Ok(mut r) => check_reader(&mut r, lines, limits),
                Err(e) => {
                    let msg = e.to_string();
                    if msg.contains(".csv.gz") { Ok(()) } else { Err(format!("error without the file: {msg}")) }
                }
            }
        })?;
    }
}

#[test]
fn the_seed_files_read_as_expected() {
    // the corpus is what the mutator starts from: it must itself be mostly valid
    let expect = [(4, 0), (4, 0), (3, 0), (3, 5)];
    for (seed, (samples, skipped)) in SEEDS.iter().zip(expect) {
        let mut r = CsvReader::new(Cursor::new(*seed), Path::new("seed.csv"), Limits::default()).unwrap();
        let (mut n, mut s) = (0, 0);
        while let Some(row) = r.next_row() {
            match row {
                Row::Skipped(_) => s += 1,
                _ => n += 1,
            }
        }
        assert_eq!((n, s), (samples, skipped), "{}", String::from_utf8_lossy(seed));
    }
    // and the oracle rejects what it must: a line count too small is "does not terminate"
    let mut r = CsvReader::new(Cursor::new(SEEDS[0]), Path::new("seed.csv"), Limits::default()).unwrap();
    let e = check_reader(&mut r, 2, Limits::default()).unwrap_err();
    assert!(e.contains("does not terminate"), "{e}");
}
