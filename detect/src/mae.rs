//! The thesis' detector (docs/model.md#the-baseline-detector), kept as a baseline:
//! moving averages of the pressure residuals against thresholds learned in a
//! warm-up. It cannot size a leak.

use crate::track::{arm_step, Active, Arming, Stats};
use crate::{ClassifierConfig, EventKind, LeakEvent, Phase};
use filter::{Estimate, FLAG_SKIPPED};

/// The thesis' detector: thresholds on the MAE of the pressure residuals.
#[derive(Debug, Clone)]
pub struct MaeDetector {
    cfg: ClassifierConfig,
    arming: Arming,
    stats: [Stats; 2],
    threshold_pa: [f64; 2],
    pattern_since: Option<(EventKind, f64)>,
    active: Option<Active>,
    next_id: u64,
}

impl MaeDetector {
    /// A detector with settings `cfg`.
    pub fn new(cfg: ClassifierConfig) -> Self {
        MaeDetector {
            cfg,
            arming: Arming::Converging,
            stats: [Stats::default(); 2],
            threshold_pa: [f64::NAN; 2],
            pattern_since: None,
            active: None,
            next_id: 1,
        }
    }

    /// Whether the thresholds have been learned.
    pub fn is_armed(&self) -> bool {
        self.arming == Arming::Armed
    }

    /// The learned MAE thresholds of p1 and p2, Pa.
    pub fn thresholds_pa(&self) -> [f64; 2] {
        self.threshold_pa
    }

    /// Restarts the warm-up (after a filter reset).
    pub fn restart(&mut self) {
        let cfg = self.cfg.clone();
        let id = self.next_id;
        *self = MaeDetector::new(cfg);
        self.next_id = id;
    }

    /// Reads one estimate; pushes any event into `out`.
    pub fn on_estimate(&mut self, e: &Estimate, out: &mut Option<LeakEvent>) {
        if e.flags & FLAG_SKIPPED != 0 || !e.mae_pa.iter().all(|m| m.is_finite()) {
            return;
        }
        match arm_step(&mut self.arming, &self.cfg, e) {
            Some(false) => {
                self.stats[0].push(e.mae_pa[0]);
                self.stats[1].push(e.mae_pa[1]);
                return;
            }
            Some(true) => {
                for k in 0..2 {
                    self.threshold_pa[k] = self.cfg.mae_margin * self.stats[k].max;
                }
                return;
            }
            None if !self.is_armed() => return,
            None => {}
        }
        let high = [
            e.mae_pa[0] > self.threshold_pa[0],
            e.mae_pa[1] > self.threshold_pa[1],
        ];
        let kind = match high {
            [true, false] => Some(EventKind::Ext1),
            [false, true] => Some(EventKind::Ext2),
            [true, true] => Some(EventKind::Int),
            [false, false] => None,
        };
        match (kind, self.pattern_since) {
            (Some(k), Some((pk, _))) if k == pk => {}
            (Some(k), _) => self.pattern_since = Some((k, e.t_s)),
            (None, _) => self.pattern_since = None,
        }
        let ratio = [
            e.mae_pa[0] / self.threshold_pa[0],
            e.mae_pa[1] / self.threshold_pa[1],
        ];
        match self.active {
            None => {
                if let Some((k, t0)) = self.pattern_since {
                    if e.t_s - t0 >= self.cfg.mae_confirm_s {
                        let id = self.next_id;
                        self.next_id += 1;
                        // The MAE window delays the rise: place the onset half a window back is not
                        // possible without the window; report the start of the pattern.
                        self.active = Some(Active {
                            kind: k,
                            id,
                            t_onset_s: t0,
                            last_size_lpm: f64::NAN,
                            last_update_s: e.t_s,
                            below_since_s: None,
                            other_since_s: None,
                        });
                        let margin = (ratio[0].max(ratio[1]) - 1.0).max(0.0);
                        let mut ev = LeakEvent::plain(k, Phase::Raised, "thesis-mae", id, e.t_s, t0);
                        ev.confidence = 1.0 - (-4.0 * margin).exp();
                        ev.detail = format!(
                            "thesis baseline (not a leakwatch decision): MAE p1 {:.0} Pa, p2 {:.0} Pa",
                            e.mae_pa[0], e.mae_pa[1]
                        );
                        *out = Some(ev);
                    }
                }
            }
            Some(mut a) => {
                if a.low_for(kind.is_none(), e.t_s, self.cfg.clear_s) {
                    self.active = None;
                    let mut ev =
                        LeakEvent::plain(a.kind, Phase::Cleared, "thesis-mae", a.id, e.t_s, a.t_onset_s);
                    ev.confidence = 0.0;
                    *out = Some(ev);
                    return;
                }
                self.active = Some(a);
            }
        }
    }
}
