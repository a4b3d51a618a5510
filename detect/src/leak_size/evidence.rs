//! The leak-size detector's reading of an armed estimate: the baseline it
//! measures rises from ([`Sight`]: how far it may trust the estimate), and the
//! evidence of each leak kind ([`Evidence`]).

use super::{BlindCause, LeakSizeDetector};
use crate::offset::MISREADING_WIDENING;
use crate::{misfits_with, EventKind, M3_S_PER_LPM, REACQUIRE_S};
use filter::Estimate;

/// Least real flow per L/min of nominal size that the `min_size_lpm` (or
/// `min_internal_size_lpm`) floor is divided by (a drop of 1 % of p_s/2): below
/// it a hypothesis is not testable.
const MIN_FLOW_FACTOR: f64 = 0.1;

/// How far the detector may read one estimate.
#[derive(Debug, Clone, Copy)]
pub(super) struct Sight {
    /// After a gap, a reset, while the filter is not tracking or the baseline is
    /// taken again: nothing counts, not even a large rise.
    pub invalid: bool,
    /// Invalid, a transducer named reading off, or an excursion and its
    /// recovery: only a very large rise counts.
    pub blind: bool,
    /// A transducer is named reading off: its offset is in the sizes.
    pub misreading: bool,
}

/// The evidence of one estimate, per leak kind (ext1, ext2, int).
#[derive(Debug, Clone, Copy)]
pub(super) struct Evidence {
    /// Rise of each hypothesis' size above its healthy baseline, L/min at p_s/2.
    pub rise: [f64; 3],
    /// The part of the flow mismatch each hypothesis leaves unexplained, L/min.
    pub misfit: [f64; 3],
    /// σ of each hypothesis' size, L/min.
    pub sigma_lpm: [f64; 3],
    /// Each kind's explained rise over the threshold that names it (1).
    pub score: [f64; 3],
    /// The kind with the highest score, and that score.
    pub lead: usize,
    /// The lead's score (1).
    pub best: f64,
    /// The highest score of the other kinds (1).
    pub second: f64,
    /// A kind past `pending_factor` thresholds with evidence, and its ratio.
    pub strong: Option<(usize, f64)>,
    /// The kind whose baseline drift leads against `slow_leak_lpm`, and by how much (1).
    pub slow_lead: (usize, f64),
}

impl LeakSizeDetector {
    /// Thresholds `now` (L/min at p_s/2) raised to the smallest leak declared:
    /// a real flow of `min_size_lpm` (external) or `min_internal_size_lpm` at
    /// the measured pressures (where a hypothesis' drop is small, an internal
    /// leak while p1 ≈ p2, its size at p_s/2 is poorly pinned down and must rise further).
    fn floored(&self, now: [f64; 3]) -> [f64; 3] {
        std::array::from_fn(|k| {
            let g = self.flow_factor[k];
            let m = self.min_size_of(k);
            let floor = if g.is_finite() {
                m / g.max(MIN_FLOW_FACTOR)
            } else {
                m
            };
            now[k].max(floor)
        })
    }

    /// Follows the healthy baseline of the armed detector on estimate `e`
    /// (sizes `raw`, L/min) and says how far the estimate may be read.
    pub(super) fn follow_baseline(&mut self, e: &Estimate, dt_s: f64, raw: &[f64; 3]) -> Sight {
        // During an excursion to tank or supply pressure (where the healthy model is
        // worst and its errors move the leak estimates for a while) and a recovery
        // after it, the baseline holds and no evidence is gathered.
        let excursion = self.excursion(e);
        if excursion {
            self.blind_until_s = self.blind_until_s.max(e.t_s + self.cfg.excursion_recovery_s);
            self.blind_causes.hold(BlindCause::Excursion, self.blind_until_s);
        }
        // After a gap, a reset or while the filter is not tracking nothing counts, not
        // even a large rise; during an excursion only a very large one does.
        let reacquiring = e.t_s >= self.reacquire_after_s && e.t_s < self.reacquire_after_s + REACQUIRE_S;
        let invalid = e.t_s < self.invalid_until_s || self.awaiting_convergence || reacquiring;
        // A transducer named as reading off: the sizes carry its offset, no leak is decided.
        let misreading = self.offsets.standing().is_some();
        let blind = invalid || misreading || e.t_s < self.blind_until_s;
        if blind {
            self.blind_s += dt_s;
            self.blind_causes
                .charge(e.t_s, dt_s, self.awaiting_convergence, misreading);
        }
        // A rise past `baseline_hold` of its threshold holds the baseline for up to
        // `baseline_hold_s`: a leak that opens over seconds is not absorbed before it
        // reaches the threshold; a slow drift of the operating point is followed again.
        // A pattern no leak can make ([`crate::leak_can_make`]) as far from it holds it
        // for up to `baseline_tau_s`, from arming on: leaks only add flow, so a fall is
        // model error (a transient the filter cannot
        // follow kicks the leak estimates down, and they relax back over seconds); a
        // baseline that followed the kick would take the relaxation for a leak.
        let settled = e.t_s - self.armed_at_s >= self.cfg.baseline_tau_s;
        let band: [f64; 3] = std::array::from_fn(|k| self.cfg.baseline_hold * self.thresholds_now()[k]);
        let rise_now: [f64; 3] = std::array::from_fn(|k| raw[k] - self.baseline_lpm[k]);
        let leak_like = crate::leak_can_make_with(rise_now, self.thresholds_now(), self.internal_factors);
        let up = settled && leak_like && (0..3).any(|k| rise_now[k] > band[k]);
        let down = !leak_like && (0..3).any(|k| rise_now[k].abs() > band[k]);
        let longest = if up {
            self.cfg.baseline_hold_s
        } else {
            self.cfg.baseline_tau_s
        };
        match self.hold_since_s {
            Some((was_up, _)) if (up || down) && was_up == up => {}
            _ if up || down => self.hold_since_s = Some((up, e.t_s)),
            _ => self.hold_since_s = None,
        }
        let holding = self.hold_since_s.is_some_and(|(_, t0)| e.t_s - t0 <= longest);
        if self.active.is_none() && self.cfg.baseline_tau_s > 0.0 {
            let a = if reacquiring {
                (dt_s / 0.5).min(1.0)
            } else if blind || holding {
                0.0
            } else {
                (dt_s / self.cfg.baseline_tau_s).min(1.0)
            };
            self.offsets.follow_baseline(a);
            for k in 0..3 {
                self.baseline_lpm[k] += a * (raw[k] - self.baseline_lpm[k]);
                if reacquiring {
                    // The reference of the slow-leak check moves with it: what the
                    // baseline takes up here is not a leak growing.
                    self.stats[k].mean = self.baseline_lpm[k];
                }
            }
        }
        Sight {
            invalid,
            blind,
            misreading,
        }
    }

    /// Weighs the evidence of each leak kind on estimate `e` (sizes `raw`):
    /// rises, misfits, thresholds, the offset watch, a slowly growing leak and
    /// how long each kind has led.
    pub(super) fn weigh_evidence(
        &mut self,
        e: &Estimate,
        dt_s: f64,
        raw: &[f64; 3],
        sight: &Sight,
    ) -> Evidence {
        let Sight {
            invalid,
            blind,
            misreading,
        } = *sight;
        // Rise of each hypothesis' size above its healthy baseline, and how badly the
        // hypothesis fits (the part of the flow mismatch it leaves unexplained).
        let rise: [f64; 3] = std::array::from_fn(|k| raw[k] - self.baseline_lpm[k]);
        let misfit = misfits_with(rise, self.internal_factors);
        let sigma_lpm = self.sigma_lpm(e);
        if self.active.is_none()
            && !blind
            && self.strong_since_s.is_none()
            && (0..3).all(|k| rise[k] < self.cfg.baseline_hold * self.thresholds_now()[k])
        {
            self.refine_thresholds(e.t_s, dt_s, rise);
        }
        // Any rise is judged against `thr`; a kind named by its explained rise
        // against `naming_thr` (learned where that kind's test could alarm).
        let thr = self.past_the_delay(self.floored(self.thresholds_now()));
        if !invalid {
            let watch_thr = self.floored(self.watch_thresholds_now());
            self.watch_offsets(e, dt_s, rise, watch_thr);
        }
        // Rises an offset on a transducer explains better than any leak are no leak
        // evidence; nor are those that a drifting transducer past its tolerance
        // explains as well as a leak does.
        // No new leak is raised on an episode a growing misreading fits at least as
        // well, while it explains the rises now.
        let offset_like = misreading
            || self.offsets.vetoes()
            || self.offsets.rivals_leak(e.t_s)
            || (self.active.is_none() && self.offsets.rivals_new_leak());
        // Where a misreading could make the rises as well as a new leak, a new
        // leak's rise must pass a wider threshold.
        // ([`crate::offset::OffsetWatch::could_make_new_rises`], its fit read once)
        let could_explain = self.offsets.could_explain();
        let widened = self.active.is_none() && could_explain && !self.offsets.leaks_own_episode();
        // Where an offset explains them as well as a leak, a kind is named against `thr`.
        let naming_thr = if could_explain {
            thr
        } else {
            self.past_the_delay(self.floored(self.naming_thresholds_now()))
        };
        let score: [f64; 3] = std::array::from_fn(|k| (rise[k] - misfit[k]) / naming_thr[k]);
        // What the baseline has absorbed since the warm-up, judged against `slow_leak_lpm`.
        let slow_lead = self.follow_slow_lead(e.t_s, offset_like);
        let (lead, best) = (0..3)
            .map(|k| (k, score[k]))
            .fold((0, f64::NEG_INFINITY), |a, b| if b.1 > a.1 { b } else { a });
        let second = (0..3)
            .filter(|k| *k != lead)
            .map(|k| score[k])
            .fold(f64::NEG_INFINITY, f64::max);
        let physical = crate::leak_can_make_with(rise, self.thresholds_now(), self.internal_factors);
        // (a frozen position's pattern: no new leak while an internal leak leads)
        let frozen_x = self.frozen_position && self.active.is_none() && lead == 2;
        let mut strong = None;
        // (a rise that came with the valve's flow after a rest waits for it to stop)
        if !invalid {
            let response = e
                .offset_response_lpm_per_mpa
                .map(|r| crate::signatures_with(r, self.internal_factors));
            self.flow_hold.update(e.t_s, e.u_v, response, rise, thr);
        }
        for k in 0..3 {
            let (thr, naming_thr) = (thr[k], naming_thr[k]);
            if rise[k] < 0.25 * thr {
                self.last_low_s[k] = e.t_s;
                self.baseline_low_lpm[k] = self.baseline_lpm[k];
            }
            let under_widened = widened && rise[k] < MISREADING_WIDENING * thr;
            let with_flow = self.active.is_none() && self.flow_hold.holds(k, e.t_s, rise[k]);
            let evidence = !invalid
                && !offset_like
                && !under_widened
                && !with_flow
                && !frozen_x
                && physical
                && (!blind || rise[k] > self.cfg.excursion_override * thr);
            let ratio = rise[k] / thr;
            if evidence
                && self.cfg.pending_factor > 0.0
                && ratio > self.cfg.pending_factor
                && strong.is_none_or(|(_, r)| ratio > r)
            {
                strong = Some((k, ratio));
            }
            // The kind is decided before the alarm: the named kind must explain the
            // mismatch (what it leaves unexplained is a small part of its size).
            let clear = misfit[k] <= self.cfg.isolation_max_misfit * rise[k];
            // (a named event is followed while its kind leads; a pending one waits for a clear kind)
            let named = self.active.is_some_and(|a| a.kind != EventKind::Leak);
            if k == lead && rise[k] > naming_thr && best > 0.5 && evidence && (clear || named) {
                if self.above_since_s[k].is_none() {
                    self.above_since_s[k] = Some(e.t_s);
                    self.above_evidence_s[k] = 0.0;
                } else {
                    let gain = rise[k] / naming_thr;
                    self.above_evidence_s[k] += dt_s * gain.min(self.cfg.confirm_gain_cap).max(1.0);
                }
            } else {
                self.above_since_s[k] = None;
            }
        }
        match strong {
            Some(_) => {
                self.strong_since_s.get_or_insert(e.t_s);
            }
            None => self.strong_since_s = None,
        }
        Evidence {
            rise,
            misfit,
            sigma_lpm,
            score,
            lead,
            best,
            second,
            strong,
            slow_lead,
        }
    }

    /// σ of each hypothesis' size on estimate `e`, L/min: the filter's marginal
    /// σ (correlations ignored) combined with the spread the healthy estimate
    /// showed in the warm-up (the filter alone is overconfident about model error).
    fn sigma_lpm(&self, e: &Estimate) -> [f64; 3] {
        let sigma_q = [
            e.sigma[7] / M3_S_PER_LPM,
            e.sigma[8] / M3_S_PER_LPM,
            e.sigma[9] / M3_S_PER_LPM,
        ];
        // (√(a² + b²) directly: these are L/min, far from where `hypot`'s
        // guard against overflow matters, and it costs five library calls a sample)
        let root_sum_square = |a: f64, b: f64| (a * a + b * b).sqrt();
        let sigma_filter = [
            root_sum_square(sigma_q[0], sigma_q[2]),
            root_sum_square(sigma_q[1], sigma_q[2]),
            0.5 * (sigma_q[0].powi(2) + sigma_q[1].powi(2) + 4.0 * sigma_q[2].powi(2)).sqrt(),
        ];
        std::array::from_fn(|k| root_sum_square(sigma_filter[k], self.stats[k].std()))
    }

    /// Feeds the offset watch one sample's rises `rise` (L/min at p_s/2) on
    /// estimate `e`, `dt_s` (s) after the last, against thresholds `thr`
    /// (L/min); keeps the sensor event of a change of the named offset.
    fn watch_offsets(&mut self, e: &Estimate, dt_s: f64, rise: [f64; 3], thr: [f64; 3]) {
        self.offsets
            .leak_named(self.active.is_some_and(|a| a.kind != EventKind::Leak));
        let change = self.offsets.on_rise(
            e.t_s,
            dt_s,
            rise,
            &crate::offset::MisreadingResponse {
                offset_lpm_per_mpa: e.offset_response_lpm_per_mpa,
                span_lpm: e.span_response_lpm,
                position_lpm_per_mm: e.position_offset_response_lpm_per_mm,
            },
            [e.measured[1] * 1e-6, e.measured[2] * 1e-6],
            self.internal_factors,
            thr,
            &mut self.next_id,
        );
        if let Some(change) = change {
            self.sensor_event = Some(crate::offset::offset_event(change, e.t_s, "leak-size"));
        }
    }

    /// The kind whose baseline drift since the warm-up leads against
    /// `slow_leak_lpm`, and by how much (1); at `t_s` (s) it starts or ends
    /// the time that kind has led (none while `offset_like` or an event stands).
    fn follow_slow_lead(&mut self, t_s: f64, offset_like: bool) -> (usize, f64) {
        let drift: [f64; 3] = std::array::from_fn(|k| self.baseline_lpm[k] - self.stats[k].mean);
        let drift_misfit = misfits_with(drift, self.internal_factors);
        let slow_lead = (0..3)
            .map(|k| (k, (drift[k] - drift_misfit[k]) / self.cfg.slow_leak_lpm.max(1e-9)))
            .fold((0, f64::NEG_INFINITY), |a, b| if b.1 > a.1 { b } else { a });
        if self.active.is_none() && self.cfg.baseline_tau_s > 0.0 && slow_lead.1 > 1.0 && !offset_like {
            match self.slow_since_s {
                Some((j, _)) if j == slow_lead.0 => {}
                _ => self.slow_since_s = Some((slow_lead.0, t_s)),
            }
        } else {
            self.slow_since_s = None;
        }
        slow_lead
    }
}
