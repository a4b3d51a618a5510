//! The flag bits an estimate carries (`Estimate::flags`).
//!
//! They are the wire's (`frames::estimate_flags`), so flags are copied, not
//! recoded; `estimator::wire` checks at compile time that the two agree (this
//! crate is pure and does not depend on the wire types).

/// Flag bit: the filter was reset at this sample (see [`crate::Estimate::flags`]).
pub const FLAG_RESET: u32 = 1 << 0;
/// Flag bit: the sample could not be used (no measurement update).
pub const FLAG_SKIPPED: u32 = 1 << 1;
/// Flag bit: the prediction had to be clamped to the physical range.
pub const FLAG_CLAMPED: u32 = 1 << 2;
/// Flag bit: the filter is still inside its initial convergence time.
pub const FLAG_CONVERGING: u32 = 1 << 4;
/// Flag bit: samples were missing just before this one (bridged or re-anchored).
pub const FLAG_AFTER_GAP: u32 = 1 << 5;
/// Flag bit: the estimated rod position is within [`END_STOP_MARGIN_M`] of an end of
/// its stroke (for the record: the leak filter's model has the stops, stepped in
/// [`model::process::STOP_SUBSTEPS`] sub-steps while the rod is in one, and the
/// detector takes evidence there as anywhere else).
pub const FLAG_END_STOP: u32 = 1 << 6;
/// Flag bit: the filter's fast states restarted from this sample, its slow ones
/// kept: after a gap longer than it bridges ([`crate::Tuning::max_bridged_gap_samples`];
/// set with [`FLAG_AFTER_GAP`], which a bridged gap carries alone), or after it
/// lost track ([`crate::track`]).
pub const FLAG_REANCHORED: u32 = 1 << 7;
/// Flag bit: θ reads the oil past its operating range by more than
/// [`crate::oil::OIL_RANGE_MARGIN_K`]; the model is held at the range's edge and
/// the temperature's σ grows by the distance ([`crate::oil::OilFromStiffness::past_range_k`]).
pub const FLAG_OIL_PAST_RANGE: u32 = 1 << 8;
/// The flag bits of an estimate that is not yet a settled one: reset,
/// unused or still converging (what averages over a recording leave out).
pub const FLAGS_UNSETTLED: u32 = FLAG_CONVERGING | FLAG_SKIPPED | FLAG_RESET;
/// Every flag bit a [`crate::Estimate`] can carry (the wire's end-of-stream bit is not one).
pub const FLAGS_ALL: u32 = FLAG_RESET
    | FLAG_SKIPPED
    | FLAG_CLAMPED
    | FLAG_CONVERGING
    | FLAG_AFTER_GAP
    | FLAG_END_STOP
    | FLAG_REANCHORED
    | FLAG_OIL_PAST_RANGE;
/// Distance from either end of the stroke within which an estimate carries
/// [`FLAG_END_STOP`], m (an encoder count or two, plus the bounce of a stop).
pub const END_STOP_MARGIN_M: f64 = 2e-3;
