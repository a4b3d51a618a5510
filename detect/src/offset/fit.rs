//! The least-squares fits of the offset watch: a misreading of p1, p2 or x
//! against a steady leak, over the chamber flows' rises (w1, w2).

use super::{
    MOST_DRIFT_MPA_PER_S, POSITION_FIT_RATIO, POSITION_MOST_OFFSET_MM, REVERSE_INTERNAL_LEAST_FACTOR,
    SPAN_FIT_RATIO, SWING_FIT_RATIO,
};

/// The misreadings fitted. Per pressure channel c (0 p1, 1 p2), hypothesis
/// h = 2·form + c: form 0, an offset (the filter's response δ_c as given);
/// form 1, its swing about its baseline; form 2, a span error (the filter's
/// response σ_c to one: the offset a gain error makes moves with the
/// pressure); form 3, its swing. Then x (channel 2): h = 8, an offset as
/// given; h = 9, its swing. Each takes one response.
pub(crate) const HYPOTHESES: usize = 10;

/// The first drifting offset: h = 10 + c is an offset on p_c that grows at
/// a steady rate (the response as given, times b + ḃ·τ).
pub(crate) const FIRST_DRIFT_HYPOTHESIS: usize = HYPOTHESES;

/// Every hypothesis fitted: those of one response ([`HYPOTHESES`]) and the
/// two drifting offsets.
pub(crate) const ALL_HYPOTHESES: usize = HYPOTHESES + 2;

/// The first hypothesis on x.
pub(crate) const FIRST_POSITION_HYPOTHESIS: usize = 8;

/// The channel of x (p1 is 0, p2 1), an index into
/// [`super::OFFSET_CHANNEL_NAMES`].
pub(crate) const POSITION_CHANNEL: usize = 2;

/// The channel of hypothesis `h` (0 p1, 1 p2, 2 x).
pub(crate) const fn channel_of(h: usize) -> usize {
    if h < FIRST_POSITION_HYPOTHESIS {
        h % 2
    } else if h < FIRST_DRIFT_HYPOTHESIS {
        POSITION_CHANNEL
    } else {
        h - FIRST_DRIFT_HYPOTHESIS
    }
}

/// Whether hypothesis `h` is a span error (its coefficient a gain error, 1)
/// rather than an offset (MPa, or mm on x).
pub(crate) const fn is_span(h: usize) -> bool {
    h >= 4 && h < FIRST_POSITION_HYPOTHESIS
}

/// Whether hypothesis `h` is an offset on x (its coefficient in mm).
pub(crate) const fn is_position(h: usize) -> bool {
    h >= FIRST_POSITION_HYPOTHESIS && h < FIRST_DRIFT_HYPOTHESIS
}

/// Whether hypothesis `h` is a drifting offset on p1 or p2.
pub(crate) const fn is_drift(h: usize) -> bool {
    h >= FIRST_DRIFT_HYPOTHESIS
}

/// Whether hypothesis `h` is a swing about its baseline (fitted in place of
/// hypothesis [`as_given`]`(h)`, its response as given).
const fn is_swing(h: usize) -> bool {
    if h < FIRST_POSITION_HYPOTHESIS {
        (h / 2) % 2 == 1
    } else {
        h == FIRST_POSITION_HYPOTHESIS + 1
    }
}

/// The sums of a drifting offset's fit beyond its response's
/// ([`Fit::response_rise`], [`Fit::response_energy`]), in the age τ ≤ 0 of
/// each sample (s before the last one).
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct DriftSums {
    /// Σw·τ·δ·rise, (L/min)²/MPa·s².
    pub(crate) age_response_rise: f64,
    /// Σw·τ·|δ|², (L/min/MPa)²·s².
    pub(crate) age_response_energy: f64,
    /// Σw·τ²·|δ|², (L/min/MPa)²·s³.
    pub(crate) age2_response_energy: f64,
}

/// The hypothesis whose response as given swing hypothesis `h` is taken about.
const fn as_given(h: usize) -> usize {
    if h < FIRST_POSITION_HYPOTHESIS {
        h - 2
    } else {
        h - 1
    }
}

/// The hypotheses that take a response as given, in the order of the
/// filter's responses: the offsets on p1 and p2, the span errors on p1 and
/// p2, the offset on x.
pub(crate) const AS_GIVEN: [usize; 5] = [0, 1, 4, 5, FIRST_POSITION_HYPOTHESIS];

/// The swing hypothesis taken about hypothesis `h` (one of [`AS_GIVEN`]):
/// the inverse of [`as_given`].
pub(crate) const fn swing_of(h: usize) -> usize {
    if h < FIRST_POSITION_HYPOTHESIS {
        h + 2
    } else {
        h + 1
    }
}

/// Exponentially weighted sums of both fits over the chamber flows' rises
/// (w1, w2) (weights in s).
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Fit {
    /// Σw, s.
    pub(crate) w: f64,
    /// Σw·|rise|², (L/min)²·s.
    pub(crate) energy: f64,
    /// Σw·δ_h·rise per hypothesis ([`HYPOTHESES`]), (L/min)²/MPa·s for an
    /// offset, (L/min)²·s per unit error for a span, (L/min)²/mm·s on x.
    pub(crate) response_rise: [f64; HYPOTHESES],
    /// Σw·|δ_h|² per hypothesis, (L/min/MPa)²·s for an offset, (L/min)²·s per
    /// unit error squared for a span, (L/min/mm)²·s on x.
    pub(crate) response_energy: [f64; HYPOTHESES],
    /// Σw·rise, L/min·s.
    pub(crate) rise: [f64; 2],
    /// The drifting offsets' further sums, on p1 and p2.
    pub(crate) drift: [DriftSums; 2],
    /// Σw·τ (s²), Σw·τ² (s³) and Σw·τ·rise (L/min·s²) over the samples'
    /// ages τ ≤ 0: a growing leak's fit.
    pub(crate) age: (f64, f64, [f64; 2]),
    /// The energy each hypothesis' misreading explains ([`ALL_HYPOTHESES`]),
    /// (L/min)²·s, as of the last sample added: every reader of a sample
    /// asks for it, so it is fitted once.
    explained: [f64; ALL_HYPOTHESES],
}

/// The misreading that explains most ([`Fit::best_offset`]) and what the
/// leaks leave beside it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct BestOffset {
    /// Its hypothesis.
    pub(crate) h: usize,
    /// The energy its fit leaves unexplained, (L/min)²·s.
    pub(crate) left: f64,
    /// The energy the best leak's fit leaves, (L/min)²·s: a growing leak's
    /// for a drifting offset ([`is_drift`]), a steady leak's for the others.
    pub(crate) leak_left: f64,
}

impl Fit {
    /// Adds a sample of weight `dt_s` after decaying the past by `keep` (1).
    pub(crate) fn add(&mut self, keep: f64, dt_s: f64, rise: [f64; 2], response: &[[f64; 2]; HYPOTHESES]) {
        // (every past sample ages by dt_s; the new one has age 0)
        for (c, d) in self.drift.iter_mut().enumerate() {
            let (rr, re) = (self.response_rise[c], self.response_energy[c]);
            d.age2_response_energy =
                keep * (d.age2_response_energy - 2.0 * dt_s * d.age_response_energy + dt_s * dt_s * re);
            d.age_response_energy = keep * (d.age_response_energy - dt_s * re);
            d.age_response_rise = keep * (d.age_response_rise - dt_s * rr);
        }
        let (t1, t2, tr) = &mut self.age;
        *t2 = keep * (*t2 - 2.0 * dt_s * *t1 + dt_s * dt_s * self.w);
        *t1 = keep * (*t1 - dt_s * self.w);
        for k in 0..2 {
            tr[k] = keep * (tr[k] - dt_s * self.rise[k]);
        }
        self.w = keep * self.w + dt_s;
        self.energy = keep * self.energy + dt_s * (rise[0] * rise[0] + rise[1] * rise[1]);
        for c in 0..HYPOTHESES {
            let d = &response[c];
            let dr = d[0] * rise[0] + d[1] * rise[1];
            let dd = d[0] * d[0] + d[1] * d[1];
            self.response_rise[c] = keep * self.response_rise[c] + dt_s * dr;
            self.response_energy[c] = keep * self.response_energy[c] + dt_s * dd;
        }
        for k in 0..2 {
            self.rise[k] = keep * self.rise[k] + dt_s * rise[k];
        }
        self.explained = std::array::from_fn(|h| self.fit_explained(h));
    }

    /// The coefficient of hypothesis `c` that fits best: an offset in MPa (in
    /// mm on x, [`is_position`]; a drifting offset's at the last sample,
    /// [`is_drift`]), a span error in 1 ([`is_span`]); 0 without a response.
    pub(crate) fn coefficient(&self, c: usize) -> f64 {
        if is_drift(c) {
            self.drift_fit(c - FIRST_DRIFT_HYPOTHESIS).0
        } else if self.response_energy[c] > 0.0 {
            self.response_rise[c] / self.response_energy[c]
        } else {
            0.0
        }
    }

    /// The energy the misreading of hypothesis `c` explains, (L/min)²·s.
    pub(crate) fn explained_by_offset(&self, c: usize) -> f64 {
        self.explained[c]
    }

    /// [`Self::explained_by_offset`] fitted from the sums.
    fn fit_explained(&self, c: usize) -> f64 {
        if is_drift(c) {
            self.drift_fit(c - FIRST_DRIFT_HYPOTHESIS).1
        } else {
            self.coefficient(c) * self.response_rise[c]
        }
    }

    /// The rate of hypothesis `h`'s misreading, MPa/s: a drifting offset's
    /// ([`is_drift`]); 0 for the others, which stand still.
    pub(crate) fn drift_rate_mpa_per_s(&self, h: usize) -> f64 {
        if is_drift(h) {
            self.drift_fit(h - FIRST_DRIFT_HYPOTHESIS).2
        } else {
            0.0
        }
    }

    /// The drifting offset on p_c (c 0 or 1) that fits best: b + ḃ·τ at the
    /// sample of age τ, ḃ at most [`MOST_DRIFT_MPA_PER_S`] either way. Its
    /// offset at the last sample b (MPa), the energy it explains
    /// ((L/min)²·s) and its rate ḃ (MPa/s).
    fn drift_fit(&self, c: usize) -> (f64, f64, f64) {
        let (r0, e0) = (self.response_rise[c], self.response_energy[c]);
        let d = &self.drift[c];
        let (r1, e1, e2) = (d.age_response_rise, d.age_response_energy, d.age2_response_energy);
        if e0 <= 0.0 {
            return (0.0, 0.0, 0.0);
        }
        let det = e0 * e2 - e1 * e1;
        let free_rate = if det > 1e-9 * e0 * e2 {
            (e0 * r1 - e1 * r0) / det
        } else {
            0.0
        };
        let rate = free_rate.clamp(-MOST_DRIFT_MPA_PER_S, MOST_DRIFT_MPA_PER_S);
        let b = (r0 - rate * e1) / e0;
        // energy − what the fit leaves: 2(b·r0 + ḃ·r1) − (b²e0 + 2bḃe1 + ḃ²e2)
        let explained = 2.0 * (b * r0 + rate * r1) - (b * b * e0 + 2.0 * b * rate * e1 + rate * rate * e2);
        (b, explained, rate)
    }

    /// The energy the best steady leak leaves unexplained, (L/min)²·s: a leak
    /// of kind k moves (w1, w2) along `directions[k]` (unit vectors).
    pub(crate) fn unexplained_by_leak(&self, directions: &[[f64; 2]; 3]) -> f64 {
        let best = directions
            .iter()
            .map(|u| (u[0] * self.rise[0] + u[1] * self.rise[1]).powi(2) / self.w.max(1e-12))
            .fold(0.0, f64::max);
        self.energy - best
    }

    /// The offset hypothesis that explains most, and what its fit leaves,
    /// (L/min)²·s. A channel's swing about its baseline counts only where it
    /// leaves less than [`SWING_FIT_RATIO`] of what its response as given
    /// leaves: the baseline has taken up the offset's steady part.
    /// A span error counts only where it leaves less than
    /// [`SPAN_FIT_RATIO`] of what the channel's offset in the same form
    /// leaves. An offset on x counts only with `position` (x watched), up to [`POSITION_MOST_OFFSET_MM`],
    /// and where it leaves less than [`POSITION_FIT_RATIO`] of what the best
    /// misreading of p1 or p2 leaves.
    /// Without `all_forms`, the pressures' offsets' responses as given alone
    /// (an offset on x grows at a transducer's drift, mm per minute: it makes
    /// no episode's step).
    /// Between the pressures' standing misreadings and their drifting offsets
    /// it takes the one whose fit leaves the smaller share of what its leak
    /// leaves ([`BestOffset::leak_left`]; the leaks of kinds `directions`):
    /// a drift fits everything a standing offset fits, and as much more as
    /// its rate allows, so it is judged against a leak with a rate too.
    pub(crate) fn best_offset(
        &self,
        all_forms: bool,
        position: bool,
        directions: &[[f64; 2]; 3],
    ) -> BestOffset {
        let left: [f64; ALL_HYPOTHESES] = std::array::from_fn(|h| self.energy - self.explained_by_offset(h));
        let best = |range: std::ops::Range<usize>| {
            range
                .filter(|&h| !is_swing(h) || (all_forms && left[h] < SWING_FIT_RATIO * left[as_given(h)]))
                .filter(|&h| !is_span(h) || (all_forms && left[h] < SPAN_FIT_RATIO * left[h - 4]))
                .map(|h| (h, left[h]))
                .fold((0, f64::INFINITY), |a, b| if b.1 < a.1 { b } else { a })
        };
        let pressure = best(0..FIRST_POSITION_HYPOTHESIS);
        let drifting = best(FIRST_DRIFT_HYPOTHESIS..ALL_HYPOTHESES);
        let (steady, growing) = (
            self.unexplained_by_leak(directions),
            self.unexplained_by_growing_leak(directions),
        );
        let pressure = if drifting.1 * steady < pressure.1 * growing {
            drifting
        } else {
            pressure
        };
        let position = if all_forms && position {
            best(FIRST_POSITION_HYPOTHESIS..HYPOTHESES)
        } else {
            (0, f64::INFINITY)
        };
        let position = if self.coefficient(position.0).abs() <= POSITION_MOST_OFFSET_MM {
            position
        } else {
            (position.0, f64::INFINITY)
        };
        let (h, left) = if position.1 < POSITION_FIT_RATIO * pressure.1 {
            position
        } else {
            pressure
        };
        BestOffset {
            h,
            left,
            leak_left: if is_drift(h) { growing } else { steady },
        }
    }

    /// The least energy a misreading of the other pressure channel than
    /// `c` leaves unexplained, in any of its forms, (L/min)²·s.
    pub(crate) fn other_pressure_channel_left(&self, c: usize) -> f64 {
        (0..ALL_HYPOTHESES)
            .filter(|&h| !is_position(h) && channel_of(h) != c)
            .map(|h| self.energy - self.explained_by_offset(h))
            .fold(f64::INFINITY, f64::min)
    }

    /// The energy the best leak growing at a steady rate leaves unexplained,
    /// (L/min)²·s: (q + q̇·τ) along `directions[k]` at the sample of age τ.
    /// A drifting offset is judged against it: each has a rate to fit.
    pub(crate) fn unexplained_by_growing_leak(&self, directions: &[[f64; 2]; 3]) -> f64 {
        let (t1, t2, tr) = self.age;
        let det = self.w * t2 - t1 * t1;
        let best = directions
            .iter()
            .map(|u| {
                let s0 = u[0] * self.rise[0] + u[1] * self.rise[1];
                let s1 = u[0] * tr[0] + u[1] * tr[1];
                if det > 1e-9 * self.w * t2 {
                    // the normal equations' solution explains q·s0 + q̇·s1
                    (t2 * s0 * s0 - 2.0 * t1 * s0 * s1 + self.w * s1 * s1) / det
                } else {
                    s0 * s0 / self.w.max(1e-12)
                }
            })
            .fold(0.0, f64::max);
        self.energy - best
    }

    /// Whether the best misreading `best` (of [`Fit::best_offset`] on this
    /// fit) leaves less than `ratio` times what the best leak's fit leaves.
    pub(crate) fn offset_fits_better(&self, best: &BestOffset, ratio: f64) -> bool {
        self.energy > 0.0 && best.left < ratio * best.leak_left
    }

    /// RMS of the rises that the offset of hypothesis `c` explains, L/min.
    pub(crate) fn explained_rms_lpm(&self, c: usize) -> f64 {
        (self.explained_by_offset(c).max(0.0) / self.w.max(1e-12)).sqrt()
    }

    /// RMS of the rises that a misreading of each channel (p1, p2, x)
    /// explains in any form, L/min.
    pub(crate) fn channels_explained_rms_lpm(&self) -> [f64; 3] {
        // (each channel's largest energy's RMS: the square root and the
        // division keep the order, so one root gives the largest RMS exactly)
        let mut most = [0.0f64; 3];
        for h in 0..ALL_HYPOTHESES {
            let c = channel_of(h);
            most[c] = most[c].max(self.explained_by_offset(h).max(0.0));
        }
        most.map(|m| (m / self.w.max(1e-12)).sqrt())
    }
}

/// The unit directions in (w1, w2) of ext1, ext2 and int for the internal
/// leak's pressure factors `factors` ([`crate::signatures_with`]).
pub(crate) fn leak_directions(factors: [f64; 2]) -> [[f64; 2]; 3] {
    let [r1, r2] = factors;
    let n = (r1 * r1 + r2 * r2).sqrt().max(1e-12);
    [[1.0, 0.0], [0.0, 1.0], [r1 / n, -r2 / n]]
}

/// The rise `rise` in (w1, w2) (L/min) with its part against an internal
/// leak taken out, and the offset hypotheses' responses `hypotheses` with
/// theirs, where the rise has such a part; else all as they are. An internal
/// leak of the pressure factors `factors` moves (w1, w2) along u = (r1, −r2);
/// the rise is split along u and along the external leak whose ray bounds
/// what leaks can make on that side (ext2 while r1 ≥ 0, else ext1). A
/// negative part along u is a chamber gaining what the other loses, the wrong
/// way for any leak: it is what is taken out, of the rise and of every
/// response alike.
///
/// The model makes that pattern itself: the fast moves of a handling cycle,
/// and the rests under load after them, with no fault at all. No leak makes
/// it, and an offset alone does not explain it: left in, it weighs on both
/// fits alike, and a drift's smaller part of the rises is lost in it.
pub(crate) fn without_reverse_internal(
    rise: [f64; 2],
    factors: [f64; 2],
    hypotheses: &mut [[f64; 2]],
) -> [f64; 2] {
    let [r1, r2] = factors;
    // the part along u of v split along u and the bounding external leak
    let along = |v: [f64; 2]| {
        if r1 >= 0.0 {
            v[0] / r1
        } else {
            -v[1] / r2
        }
    };
    let least = REVERSE_INTERNAL_LEAST_FACTOR;
    if !(r1.abs() >= least && r2.abs() >= least && along(rise) < 0.0) {
        return rise;
    }
    let take_out = |v: [f64; 2]| {
        let c = along(v);
        [v[0] - c * r1, v[1] + c * r2]
    };
    for h in hypotheses.iter_mut() {
        *h = take_out(*h);
    }
    take_out(rise)
}
