//! Property-test fuzz harness of the configuration loader: arbitrary text and
//! mutated valid configurations (seeds in `tests/corpus/*.toml`) through
//! [`Config::parse`] must never panic: either a configuration that passes its
//! own validation again, or an error message.
//!
//! Case counts are small by default; `LEAKWATCH_FUZZ_CASES=20000 cargo test -p
//! config fuzz` runs longer.

use proptest::prelude::*;

use crate::Config;

/// The seed files: valid configurations.
const SEEDS: [&str; 3] = [
    include_str!("../tests/corpus/default.toml"),
    include_str!("../tests/corpus/partial.toml"),
    include_str!("../tests/corpus/inline.toml"),
];

/// Values and fragments swapped in by the mutator.
const TOKENS: [&str; 30] = [
    "nan",
    "-nan",
    "inf",
    "-inf",
    "1e308",
    "-1e308",
    "1e-320",
    "-0.0",
    "0",
    "-1",
    "9223372036854775807",
    "-9223372036854775808",
    "18446744073709551616",
    "0x7fff_ffff",
    "0b1",
    "1_000",
    "\"13.8 MPa\"",
    "'x'",
    "[]",
    "[1, 2]",
    "{}",
    "{ a = 1 }",
    "true",
    "1979-05-27T07:32:00Z",
    "\"\"\"",
    "[model]",
    "[[model.leaks]]",
    "é\u{1F4A7}",
    "\n",
    "=",
];

fn cases(default: u32) -> u32 {
    std::env::var("LEAKWATCH_FUZZ_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

/// One mutation: (what, where, byte, token).
type Mutation = (u8, usize, u8, usize);

/// Byte flips, insertions, deletions, a value replaced by a token, a line
/// duplicated or removed; the result is read as (lossy) UTF-8 like a file.
fn mutate(seed: &str, mutations: &[Mutation]) -> String {
    let mut b = seed.as_bytes().to_vec();
    for &(what, at, byte, token) in mutations {
        let len = b.len();
        let tok = TOKENS[token % TOKENS.len()].as_bytes();
        match what % 6 {
            0 if len > 0 => b[at % len] ^= 1 << (byte % 8),
            1 => b.insert(at % (len + 1), byte),
            2 if len > 0 => {
                b.remove(at % len);
            }
            3 | 4 if len > 0 => {
                // the value after the `=` of the line around `at`
                let (start, end) = line_around(&b, at % len);
                match b[start..end].iter().position(|&c| c == b'=') {
                    Some(eq) => {
                        b.splice(start + eq + 1..end, tok.iter().copied());
                    }
                    None => {
                        b.splice(start..end, tok.iter().copied());
                    }
                }
            }
            5 if len > 0 => {
                // a line duplicated (a key or a section given twice) or removed
                let (start, end) = line_around(&b, at % len);
                // with its newline
                let end = (end + 1).min(len);
                if byte & 1 == 0 {
                    let line = b[start..end].to_vec();
                    b.splice(end..end, line);
                } else {
                    b.drain(start..end);
                }
            }
            _ => b.extend_from_slice(tok),
        }
    }
    String::from_utf8_lossy(&b).into_owned()
}

/// Parses `text`: no panic, and an accepted configuration is valid when written and read again.
fn check(text: &str) -> Result<(), TestCaseError> {
    match std::panic::catch_unwind(|| Config::parse(text)) {
        Err(_) => Err(TestCaseError::fail("Config::parse panicked")),
        Ok(Err(e)) => {
            prop_assert!(!e.trim().is_empty(), "an empty error");
            Ok(())
        }
        Ok(Ok(cfg)) => {
            // what was accepted writes back as a configuration that is accepted again
            let again = toml::to_string(&cfg).map_err(|e| TestCaseError::fail(e.to_string()))?;
            match Config::parse(&again) {
                Ok(back) => {
                    prop_assert_eq!(toml::to_string(&back).ok(), Some(again));
                    Ok(())
                }
                Err(e) => Err(TestCaseError::fail(format!(
                    "accepted, but not once written back: {e}"
                ))),
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: cases(256), ..ProptestConfig::default() })]

    #[test]
    fn arbitrary_text_never_panics(text in "[a-z_\\[\\]=.\"'{},0-9eE+\\- \n#é]{0,300}") {
        check(&text)?;
    }

    #[test]
    fn arbitrary_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..300)) {
        check(&String::from_utf8_lossy(&bytes))?;
    }

    #[test]
    fn mutated_valid_configs_never_panic(
        seed in 0..SEEDS.len(),
        mutations in proptest::collection::vec((any::<u8>(), any::<usize>(), any::<u8>(), any::<usize>()), 1..8),
    ) {
        check(&mutate(SEEDS[seed], &mutations))?;
    }
}

#[test]
fn the_seeds_are_valid_and_the_mutator_changes_them() {
    for seed in SEEDS {
        Config::parse(seed).unwrap();
        check(seed).unwrap();
    }
    assert_eq!(Config::parse(SEEDS[0]).unwrap(), Config::default());
    let c = Config::parse(SEEDS[1]).unwrap();
    assert_eq!((c.model.mass_kg, c.model.leaks.len()), (12.5, 1));
    let c = Config::parse(SEEDS[2]).unwrap();
    assert_eq!((c.sensors.adc_bits, c.classifier.warmup_s), (14, 15.0));
    // `mass_kg = 12.5` becomes `mass_kg =nan`: refused by name
    let m = mutate(SEEDS[1], &[(3, SEEDS[1].find("12.5").unwrap(), 0, 0)]);
    assert!(m.contains("mass_kg =nan"), "{m}");
    let e = Config::parse(&m).unwrap_err();
    assert!(e.contains("mass_kg"), "{e}");
}

/// The line of `b` around byte `at`: from its first byte to its newline
/// (exclusive; `b.len()` for the last line without one).
fn line_around(b: &[u8], at: usize) -> (usize, usize) {
    let start = b[..at].iter().rposition(|&c| c == b'\n').map_or(0, |i| i + 1);
    let end = b[at..]
        .iter()
        .position(|&c| c == b'\n')
        .map_or(b.len(), |i| at + i);
    (start, end)
}
