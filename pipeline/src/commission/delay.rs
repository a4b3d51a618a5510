//! The pressure transducers' delay, fitted to the leak sizes' swings on the
//! commissioning's recording.
//!
//! A transducer delayed by d reads p − d·ṗ. Where the pressures move fast
//! (a press's stiff chambers) that misreading moves the leak sizes by d times
//! the filter's own response to a delay
//! ([`filter::Estimate::delay_response_lpm_per_ms`]): a swing with the duty
//! cycle, not a leak's step. On a healthy recording the leaks are zero, so
//! each size is a constant plus d times its response: d is the least-squares
//! coefficient, one for both transducers. The identification's lag reading
//! ([`identify::Identification::pressure_lag_s`]) fits the pressures' own
//! rates and can trade against what else is fast; this fit reads d where it
//! matters, on the leak sizes.

use filter::{FLAG_CONVERGING, FLAG_RESET, FLAG_SKIPPED};
use model::process::I_QE1;
use model::units::m3_s_to_lpm;

use super::{bias_then_learn, energy, fit_misreading, Pass, MISREADING_LEAST_SHARE};
use config::Config;
use std::path::Path;

/// The least uncertainty of a delay taken, as a share of it (1): the fit
/// reads a pure delay, while a lag also damps a swing's fast part, so the
/// delay that fits depends on the duty cycle, and the fit takes up what else
/// swings like it. `bench instances`' seed 1: the commissioning's fit read
/// 0.51-1.15 times the transducers' lag on the press (median 0.97), 0.24-1.01
/// on the lift (median 0.90).
pub const DELAY_UNCERTAIN_SHARE: f64 = 0.2;

/// The delay's fit is sure where taking it off the leak sizes takes at least
/// this share of the healthy spreads' energy (1), or halves the time left
/// out ([`LEFT_OUT_LEAST_S`]): the swings are the delay's. Short of it the
/// fit may have taken up what else swings like it, and the healthy spreads
/// hold over no delay to [`DELAY_HELD_ABOVE`] times it.
pub const SURE_FIT_SHARE: f64 = 0.8;

/// The longest delay the healthy spreads of a fit that is not sure hold
/// over, as a share of the one taken (1); the shortest is none.
pub const DELAY_HELD_ABOVE: f64 = 1.2;

/// The time left out as a pattern no leak can make, s, past which a delay
/// that halves it is taken whatever the spreads do: the spreads of a pass
/// that leaves much of the recording out are learned on what the model
/// follows, and do not compare with those of one that follows more of it.
/// `bench instances`' seed-1 press, inst_005 (lags 0.47 ms): 66 s of 116 left
/// out without the delay, none with it; its spreads' energy grows 4-fold.
pub const LEFT_OUT_LEAST_S: f64 = 10.0;

/// The longest lag the datasheet's response time allows `cfg`'s pressure
/// transducers, s ([`identify::MAX_LAG_S`] without one).
pub(super) fn lag_bound_s(cfg: &Config) -> f64 {
    cfg.datasheet
        .as_ref()
        .and_then(|d| d.pressure_transducers.lag_bound_s())
        .unwrap_or(identify::MAX_LAG_S)
}

/// The sums of the least-squares fit of each leak size (L/min) to a constant
/// plus d times its delay response (L/min per ms), over the converged samples,
/// and those responses.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct DelayFit {
    /// Samples summed.
    n: u64,
    /// Per kind (ext1, ext2, int): Σr, Σq, Σr·q, Σr² (r the response summed over p1 and p2).
    sums: [[f64; 4]; 3],
    /// Each converged sample's response (q_e1, q_e2, q_i), L/min per ms.
    responses: Vec<[f64; 3]>,
}

/// The share of the commissioning's samples whose response to a delay the
/// reach ([`DelayFit::reach_lpm_per_ms`]) holds (1): its spreads, and so the
/// thresholds, saw responses up to it.
pub const RESPONSE_REACH_SHARE: f64 = 0.99;

impl DelayFit {
    /// Adds estimate `e` when the filter has converged on a full sample.
    pub fn push(&mut self, e: &filter::Estimate) {
        if e.flags & (FLAG_CONVERGING | FLAG_RESET | FLAG_SKIPPED) != 0 {
            return;
        }
        let r: [f64; 3] =
            std::array::from_fn(|k| e.delay_response_lpm_per_ms[0][k] + e.delay_response_lpm_per_ms[1][k]);
        let q: [f64; 3] = std::array::from_fn(|k| m3_s_to_lpm(e.state[I_QE1 + k]));
        if r.iter().chain(&q).any(|v| !v.is_finite()) {
            return;
        }
        self.n += 1;
        self.responses.push(r);
        for k in 0..3 {
            let s = &mut self.sums[k];
            s[0] += r[k];
            s[1] += q[k];
            s[2] += r[k] * q[k];
            s[3] += r[k] * r[k];
        }
    }

    /// The response to a delay each kind's size (ext1, ext2, int, in the
    /// signatures with `factors`: [`detect::signatures_with`]) stayed within
    /// on [`RESPONSE_REACH_SHARE`] of the samples, L/min per ms (0 without samples).
    pub fn reach_lpm_per_ms(&self, factors: [f64; 2]) -> [f64; 3] {
        // (each response in the signatures once, not once per kind)
        let signatures: Vec<[f64; 3]> = self
            .responses
            .iter()
            .map(|r| detect::signatures_with(*r, factors))
            .collect();
        std::array::from_fn(|k| {
            let mut v: Vec<f64> = signatures.iter().map(|s| s[k].abs()).collect();
            if v.is_empty() {
                return 0.0;
            }
            let i = ((RESPONSE_REACH_SHARE * v.len() as f64) as usize).min(v.len() - 1);
            *v.select_nth_unstable_by(i, f64::total_cmp).1
        })
    }

    /// The delay that fits the sizes' swings, s (`None` without samples or
    /// without a response to fit); the sizes summed are those published, so
    /// it adds to the delay already taken off them.
    pub fn delay_s(&self) -> Option<f64> {
        if self.n < 2 {
            return None;
        }
        let n = self.n as f64;
        let (mut rq, mut rr) = (0.0, 0.0);
        for s in &self.sums {
            rq += s[2] - s[0] * s[1] / n;
            rr += s[3] - s[0] * s[0] / n;
        }
        (rr > 0.0).then(|| rq / rr * 1.0e-3)
    }
}

/// Widens the healthy spreads of `pass` (learned from `identified` on
/// `input`, with the delay `taken` off the sizes and the misreading `pass`
/// took) to hold over a fit that is not sure ([`DelayTaken::sure`]): each
/// kind's spread (and its clear spread) becomes the largest of its own, of
/// the commissioning's without the delay taken off (its misreading fitted
/// within `tolerance` as it would be then), and of the one with the delay
/// [`DELAY_HELD_ABOVE`] times longer (up to the datasheet's bound).
pub(super) fn hold_over_unsure_fit(
    input: &Path,
    identified: &Config,
    taken: &DelayTaken,
    tolerance: Option<identify::TransducerTolerance>,
    pass: &mut Pass,
) -> Result<(), String> {
    let mut plain_cfg = identified.clone();
    plain_cfg.leak_filter.lag_correction_s = 0.0;
    let mut plain = bias_then_learn(input, &plain_cfg)?;
    if let Some(t) = tolerance {
        fit_misreading(input, &plain_cfg, t, &mut plain)?;
    }
    let mut longer_cfg = identified.clone();
    longer_cfg.model.pressure_misreading_pa = pass.cfg.model.pressure_misreading_pa;
    longer_cfg.leak_filter.lag_correction_s = taken.longest_held_s();
    let longer = bias_then_learn(input, &longer_cfg)?;
    for other in [plain.trace.commissioning, longer.trace.commissioning] {
        let held = &mut pass.trace.commissioning;
        for k in 0..3 {
            held.spreads_lpm[k] = held.spreads_lpm[k].max(other.spreads_lpm[k]);
            if held.clear_spreads_lpm[k].is_finite() && other.clear_spreads_lpm[k].is_finite() {
                held.clear_spreads_lpm[k] = held.clear_spreads_lpm[k].max(other.clear_spreads_lpm[k]);
            }
        }
    }
    Ok(())
}

/// The delay fitted and whether it was taken.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DelayTaken {
    /// The delay fitted, clamped to what the datasheet allows, s.
    pub delay_s: f64,
    /// The longest lag the datasheet allows, s.
    pub bound_s: f64,
    /// The healthy spreads before and with it taken off (ext1, ext2, int), L/min.
    pub spreads_lpm: [[f64; 3]; 2],
    /// The time left out as a pattern no leak can make, before and with it taken off, s.
    pub left_out_s: [f64; 2],
    /// Taken: the spreads' energy fell by [`MISREADING_LEAST_SHARE`] or
    /// more, or the time left out ([`LEFT_OUT_LEAST_S`] or more) halved.
    pub taken: bool,
}

impl DelayTaken {
    /// The share of the healthy spreads' energy taking the delay off takes (1).
    pub fn energy_fall(&self) -> f64 {
        1.0 - energy(self.spreads_lpm[1]) / energy(self.spreads_lpm[0]).max(f64::MIN_POSITIVE)
    }

    /// Whether the fit is sure ([`SURE_FIT_SHARE`], or the time left out
    /// halved: a pass without it does not follow the rig).
    pub fn sure(&self) -> bool {
        self.taken && (self.energy_fall() >= SURE_FIT_SHARE || follows_more(self.left_out_s))
    }

    /// The longest delay the healthy spreads of a fit that is not sure hold
    /// over, s: [`DELAY_HELD_ABOVE`] times the one taken, up to the datasheet's bound.
    pub fn longest_held_s(&self) -> f64 {
        (self.delay_s * DELAY_HELD_ABOVE).min(self.bound_s)
    }

    /// The line commissioning prints.
    pub fn line(&self) -> String {
        let fall = self.energy_fall();
        let verdict = if self.sure() {
            "taken off the leak sizes, a sure fit".to_string()
        } else if self.taken {
            format!(
                "taken off the leak sizes; not a sure fit (a fall under {:.0} %): the thresholds hold over 0-{:.3} ms",
                100.0 * SURE_FIT_SHARE,
                self.longest_held_s() * 1e3
            )
        } else {
            format!("not taken (a fall under {:.0} %)", 100.0 * MISREADING_LEAST_SHARE)
        };
        let left_out = if self.left_out_s[0] > 0.0 || self.left_out_s[1] > 0.0 {
            format!(
                ", the time left out as no leak's pattern {:.1} -> {:.1} s",
                self.left_out_s[0], self.left_out_s[1]
            )
        } else {
            String::new()
        };
        format!(
            "the pressure transducers' delay fitted to the leak sizes' swings: {:.3} ms; \
             the healthy spreads' energy falls by {:.0} % with it{left_out}: {verdict}",
            self.delay_s * 1e3,
            100.0 * fall
        )
    }
}

/// Whether a delay is taken, with the healthy spreads (L/min) and the time
/// left out as no leak's pattern (s) before and with it: the spreads' energy
/// falls by [`MISREADING_LEAST_SHARE`], or the time left out,
/// [`LEFT_OUT_LEAST_S`] or more, halves.
fn takes_delay(spreads_lpm: [[f64; 3]; 2], left_out_s: [f64; 2]) -> bool {
    let falls = energy(spreads_lpm[1]) <= (1.0 - MISREADING_LEAST_SHARE) * energy(spreads_lpm[0]);
    falls || follows_more(left_out_s)
}

/// Whether the time left out as no leak's pattern (s; before and with a
/// delay taken), [`LEFT_OUT_LEAST_S`] or more, halves with the delay.
fn follows_more(left_out_s: [f64; 2]) -> bool {
    left_out_s[0] >= LEFT_OUT_LEAST_S && left_out_s[1] <= 0.5 * left_out_s[0]
}

/// Fits the transducers' delay to the commissioning of `pass` (learned from
/// `identified` on `input`), up to `bound_s`, and takes it off the leak sizes
/// where the healthy spreads' energy falls by [`MISREADING_LEAST_SHARE`], or
/// where the time left out as no leak's pattern, [`LEFT_OUT_LEAST_S`] or
/// more, halves:
/// `identified` and `pass` then carry it. `None` when nothing fits (no
/// response, or a delay of 0).
pub(super) fn fit_delay(
    input: &Path,
    identified: &mut Config,
    bound_s: f64,
    pass: &mut Pass,
) -> Result<Option<DelayTaken>, String> {
    let Some(d) = pass.trace.delay.delay_s() else {
        return Ok(None);
    };
    let delay_s = (identified.leak_filter.lag_correction_s + d).clamp(0.0, bound_s);
    if delay_s <= 0.0 {
        return Ok(None);
    }
    let mut trial_cfg = identified.clone();
    trial_cfg.leak_filter.lag_correction_s = delay_s;
    let trial = bias_then_learn(input, &trial_cfg)?;
    let before = pass.trace.commissioning.spreads_lpm;
    let after = trial.trace.commissioning.spreads_lpm;
    let left_out_s = [pass.trace.left_out_s, trial.trace.left_out_s];
    let taken = takes_delay([before, after], left_out_s);
    if taken {
        *identified = trial_cfg;
        *pass = trial;
    }
    Ok(Some(DelayTaken {
        delay_s,
        bound_s,
        spreads_lpm: [before, after],
        left_out_s,
        taken,
    }))
}

/// How uncertain the delay taken off the leak sizes (`lag_correction_s`, s;
/// 0: none taken) is, s: how far it lies from the identification's lag
/// (`pressure_lag_s`, s, the mean of p1's and p2's; not counted where none
/// was read), and at least [`DELAY_UNCERTAIN_SHARE`] of it. The fit here
/// reads the delay on the commissioning's duty cycle and takes up what else
/// swings like it; the identification reads it on the pressures' own rates.
/// A limit cycle the recording lacks (a press's 125 Hz oscillation in a
/// slow stroke, `bench instances`' seed-2 inst_016) moves the sizes by the
/// delay's error times their response to a delay.
pub fn uncertainty_s(lag_correction_s: f64, pressure_lag_s: [f64; 2]) -> f64 {
    if !lag_correction_s.is_finite() {
        return 0.0;
    }
    let taken_s = lag_correction_s.max(0.0);
    let lag_s = mean_lag_s(pressure_lag_s);
    let apart_s = if lag_s.is_finite() && lag_s > 0.0 {
        (taken_s - lag_s).abs()
    } else {
        0.0
    };
    apart_s.max(DELAY_UNCERTAIN_SHARE * taken_s)
}

/// The mean of p1's and p2's lag `pressure_lag_s` (s): the identification's
/// one reading of the delay.
fn mean_lag_s(pressure_lag_s: [f64; 2]) -> f64 {
    0.5 * (pressure_lag_s[0] + pressure_lag_s[1])
}

/// The response to a delay (L/min per ms, per kind) the commissioning's
/// spreads saw its uncertainty at, for a delay `sure_fit` taken or not and
/// the recording's `reach_lpm_per_ms` ([`DelayFit::reach_lpm_per_ms`]): none
/// after a sure fit (it chose the delay to make those spreads least, so they
/// understate a delay that is off), the recording's reach otherwise (its
/// spreads hold over the delay's range, or carry the lag's whole imprint).
pub fn response_seen_lpm_per_ms(sure_fit: bool, reach_lpm_per_ms: [f64; 3]) -> [f64; 3] {
    if sure_fit {
        [0.0; 3]
    } else {
        reach_lpm_per_ms
    }
}

/// The line commissioning prints on the delay's uncertainty `uncertainty_s`
/// (s) with the identification's lags `pressure_lag_s` (s); `None` without one.
pub fn uncertainty_line(uncertainty_s: f64, pressure_lag_s: [f64; 2]) -> Option<String> {
    (uncertainty_s > 0.0).then(|| {
        let lag_s = mean_lag_s(pressure_lag_s);
        let read = if lag_s > 0.0 {
            format!("the identification's lag {:.3} ms", lag_s * 1e3)
        } else {
            format!(
                "no lag identified: {:.0} % of the delay taken",
                DELAY_UNCERTAIN_SHARE * 100.0
            )
        };
        format!(
            "the transducers' delay is uncertain by {:.3} ms ({read}): \
             a leak's rise must pass its threshold and that times the leak sizes' response to a delay",
            uncertainty_s * 1e3,
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use model::units::lpm_to_m3_s;

    #[test]
    fn the_line_says_whether_the_delay_is_taken_and_its_fit_sure() {
        let taken = |fall: f64, taken: bool| DelayTaken {
            delay_s: 0.4e-3,
            bound_s: 0.45e-3,
            // the spreads' energy falls by `fall`: the second's is 1 − fall of the first's
            spreads_lpm: [[0.1, 0.0, 0.0], [0.1 * (1.0 - fall).sqrt(), 0.0, 0.0]],
            left_out_s: [0.0; 2],
            taken,
        };
        let sure = taken(0.95, true);
        assert!((sure.energy_fall() - 0.95).abs() < 1e-12);
        assert!(sure.sure());
        assert!(
            sure.line().contains("0.400 ms; the healthy spreads' energy falls by 95 % with it: taken off the leak sizes, a sure fit"),
            "{}",
            sure.line()
        );
        // a fall of 75 %: taken, not sure, held up to 1.2 times it (the datasheet's bound)
        let unsure = taken(0.75, true);
        assert!(!unsure.sure());
        assert!((unsure.longest_held_s() - 0.45e-3).abs() < 1e-15);
        assert!(
            unsure.line().ends_with("the thresholds hold over 0-0.450 ms"),
            "{}",
            unsure.line()
        );
        assert!(taken(0.2, false)
            .line()
            .ends_with("not taken (a fall under 33 %)"));
        assert!(!taken(0.95, false).sure());
        // the time left out halved: sure, whatever the spreads do
        let follows = DelayTaken {
            left_out_s: [66.0, 0.0],
            ..taken(-3.0, true)
        };
        assert!(follows.sure());
        assert!(
            follows
                .line()
                .contains("left out as no leak's pattern 66.0 -> 0.0 s"),
            "{}",
            follows.line()
        );
    }

    #[test]
    fn the_reach_is_the_response_99_percent_of_the_samples_stay_within() {
        let factors = detect::NOMINAL_INTERNAL_FACTORS;
        // 200 samples with responses 1..=200 on ext1 and half of it, reversed, on ext2
        let fit = DelayFit {
            responses: (1..=200)
                .map(|i| [i as f64, -0.5 * (201 - i) as f64, 0.0])
                .collect(),
            ..DelayFit::default()
        };
        let want: [f64; 3] = std::array::from_fn(|k| {
            let mut v: Vec<f64> = fit
                .responses
                .iter()
                .map(|r| detect::signatures_with(*r, factors)[k].abs())
                .collect();
            v.sort_by(f64::total_cmp);
            v[198]
        });
        assert_eq!(fit.reach_lpm_per_ms(factors), want);
        assert!(want[0] > 0.0 && want[1] > 0.0, "{want:?}");
        assert_eq!(DelayFit::default().reach_lpm_per_ms(factors), [0.0; 3]);
    }

    #[test]
    fn the_response_seen_is_none_after_a_sure_fit() {
        let reach = [0.1, 0.2, 0.3];
        assert_eq!(response_seen_lpm_per_ms(true, reach), [0.0; 3]);
        assert_eq!(response_seen_lpm_per_ms(false, reach), reach);
    }

    #[test]
    fn the_delay_is_as_uncertain_as_its_two_readings_disagree() {
        // the fit's 0.865 ms against lags of 0.649 and 0.647 ms
        let u = uncertainty_s(0.865e-3, [0.649e-3, 0.647e-3]);
        assert!((u - 0.217e-3).abs() < 1e-12, "{u}");
        // none taken: as uncertain as the lag read
        assert!((uncertainty_s(0.0, [0.3e-3, 0.5e-3]) - 0.4e-3).abs() < 1e-12);
        // readings that agree, or no lag read: a fifth of the delay taken
        assert!((uncertainty_s(0.5e-3, [0.49e-3, 0.51e-3]) - 0.1e-3).abs() < 1e-12);
        assert!((uncertainty_s(0.865e-3, [0.0; 2]) - 0.173e-3).abs() < 1e-12);
        // nothing taken and no lag read, or a delay that is no number: none
        assert_eq!(uncertainty_s(0.0, [0.0; 2]), 0.0);
        assert_eq!(uncertainty_s(f64::NAN, [0.6e-3; 2]), 0.0);
        let line = uncertainty_line(u, [0.649e-3, 0.647e-3]).expect("a line");
        assert!(
            line.contains("uncertain by 0.217 ms") && line.contains("lag 0.648 ms"),
            "{line}"
        );
        assert_eq!(uncertainty_line(0.0, [0.0; 2]), None);
        let line = uncertainty_line(0.173e-3, [0.0; 2]).expect("a line");
        assert!(
            line.contains("uncertain by 0.173 ms (no lag identified: 20 % of the delay taken)"),
            "{line}"
        );
    }

    #[test]
    fn a_delay_is_taken_where_the_spreads_fall_or_the_time_left_out_halves() {
        let (small, large) = ([0.01, 0.01, 0.01], [0.02, 0.02, 0.02]);
        // a third of the energy away: taken
        assert!(takes_delay([large, [0.016, 0.016, 0.016]], [0.0; 2]));
        assert!(!takes_delay([large, [0.017, 0.017, 0.017]], [0.0; 2]));
        // spreads four times the energy, but 66 s left out before and none after
        assert!(takes_delay([small, large], [66.0, 0.0]));
        // less than halved, or too little left out to count
        assert!(!takes_delay([small, large], [66.0, 40.0]));
        assert!(!takes_delay([small, large], [8.0, 0.0]));
    }

    #[test]
    fn the_fit_reads_the_delay_of_sizes_that_swing_with_their_response() {
        // each size a constant of its own plus 0.3 ms times its response
        // (L/min per ms), the responses swinging differently per kind
        let mut fit = DelayFit::default();
        let mut e = filter::Estimate::default();
        for i in 0..1000 {
            let t = i as f64 * 1e-3;
            e.delay_response_lpm_per_ms = [[0.0; 3]; 2];
            for k in 0..3 {
                let r = (7.0 * t + k as f64).sin() * (k + 1) as f64;
                // on p1 for ext1 and int, on p2 for ext2: the fit sums the two
                e.delay_response_lpm_per_ms[k % 2][k] = r;
                e.state[I_QE1 + k] = lpm_to_m3_s(0.05 * k as f64 + 0.3 * r);
            }
            fit.push(&e);
        }
        let d = fit.delay_s().expect("a delay");
        assert!((d - 0.3e-3).abs() < 1e-12, "read {d} s");
        // an estimate still converging is not summed
        let mut converging = DelayFit::default();
        e.flags = FLAG_CONVERGING;
        converging.push(&e);
        assert_eq!(converging.delay_s(), None);
    }
}
