//! The leak-size detector's decisions on the evidence of an armed estimate:
//! a leak raised (its kind named or pending), a pending kind named, a named
//! leak followed (re-isolated, updated, cleared).

use super::evidence::{Evidence, Sight};
use super::LeakSizeDetector;
use crate::track::Active;
use crate::{misfits_with, EventKind, LeakEvent, Phase, KIND_AVERAGE_S};
use filter::Estimate;

impl LeakSizeDetector {
    /// No leak is active: raises one once a kind has explained the mismatch
    /// clearly long enough, a rise has stayed strong, or the baseline has
    /// drifted as a slowly growing leak.
    pub(super) fn raise(&mut self, e: &Estimate, raw: &[f64; 3], ev: &Evidence, out: &mut Option<LeakEvent>) {
        let Evidence {
            sigma_lpm,
            lead,
            best,
            second,
            strong,
            slow_lead,
            ..
        } = *ev;
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
            if let Some(rival) = self.offsets.rival_misreading() {
                ev.detail += &format!("; {rival} would explain the rises as well: check that transducer");
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

    /// A leak of pending kind: names it once one kind has led clearly for
    /// `kind_confirm_s`, or clears it. While a transducer is named reading off
    /// (`sight.misreading`) no kind is named: its offset is in the rises.
    pub(super) fn name_pending(
        &mut self,
        mut a: Active,
        e: &Estimate,
        dt_s: f64,
        sight: &Sight,
        ev: &Evidence,
        out: &mut Option<LeakEvent>,
    ) {
        let invalid = sight.invalid;
        let Evidence {
            rise,
            sigma_lpm,
            best,
            second,
            ..
        } = *ev;
        // Kind pending: name it once one kind has led, clearly (it explains the
        // mismatch) and with a rise past half its threshold, for `kind_confirm_s`
        // (the same event id, raised again with its kind).
        if !invalid && !sight.misreading {
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
            && !sight.misreading
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

    /// A named leak: re-isolates it when another kind explains the data
    /// clearly better, clears it when its rise has stayed low, or updates its size.
    pub(super) fn follow_named(
        &mut self,
        mut a: Active,
        e: &Estimate,
        invalid: bool,
        ev: &Evidence,
        out: &mut Option<LeakEvent>,
    ) {
        let Evidence {
            rise,
            misfit,
            sigma_lpm,
            score,
            lead,
            best,
            ..
        } = *ev;
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
            size < 0.5 * self.naming_thresholds_now()[k] && !invalid,
            e.t_s,
            self.cfg.clear_s,
        ) {
            self.active = None;
            *out = Some(self.event(a.kind, Phase::Cleared, a.id, e.t_s, size, sigma_lpm[k], 0.0, 0.0));
            return;
        }
        if !invalid
            && e.t_s - a.last_update_s >= self.cfg.update_interval_s
            && (size - a.last_size_lpm).abs() > self.cfg.update_relative * a.last_size_lpm.abs().max(1e-3)
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
