//! Every effect of the library under varied inputs
//! (docs/calibration/README.md): `suite::matrix_cases` puts each effect (both forms of
//! `bulk-modulus`) on a rig with sensor noise and a small mismatch in mass
//! and viscous friction, under each of the open-loop sine, the open-loop
//! chirp and the closed-loop pseudorandom steps, and the spring also under
//! the two loaded scenarios; plus the two-effect cases and nine clean
//! controls. The workflow must name the hidden effect first, fit its
//! parameters within 10 % and shrink the validation gap by at least 70 %;
//! two-effect cases must find both; clean data must name nothing.
//!
//! This matrix asserts the multiple-shooting comparison
//! (`CalibrateOptions::shooting()`, smooth rig). The default equation-error
//! comparison is asserted on the base suite (`hidden_effects.rs`) and on the
//! stick-slip rig (`thesis_rig.rs`).
//!
//! Which pairs are left out, and why:
//! - every effect is excitable by all three inputs. The spring touches at
//!   0.22 m and every scenario starts the rod at 0.30 m, so the spring is
//!   compressed from the first sample; the sine and the closed-loop steps
//!   also cross the contact. (A spring whose contact the data never reach is
//!   tested in `identifiability_and_bad_input.rs`: not identifiable.)
//! - the loaded scenarios carry their own spring (`Simulator` puts it on the
//!   rig), so they are paired with `spring-load` only: with any other effect
//!   they would be two-effect cases with a spring nobody asked about.
//!
//! The one case that cannot meet the letter of the requirement, and what is
//! asserted instead: entrained air under the closed-loop steps. The position
//! controller keeps both chambers near the operating pressure (mean 6.9 MPa,
//! rarely below 4 MPa), where an air fraction and a lower constant bulk
//! modulus are the same thing: over every window the two forms explain the
//! record equally (paired t ≈ 2 against ≥ 5 under the open-loop inputs).
//! The air fraction is then confounded with the 3 % mass mismatch (which
//! looks like a 3 % softer oil) and comes out 16 % high. The workflow says so
//! (`FoundEffect::caveat`: "form not identifiable from this data"); the test
//! asserts that caveat, the right name first, the gap shrink, and that the
//! effective bulk modulus at the mean chamber pressure (what the data do pin
//! down) is within 10 %.
//!
//! Runs the 44 cases on two threads (`suite::bench_cases`, `std::thread::scope`).

use std::time::Instant;

use calibrate::suite::{bench_cases, matrix_cases, CaseResult, MATRIX_SCENARIOS};
use calibrate::{CalibrateOptions, Effect, NOT_IDENTIFIABLE};

/// What a case must show.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Expect {
    /// Every hidden effect named (one of them first), nothing else;
    /// parameters within 10 %; gap shrink ≥ 70 %; no caveat.
    Found,
    /// As `Found`, but the workflow must say the effect's form is not
    /// identifiable; the effective bulk modulus at the mean chamber pressure
    /// stands in for the air fraction.
    FormNotIdentifiable,
    /// Clean data: nothing named.
    Quiet,
}

fn expectation(r: &CaseResult) -> Expect {
    if r.hidden.is_empty() {
        Expect::Quiet
    } else if r.case == "bulk-modulus (entrained air) / closed-loop-random" {
        Expect::FormNotIdentifiable
    } else {
        Expect::Found
    }
}

fn check(r: &CaseResult, failures: &mut Vec<String>) {
    let mut fail = |m: String| failures.push(format!("{}: {m}", r.case));
    if let Some(e) = &r.error {
        fail(format!("error {e}"));
        return;
    }
    let expect = expectation(r);
    if expect == Expect::Quiet {
        if !r.named.is_empty() {
            fail(format!("clean data named {:?}", r.named));
        }
        return;
    }
    if !r.right_first {
        fail(format!("named {:?} first, hidden {:?}", r.named, r.hidden));
    }
    if !r.all_found {
        fail(format!("named {:?}, hidden {:?}", r.named, r.hidden));
    }
    if r.gap_shrink.is_nan() || r.gap_shrink < 0.70 {
        fail(format!("gap shrank only {:.0} %", 100.0 * r.gap_shrink));
    }
    match expect {
        Expect::Found => {
            for p in &r.parameters {
                if p.relative_error.is_nan() || p.relative_error > 0.10 {
                    fail(format!(
                        "{} fitted {:.4e} vs truth {:.4e} ({:.1} %)",
                        p.parameter,
                        p.fitted,
                        p.truth,
                        100.0 * p.relative_error
                    ));
                }
            }
            if !r.caveats.is_empty() {
                fail(format!("unexpected caveat {:?}", r.caveats));
            }
        }
        Expect::FormNotIdentifiable => {
            if !r.caveats.iter().any(|c| c.contains(NOT_IDENTIFIABLE)) {
                fail(format!("the form was claimed (caveats {:?})", r.caveats));
            }
            match r.effective_bulk_modulus_error {
                Some(e) if e <= 0.10 => {}
                other => fail(format!("effective bulk modulus error {other:?}")),
            }
        }
        Expect::Quiet => {}
    }
}

#[test]
fn every_effect_under_every_input() {
    let list = matrix_cases();
    // coverage: each effect form under each input of the matrix
    for e in Effect::ALL {
        for sc in MATRIX_SCENARIOS {
            assert!(
                list.iter()
                    .any(|c| c.scenario == sc && c.hidden.len() == 1 && c.hidden[0].0.name() == e.name()),
                "no matrix case for {e:?} under {sc}"
            );
        }
    }
    assert!(list.iter().filter(|c| c.hidden.len() == 2).count() >= 3);
    assert!(list.iter().filter(|c| c.hidden.is_empty()).count() >= 9);

    let t0 = Instant::now();
    let rep = bench_cases(&list, &CalibrateOptions::shooting(), 2);
    eprintln!("{}", rep.markdown());
    eprintln!("{} cases in {:.1} s", list.len(), t0.elapsed().as_secs_f64());
    assert_eq!(rep.cases.len(), list.len());

    let mut failures = Vec::new();
    for r in &rep.cases {
        check(r, &mut failures);
    }
    assert!(
        failures.is_empty(),
        "{} failures:\n{}",
        failures.len(),
        failures.join("\n")
    );
}
