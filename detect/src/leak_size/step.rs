// Over 600 lines: one decision per estimate, in order; it is split into typed parts (validity gate, baseline, arming, evidence) with the detector's split.
//! The leak-size detector's decision on each estimate: the validity gate, the
//! baseline, the alarm (kind pending or named), re-isolation, updates and clearing.

use super::LeakSizeDetector;
use crate::track::Active;
use crate::track::Arming;
use crate::{
    misfits_with, EventKind, LeakEvent, Phase, COMMAND_RATE_WINDOW_S, COMMAND_REVERSAL_BAND_V,
    KIND_AVERAGE_S, M3_S_PER_LPM, NIS_RATIO_WINDOW_S, REACQUIRE_S,
};
use filter::{Estimate, FLAG_CONVERGING, FLAG_REANCHORED, FLAG_RESET, FLAG_SKIPPED};

/// Least real flow per L/min of nominal size that the `min_size_lpm` (or
/// `min_internal_size_lpm`) floor is divided by (a drop of 1 % of p_s/2): below
/// it a hypothesis is not testable.
const MIN_FLOW_FACTOR: f64 = 0.1;

impl LeakSizeDetector {
    /// The thresholds in force, L/min at p_s/2: the commissioning's (or the
    /// refined ones) widened by what the oil's temperature leaves uncertain.
    fn thresholds_now(&self) -> [f64; 3] {
        std::array::from_fn(|k| self.threshold_lpm[k] + self.oil_band_lpm[k])
    }

    /// Takes the laminar flows' uncertainty of estimate `e` into
    /// [`Self::thresholds_now`]: the model's null leakage (its band) and the
    /// healthy offsets, each as uncertain as the laminar factor.
    fn widen_for_the_oil(&mut self, e: &Estimate) {
        self.oil_band_lpm = crate::oil_band_lpm(
            e.laminar_factor_sigma,
            e.null_leakage_band_lpm,
            self.offsets_lpm(),
        );
    }

    /// Reads one estimate; pushes any event into `out` (at most one per call).
    pub fn on_estimate(&mut self, e: &Estimate, out: &mut Option<LeakEvent>) {
        if e.n_states < 10 {
            return;
        }
        self.widen_for_the_oil(e);
        let dt_s = if self.last_t_s.is_finite() {
            (e.t_s - self.last_t_s).clamp(0.0, 1.0)
        } else {
            0.0
        };
        // Validity gate: a gap the filter could not bridge (it re-anchored), a skipped
        // sample or a reset blinds the detector for `recovery_s`; so does a filter
        // whose innovations are far beyond its own covariance (not tracking). The
        // baseline holds while blind. A gap the filter bridged by prediction (a few
        // samples; `FLAG_AFTER_GAP` alone) or estimates lost on their way here leave
        // the filter tracking: evidence goes on (the NIS gate still watches).
        let recover = e.t_s + self.cfg.recovery_s;
        if e.flags & (FLAG_SKIPPED | FLAG_REANCHORED | FLAG_RESET) != 0 {
            self.invalid_until_s = self.invalid_until_s.max(recover);
            if e.flags & FLAG_RESET != 0 {
                // The filter started again from its initial leak sizes: the baseline
                // is taken again once it has settled. (After a gap the filter keeps
                // its leak sizes and only re-anchors its fast states, so the baseline
                // holds: taken again at one operating point, it would not be the
                // average over all of them the thresholds were learned against.)
                self.reacquire_after_s = self.invalid_until_s;
            }
        }
        if e.flags & FLAG_SKIPPED != 0 {
            return;
        }
        // A channel left out of the update (NaN or out of range) leaves the leak
        // states to drift on the others: no evidence until it has been back for a while.
        if e.residual.iter().any(|r| r.is_nan()) {
            self.invalid_until_s = self.invalid_until_s.max(recover);
        }
        if e.nis.is_finite() && e.nis > self.cfg.nis_gate {
            self.invalid_until_s = self.invalid_until_s.max(recover);
        }
        if e.nis.is_finite() {
            let nis = e.nis.min(1e6);
            // Averaged over 5 s: the burst of a leak's onset (under a second) does not
            // trip it, a sustained loss of tracking does.
            self.nis_avg = if self.nis_avg.is_finite() {
                self.nis_avg + (dt_s / NIS_RATIO_WINDOW_S).min(1.0) * (nis - self.nis_avg)
            } else {
                nis
            };
            if self.cfg.nis_ratio_gate > 0.0 && self.nis_avg > self.cfg.nis_ratio_gate * self.nis_healthy {
                self.invalid_until_s = self.invalid_until_s.max(e.t_s);
            }
        }
        // The command's reversal rate is tracked only for the command-rate gate (off by default).
        if self.cfg.max_command_hz > 0.0 && e.u_v.is_finite() {
            let side = if e.u_v > COMMAND_REVERSAL_BAND_V {
                1
            } else if e.u_v < -COMMAND_REVERSAL_BAND_V {
                -1
            } else {
                0
            };
            let mut impulse = 0.0;
            if side != 0 && side != self.command_side {
                if self.command_side != 0 {
                    impulse = 1.0;
                }
                self.command_side = side;
            }
            self.reversals_per_s += (impulse - self.reversals_per_s * dt_s) / COMMAND_RATE_WINDOW_S;
            if 0.5 * self.reversals_per_s > self.cfg.max_command_hz {
                self.invalid_until_s = self.invalid_until_s.max(e.t_s + 1.0);
                // The leak estimates wander while the model cannot follow the input and
                // relax slowly afterwards: take the baseline again once it is over.
                self.reacquire_after_s = self.invalid_until_s;
            }
        }
        if self.awaiting_convergence {
            if e.flags & (FLAG_CONVERGING | FLAG_RESET) != 0 {
                self.invalid_until_s = self.invalid_until_s.max(recover);
            } else {
                self.awaiting_convergence = false;
            }
        }
        self.update_flow_factor(e, dt_s);
        let raw = self.raw_sizes(e);
        if !raw.iter().all(|v| v.is_finite()) {
            return;
        }
        if !self.is_armed() {
            // (the figures are copied out: no clone of the commissioning, which holds a String, per sample)
            if let (Arming::Converging, Some(c)) = (self.arming, self.cfg.commissioning.as_ref()) {
                let (nis, offsets, spreads, crossings) =
                    (c.nis_mean, c.offsets_lpm, c.spreads_lpm, c.crossings_per_s);
                if e.flags & FLAG_CONVERGING == 0 {
                    self.nis_healthy = nis;
                    self.arm_with(offsets, spreads, crossings, e.t_s);
                }
                return;
            }
            // Learning takes every valid sample: the transients a healthy rig shows
            // (reference steps, excursions) are part of the spread the threshold
            // must stand above. Gaps, resets and skipped samples are left out.
            let blind = e.t_s < self.invalid_until_s;
            match self.arming {
                Arming::Converging if e.flags & FLAG_CONVERGING == 0 => {
                    self.arming = Arming::Settling(e.t_s);
                }
                Arming::Settling(t0) if e.t_s - t0 >= self.cfg.settle_s => {
                    self.arming = Arming::Learning(e.t_s);
                }
                Arming::Learning(_) if !blind => {
                    // (A warm-up of seconds cannot tell whether p1 − p2 keeps its sign: the
                    // internal leak's factors stay nominal without a commissioning. Taken
                    // from a 5 s warm-up they raised a false alarm in the 30-hour suite.)
                    self.record.push(e.t_s, dt_s, super::leak_sizes_lpm(e), e.nis);
                    if self.record.learned_s >= self.cfg.warmup_s {
                        let (offsets, spreads, crossings) = self.record.summary(self.internal_factors);
                        self.nis_healthy = self.record.nis_mean();
                        self.arm_with(offsets, spreads, crossings, e.t_s);
                    }
                }
                _ => {}
            }
            self.last_t_s = e.t_s;
            return;
        }
        self.last_t_s = e.t_s;
        // During an excursion to tank or supply pressure (where the healthy model is
        // worst and its errors move the leak estimates for a while) and a recovery
        // after it, the baseline holds and no evidence is gathered.
        let excursion = self.excursion(e);
        if excursion {
            self.blind_until_s = self.blind_until_s.max(e.t_s + self.cfg.excursion_recovery_s);
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
            for k in 0..3 {
                self.baseline_lpm[k] += a * (raw[k] - self.baseline_lpm[k]);
                if reacquiring {
                    // The reference of the slow-leak check moves with it: what the
                    // baseline takes up here is not a leak growing.
                    self.stats[k].mean = self.baseline_lpm[k];
                }
            }
        }
        // Rise of each hypothesis' size above its healthy baseline, and how badly the
        // hypothesis fits (the part of the flow mismatch it leaves unexplained).
        let rise: [f64; 3] = std::array::from_fn(|k| raw[k] - self.baseline_lpm[k]);
        let misfit = misfits_with(rise, self.internal_factors);
        let sigma_q = [
            e.sigma[7] / M3_S_PER_LPM,
            e.sigma[8] / M3_S_PER_LPM,
            e.sigma[9] / M3_S_PER_LPM,
        ];
        // σ of each hypothesis' size: the filter's marginal σ (correlations ignored)
        // combined with the spread the healthy estimate showed in the warm-up (the
        // filter alone is overconfident about model error).
        // (√(a² + b²) directly: these are L/min, far from where `hypot`'s
        // guard against overflow matters, and it costs five library calls a sample)
        let root_sum_square = |a: f64, b: f64| (a * a + b * b).sqrt();
        let sigma_filter = [
            root_sum_square(sigma_q[0], sigma_q[2]),
            root_sum_square(sigma_q[1], sigma_q[2]),
            0.5 * (sigma_q[0].powi(2) + sigma_q[1].powi(2) + 4.0 * sigma_q[2].powi(2)).sqrt(),
        ];
        let sigma_lpm: [f64; 3] =
            std::array::from_fn(|k| root_sum_square(sigma_filter[k], self.stats[k].std()));
        if self.active.is_none()
            && !blind
            && self.strong_since_s.is_none()
            && (0..3).all(|k| rise[k] < self.cfg.baseline_hold * self.thresholds_now()[k])
        {
            self.refine_thresholds(e.t_s, dt_s, rise);
        }
        // The smallest leak declared is a real flow of `min_size_lpm` (external) or
        // `min_internal_size_lpm` at the measured pressures: where a hypothesis'
        // drop is small (an internal leak while p1 ≈ p2), its size at p_s/2 is
        // poorly pinned down and must rise further.
        let thr: [f64; 3] = std::array::from_fn(|k| {
            let g = self.flow_factor[k];
            let m = self.min_size_of(k);
            let floor = if g.is_finite() {
                m / g.max(MIN_FLOW_FACTOR)
            } else {
                m
            };
            self.thresholds_now()[k].max(floor)
        });
        let score: [f64; 3] = std::array::from_fn(|k| (rise[k] - misfit[k]) / thr[k]);
        if !invalid {
            let change = self.offsets.on_rise(
                e.t_s,
                dt_s,
                rise,
                &e.offset_response_lpm_per_mpa,
                self.internal_factors,
                thr,
                &mut self.next_id,
            );
            if let Some(change) = change {
                self.sensor_event = Some(crate::offset::offset_event(change, e.t_s, "leak-size"));
            }
        }
        // Rises an offset on a transducer explains better than any leak are no leak evidence.
        let offset_like = misreading || self.offsets.vetoes();
        // What the baseline has absorbed since the warm-up, judged against `slow_leak_lpm`.
        let drift: [f64; 3] = std::array::from_fn(|k| self.baseline_lpm[k] - self.stats[k].mean);
        let drift_misfit = misfits_with(drift, self.internal_factors);
        let slow_lead = (0..3)
            .map(|k| (k, (drift[k] - drift_misfit[k]) / self.cfg.slow_leak_lpm.max(1e-9)))
            .fold((0, f64::NEG_INFINITY), |a, b| if b.1 > a.1 { b } else { a });
        if self.active.is_none() && self.cfg.baseline_tau_s > 0.0 && slow_lead.1 > 1.0 && !offset_like {
            match self.slow_since_s {
                Some((j, _)) if j == slow_lead.0 => {}
                _ => self.slow_since_s = Some((slow_lead.0, e.t_s)),
            }
        } else {
            self.slow_since_s = None;
        }
        let (lead, best) = (0..3)
            .map(|k| (k, score[k]))
            .fold((0, f64::NEG_INFINITY), |a, b| if b.1 > a.1 { b } else { a });
        let second = (0..3)
            .filter(|k| *k != lead)
            .map(|k| score[k])
            .fold(f64::NEG_INFINITY, f64::max);
        let physical = crate::leak_can_make_with(rise, self.thresholds_now(), self.internal_factors);
        let mut strong = None;
        for k in 0..3 {
            let thr = thr[k];
            if rise[k] < 0.25 * thr {
                self.last_low_s[k] = e.t_s;
                self.baseline_low_lpm[k] = self.baseline_lpm[k];
            }
            let evidence = !invalid
                && !offset_like
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
            if k == lead && rise[k] > thr && best > 0.5 && evidence && (clear || named) {
                if self.above_since_s[k].is_none() {
                    self.above_since_s[k] = Some(e.t_s);
                    self.above_evidence_s[k] = 0.0;
                } else {
                    self.above_evidence_s[k] += dt_s * ratio.min(self.cfg.confirm_gain_cap).max(1.0);
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
        match self.active {
            None => {
                // A leak is raised once one kind has explained the mismatch clearly for
                // `confirm_s` (`confirm_external_s` for an external leak; named if it has
                // led for `kind_confirm_s`), or once some
                // hypothesis' rise has been past `pending_factor` thresholds for
                // `confirm_s` (kind pending: the mismatch shows on both chambers).
                // (an external leak that alone explains the mismatch needs less: a
                // transient of the rod or spool does not make that pattern)
                let need_s = if lead < 2 {
                    self.cfg.confirm_external_s.min(self.cfg.confirm_s)
                } else {
                    self.cfg.confirm_s
                };
                let clear_ready = self.above_since_s[lead].filter(|_| self.above_evidence_s[lead] >= need_s);
                let strong_ready = strong.filter(|_| {
                    self.strong_since_s
                        .is_some_and(|t0| e.t_s - t0 >= self.cfg.confirm_s)
                });
                let ready = match (clear_ready, strong_ready) {
                    (Some(t0), _) => Some((lead, e.t_s - t0 >= self.cfg.kind_confirm_s)),
                    (None, Some((k, _))) => Some((k, false)),
                    (None, None) => None,
                };
                if let Some((lead, decided)) = ready {
                    // Measure the leak from the baseline before its onset: what the
                    // baseline absorbed while the leak rose is part of the leak.
                    self.baseline_lpm = self.baseline_low_lpm;
                    let rise: [f64; 3] = std::array::from_fn(|k| raw[k] - self.baseline_lpm[k]);
                    let id = self.next_id;
                    self.next_id += 1;
                    // The kind is named at once only if it has led long enough;
                    // otherwise the leak is raised with its kind pending.
                    let kind = EventKind::LEAKS[lead];
                    self.active = Some(Active {
                        kind: if decided { kind } else { EventKind::Leak },
                        id,
                        t_onset_s: self.last_low_s[lead],
                        last_size_lpm: rise[lead],
                        last_update_s: e.t_s,
                        below_since_s: None,
                        // (pending: since when the kind now leading has led, on average)
                        other_since_s: (!decided).then_some((lead, e.t_s)),
                    });
                    self.pending_rise_lpm = rise;
                    let mut ev = self.event(
                        kind,
                        Phase::Raised,
                        id,
                        e.t_s,
                        rise[lead],
                        sigma_lpm[lead],
                        best,
                        second,
                    );
                    if !decided {
                        ev.kind = EventKind::Leak;
                        ev.detail = format!("kind pending, {} leads: {}", kind.name(), ev.detail);
                    }
                    *out = Some(ev);
                } else if let (true, Some((j, t0))) = (
                    self.above_since_s[lead].is_none() && self.strong_since_s.is_none(),
                    self.slow_since_s,
                ) {
                    if e.t_s - t0 >= self.cfg.confirm_s {
                        // A leak that grew too slowly for the rise: measure it from the
                        // warm-up offset from now on (the baseline goes back there).
                        self.slow_since_s = None;
                        for k in 0..3 {
                            self.baseline_lpm[k] = self.stats[k].mean;
                            self.baseline_low_lpm[k] = self.stats[k].mean;
                        }
                        let size = raw[j] - self.stats[j].mean;
                        let id = self.next_id;
                        self.next_id += 1;
                        let kind = EventKind::LEAKS[j];
                        self.active = Some(Active {
                            kind,
                            id,
                            t_onset_s: f64::NAN,
                            last_size_lpm: size,
                            last_update_s: e.t_s,
                            below_since_s: None,
                            other_since_s: None,
                        });
                        let mut ev = self.event(
                            kind,
                            Phase::Raised,
                            id,
                            e.t_s,
                            size,
                            sigma_lpm[j],
                            slow_lead.1,
                            0.0,
                        );
                        ev.detail = format!(
                            "slowly growing: the healthy baseline drifted {size:.3} L/min (at p_s/2) since the warm-up; {}",
                            ev.detail
                        );
                        *out = Some(ev);
                    }
                }
            }
            Some(mut a) if a.kind == EventKind::Leak => {
                // Kind pending: name it once one kind has led, clearly (it explains the
                // mismatch) and with a rise past half its threshold, for `kind_confirm_s`
                // (the same event id, raised again with its kind).
                if !invalid {
                    let w = (dt_s / KIND_AVERAGE_S).min(1.0);
                    for k in 0..3 {
                        self.pending_rise_lpm[k] += w * (rise[k] - self.pending_rise_lpm[k]);
                    }
                }
                let avg = self.pending_rise_lpm;
                let avg_misfit = misfits_with(avg, self.internal_factors);
                let lead = (0..3)
                    .map(|k| (k, (avg[k] - avg_misfit[k]) / self.thresholds_now()[k]))
                    .fold((0, f64::NEG_INFINITY), |a, b| if b.1 > a.1 { b } else { a })
                    .0;
                let leads = !invalid
                    && avg[lead] > 0.5 * self.thresholds_now()[lead]
                    && avg_misfit[lead] <= self.cfg.isolation_max_misfit * avg[lead];
                a.other_since_s = match a.other_since_s {
                    Some((j, t0)) if leads && j == lead => Some((j, t0)),
                    _ if leads => Some((lead, e.t_s)),
                    _ => None,
                };
                if let Some((_, t0)) = a.other_since_s {
                    if e.t_s - t0 >= self.cfg.kind_confirm_s {
                        a.other_since_s = None;
                        a.kind = EventKind::LEAKS[lead];
                        a.last_size_lpm = rise[lead];
                        a.last_update_s = e.t_s;
                        a.below_since_s = None;
                        self.active = Some(a);
                        let mut ev = self.event(
                            a.kind,
                            Phase::Raised,
                            a.id,
                            e.t_s,
                            rise[lead],
                            sigma_lpm[lead],
                            best,
                            second,
                        );
                        ev.detail = format!("kind decided after {:.1} s: {}", e.t_s - t0, ev.detail);
                        *out = Some(ev);
                        return;
                    }
                }
                let low = (0..3).all(|k| rise[k] < 0.5 * self.thresholds_now()[k]);
                if a.low_for(low && !invalid, e.t_s, self.cfg.clear_s) {
                    self.active = None;
                    let mut ev = self.event(
                        EventKind::LEAKS[lead],
                        Phase::Cleared,
                        a.id,
                        e.t_s,
                        rise[lead],
                        sigma_lpm[lead],
                        0.0,
                        0.0,
                    );
                    ev.kind = EventKind::Leak;
                    *out = Some(ev);
                    return;
                }
                self.active = Some(a);
            }
            Some(mut a) => {
                let mut k = EventKind::LEAKS.iter().position(|x| *x == a.kind).unwrap_or(0);
                // Re-isolation: when another kind explains the data clearly better for
                // `reisolate_s`, a new event of that kind is raised (it replaces this one).
                if lead != k
                    && best > 1.0
                    && best - score[k] > 1.0
                    && misfit[lead] <= self.cfg.isolation_max_misfit * rise[lead]
                {
                    match a.other_since_s {
                        Some((j, t0)) if j == lead => {
                            if e.t_s - t0 >= self.cfg.reisolate_s {
                                let from = (a.kind, a.id);
                                let id = self.next_id;
                                self.next_id += 1;
                                a.kind = EventKind::LEAKS[lead];
                                a.id = id;
                                a.other_since_s = None;
                                a.below_since_s = None;
                                a.last_size_lpm = rise[lead];
                                a.last_update_s = e.t_s;
                                k = lead;
                                self.active = Some(a);
                                let mut ev = self.event(
                                    a.kind,
                                    Phase::Raised,
                                    a.id,
                                    e.t_s,
                                    rise[k],
                                    sigma_lpm[k],
                                    best,
                                    score[from.0 as usize % 3].min(best),
                                );
                                ev.detail = format!(
                                    "re-isolated: replaces event {} ({}); {}",
                                    from.1,
                                    from.0.name(),
                                    ev.detail
                                );
                                *out = Some(ev);
                                return;
                            }
                        }
                        _ => a.other_since_s = Some((lead, e.t_s)),
                    }
                } else {
                    a.other_since_s = None;
                }
                let size = rise[k];
                if a.low_for(
                    size < 0.5 * self.thresholds_now()[k] && !invalid,
                    e.t_s,
                    self.cfg.clear_s,
                ) {
                    self.active = None;
                    *out =
                        Some(self.event(a.kind, Phase::Cleared, a.id, e.t_s, size, sigma_lpm[k], 0.0, 0.0));
                    return;
                }
                if !invalid
                    && e.t_s - a.last_update_s >= self.cfg.update_interval_s
                    && (size - a.last_size_lpm).abs()
                        > self.cfg.update_relative * a.last_size_lpm.abs().max(1e-3)
                {
                    a.last_size_lpm = size;
                    a.last_update_s = e.t_s;
                    let others = (0..3)
                        .filter(|j| *j != k)
                        .map(|j| score[j])
                        .fold(f64::NEG_INFINITY, f64::max);
                    let mut ev = self.event(
                        a.kind,
                        Phase::Updated,
                        a.id,
                        e.t_s,
                        size,
                        sigma_lpm[k],
                        score[k],
                        others,
                    );
                    ev.t_onset_s = a.t_onset_s;
                    *out = Some(ev);
                }
                self.active = Some(a);
            }
        }
    }
}
