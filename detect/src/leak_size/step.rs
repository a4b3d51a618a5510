//! The leak-size detector's step on each estimate: the validity gate, arming,
//! then the baseline and the evidence (`evidence.rs`) and the decision
//! (`decide.rs`: the alarm, kind pending or named, re-isolation, updates, clearing).

use super::{BlindCause, LeakSizeDetector};
use crate::track::Arming;
use crate::{EventKind, LeakEvent, COMMAND_RATE_WINDOW_S, COMMAND_REVERSAL_BAND_V, NIS_RATIO_WINDOW_S};
use filter::{Estimate, FLAG_CONVERGING, FLAG_OIL_PAST_RANGE, FLAG_REANCHORED, FLAG_RESET, FLAG_SKIPPED};

impl LeakSizeDetector {
    /// The thresholds in force, L/min at p_s/2: the commissioning's (or the
    /// refined ones) widened by what the oil's temperature leaves uncertain.
    pub(super) fn thresholds_now(&self) -> [f64; 3] {
        std::array::from_fn(|k| self.threshold_lpm[k] + self.oil_band_lpm[k])
    }

    /// `thresholds` (L/min at p_s/2) widened by what the transducers' delay
    /// leaves uncertain now: the level a rise must pass to raise or name a
    /// leak. Only there: the tolerance of the pattern test, the baseline's
    /// hold and the clearing keep [`Self::thresholds_now`] (a drifting
    /// transducer's pattern stays one no leak can make).
    pub(super) fn past_the_delay(&self, thresholds: [f64; 3]) -> [f64; 3] {
        std::array::from_fn(|k| thresholds[k] + self.delay_band_lpm[k])
    }

    /// The thresholds a named leak must pass in force, L/min at p_s/2: the
    /// naming test's ([`Commissioning::clear_spreads_lpm`](crate::Commissioning::clear_spreads_lpm)),
    /// widened like [`Self::thresholds_now`].
    pub(super) fn naming_thresholds_now(&self) -> [f64; 3] {
        std::array::from_fn(|k| self.naming_threshold_lpm[k] + self.oil_band_lpm[k])
    }

    /// The thresholds the offset watch judges the rises against, L/min at
    /// p_s/2: the commissioning's (or the refined ones) widened by the oil's
    /// band as it was inside the operating range (`watch_band_lpm`).
    pub(super) fn watch_thresholds_now(&self) -> [f64; 3] {
        std::array::from_fn(|k| self.threshold_lpm[k] + self.watch_band_lpm[k])
    }

    /// Takes the laminar flows' uncertainty of estimate `e` into
    /// [`Self::thresholds_now`]: the model's null leakage (its band) and the
    /// healthy offsets, each as uncertain as the laminar factor. The offset
    /// watch's band follows it only while θ reads the oil inside its range.
    /// And the transducers' delay's: its uncertainty times the sizes' response
    /// to it beyond what the commissioning saw ([`Self::past_the_delay`]).
    fn widen_for_the_model(&mut self, e: &Estimate) {
        self.oil_band_lpm = crate::oil_band_lpm(
            e.laminar_factor_sigma,
            e.null_leakage_band_lpm,
            self.offsets_lpm(),
        );
        if e.flags & FLAG_OIL_PAST_RANGE == 0 {
            self.watch_band_lpm = self.oil_band_lpm;
        }
        if self.delay_uncertainty_ms > 0.0 {
            self.delay_band_lpm = crate::delay_band_lpm(
                self.delay_uncertainty_ms,
                e.delay_response_lpm_per_ms,
                self.internal_factors,
                self.delay_response_reach_lpm_per_ms,
            );
        }
    }

    /// Reads one estimate; pushes any event into `out` (at most one per call).
    pub fn on_estimate(&mut self, e: &Estimate, out: &mut Option<LeakEvent>) {
        if e.n_states < 10 {
            return;
        }
        self.widen_for_the_model(e);
        let dt_s = if self.last_t_s.is_finite() {
            (e.t_s - self.last_t_s).clamp(0.0, 1.0)
        } else {
            0.0
        };
        if !self.gate(e, dt_s) {
            return;
        }
        self.update_flow_factor(e, dt_s);
        let raw = self.raw_sizes(e);
        if !raw.iter().all(|v| v.is_finite()) {
            return;
        }
        if !self.is_armed() {
            self.arm_on(e, dt_s);
            return;
        }
        self.last_t_s = e.t_s;
        let sight = self.follow_baseline(e, dt_s, &raw);
        let evidence = self.weigh_evidence(e, dt_s, &raw, &sight);
        if self.withdraw_for_misreading(e, &evidence, out) {
            return;
        }
        match self.active {
            None => self.raise(e, &raw, &evidence, out),
            Some(a) if a.kind == EventKind::Leak => self.name_pending(a, e, dt_s, &sight, &evidence, out),
            Some(a) => self.follow_named(a, e, sight.invalid, &evidence, out),
        }
    }

    /// Withdraws the leak alarm standing when a transducer is named as reading
    /// off, if it was raised after that transducer began to: its rises were
    /// the misreading's. The alarm is cleared with a detail naming the
    /// transducer; a leak raised before the misreading began stands. True
    /// when an alarm was withdrawn (its event is in `out`).
    fn withdraw_for_misreading(
        &mut self,
        e: &Estimate,
        ev: &super::evidence::Evidence,
        out: &mut Option<LeakEvent>,
    ) -> bool {
        // (a transducer named at this sample: its `sensor-offset` event is waiting)
        let just_named = self
            .sensor_event
            .as_ref()
            .is_some_and(|s| s.phase == crate::Phase::Raised);
        if !just_named {
            return false;
        }
        let (Some(a), Some(s)) = (self.active, self.offsets.standing()) else {
            return false;
        };
        if a.t_onset_s < s.since_s {
            return false;
        }
        self.active = None;
        let k = EventKind::LEAKS
            .iter()
            .position(|x| *x == a.kind)
            .unwrap_or(ev.lead);
        let mut cleared = self.event(
            a.kind,
            crate::Phase::Cleared,
            a.id,
            e.t_s,
            ev.rise[k],
            ev.sigma_lpm[k],
            0.0,
            0.0,
        );
        cleared.detail = format!(
            "withdrawn: {} has read off since {:.1} s (event {}); the rises since {:.1} s were its, not a leak's",
            crate::offset::OFFSET_CHANNEL_NAMES[s.channel],
            s.since_s,
            s.event_id,
            a.t_onset_s
        );
        *out = Some(cleared);
        true
    }

    /// Withdraws the leak alarm standing when a transducer is named stuck,
    /// dead or saturated at `t_s` (s), if it opened after the channel's bad
    /// readings began at `since_s` (s): its rises were the frozen or missing
    /// channel's. `fault` says which (e.g. "x sensor-stuck (event 7)").
    /// Returns the alarm's clearing; a leak that opened before stands.
    pub fn withdraw_for_fault(&mut self, t_s: f64, since_s: f64, fault: &str) -> Option<LeakEvent> {
        let a = self.active.filter(|a| a.t_onset_s >= since_s)?;
        self.active = None;
        let mut cleared = self.event(
            a.kind,
            crate::Phase::Cleared,
            a.id,
            t_s,
            a.last_size_lpm,
            0.0,
            0.0,
            0.0,
        );
        cleared.detail = format!(
            "withdrawn: {fault} since {since_s:.1} s; the rises since {:.1} s were its, not a leak's",
            a.t_onset_s
        );
        Some(cleared)
    }

    /// The validity gate: a gap the filter could not bridge, a skipped sample, a
    /// reset, a channel left out, a NIS burst or a command too fast for the
    /// model make the evidence invalid for a while. False for a skipped sample
    /// (nothing more is read from it).
    fn gate(&mut self, e: &Estimate, dt_s: f64) -> bool {
        // Validity gate: a gap the filter could not bridge (it re-anchored), a skipped
        // sample or a reset blinds the detector for `recovery_s`; so does a filter
        // whose innovations are far beyond its own covariance (not tracking). The
        // baseline holds while blind. A gap the filter bridged by prediction (a few
        // samples; `FLAG_AFTER_GAP` alone) or estimates lost on their way here leave
        // the filter tracking: evidence goes on (the NIS gate still watches).
        let recover = e.t_s + self.cfg.recovery_s;
        if e.flags & (FLAG_SKIPPED | FLAG_REANCHORED | FLAG_RESET) != 0 {
            let cause = if e.flags & (FLAG_SKIPPED | FLAG_RESET) != 0 {
                BlindCause::Restart
            } else {
                BlindCause::Reanchored
            };
            self.invalid_until(cause, recover);
            if e.flags & FLAG_RESET != 0 {
                // The filter started again from its initial leak sizes: the baseline
                // is taken again once it has settled. (After a gap the filter keeps
                // its leak sizes and only re-anchors its fast states, so the baseline
                // holds: taken again at one operating point, it would not be the
                // average over all of them the thresholds were learned against.)
                self.reacquire_after_s = self.invalid_until_s;
                self.blind_causes
                    .hold(BlindCause::Restart, self.reacquire_after_s + crate::REACQUIRE_S);
            }
        }
        if e.flags & FLAG_SKIPPED != 0 {
            return false;
        }
        // A channel left out of the update (NaN or out of range) leaves the leak
        // states to drift on the others: no evidence until it has been back for a while.
        if e.residual.iter().any(|r| r.is_nan()) {
            self.invalid_until(BlindCause::ChannelLeftOut, recover);
        }
        if e.nis.is_finite() && e.nis > self.cfg.nis_gate {
            self.invalid_until(BlindCause::Nis, recover);
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
                self.invalid_until(BlindCause::Nis, e.t_s);
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
                self.invalid_until(BlindCause::CommandRate, e.t_s + 1.0);
                // The leak estimates wander while the model cannot follow the input and
                // relax slowly afterwards: take the baseline again once it is over.
                self.reacquire_after_s = self.invalid_until_s;
                self.blind_causes.hold(
                    BlindCause::CommandRate,
                    self.reacquire_after_s + crate::REACQUIRE_S,
                );
            }
        }
        if self.awaiting_convergence {
            if e.flags & (FLAG_CONVERGING | FLAG_RESET) != 0 {
                self.invalid_until(BlindCause::Restart, recover);
            } else {
                self.awaiting_convergence = false;
            }
        }
        true
    }

    /// Arming: a commissioning's healthy state once the filter has converged,
    /// or the healthy state learned over the warm-up.
    fn arm_on(&mut self, e: &Estimate, dt_s: f64) {
        // (the figures are copied out: no clone of the commissioning, which holds a String, per sample)
        if let (Arming::Converging, Some(c)) = (self.arming, self.cfg.commissioning.as_ref()) {
            let (nis, offsets, spreads, naming, crossings) = (
                c.nis_mean,
                c.offsets_lpm,
                c.spreads_lpm,
                c.naming_spreads_lpm(),
                c.crossings_per_s,
            );
            if e.flags & FLAG_CONVERGING == 0 {
                self.nis_healthy = nis;
                self.arm_with(offsets, spreads, naming, crossings, e.t_s);
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
                    self.arm_with(offsets, spreads, spreads, crossings, e.t_s);
                }
            }
            _ => {}
        }
        self.last_t_s = e.t_s;
    }
}
