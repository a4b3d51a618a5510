//! The offset watch's limits: its window, the fits' ratios, and the least
//! and largest misreadings it names.

/// Time constant of the window the offsets are named over, s.
pub const OFFSET_WINDOW_S: f64 = 10.0;
/// An episode of high rises ends once they have all stayed below
/// [`EPISODE_LEVEL`] of their thresholds for this long, s (longer than a duty
/// cycle's rest: an offset's rises come back with the next move).
pub const EPISODE_QUIET_S: f64 = 3.0;
/// Share of each threshold a rise must pass to start an episode (1).
pub const EPISODE_LEVEL: f64 = 0.5;
/// An offset explains the rises better than a leak when its fit leaves less
/// than this share of what the best leak's fit leaves unexplained (1): then
/// they are no leak evidence, and it may be named. (Where the offset's response
/// barely swings, as under a steady sine, both fit alike and neither wins.)
pub const OFFSET_FIT_RATIO: f64 = 0.5;
/// An offset's swing about its baseline is fitted in its place when it leaves
/// less than this share of what the offset's response as the filter gives it
/// leaves (1). A leak's steady rise, or a healthy rig's hoses, fit both forms
/// alike; a standing offset's rises, once the baseline has taken up their
/// steady part, fit the swing far better.
pub const SWING_FIT_RATIO: f64 = 0.5;
/// A span error is fitted in place of an offset on its channel where it
/// leaves less than this share of what the offset leaves (1): a healthy rig's
/// hoses make rises that fit both alike.
pub const SPAN_FIT_RATIO: f64 = 0.5;
/// To be named, the offset's fit leaves at most this share of the rises'
/// energy unexplained (1).
pub const OFFSET_MAX_UNEXPLAINED: f64 = 0.5;
/// To be named, the offset's part of the rises reaches this share of the
/// smallest threshold, RMS over the window (1).
pub const OFFSET_NAMED_SHARE: f64 = 0.3;
/// Least span error named (1): a transducer's accuracy of reading.
pub const SPAN_LEAST_ERROR: f64 = 0.005;
/// Least standing offset named, as a share of the transducer's range (1):
/// below it the offset is within a sound transducer's accuracy (a datasheet's
/// ±50 kPa zero and ±0.5 % span read up to 100 kPa off at 10 MPa).
pub const OFFSET_LEAST_SHARE_OF_RANGE: f64 = 0.005;
/// Least drifting offset named, as a share of the transducer's range (1): a
/// drift's rate also fits a healthy model's error that moves as the oil warms,
/// and a healthy rig's hoses (the drop between a manifold transducer and its
/// chamber, which moves with the oil's viscosity) make as much.
pub const DRIFT_LEAST_SHARE_OF_RANGE: f64 = 0.01;
/// A drifting offset is named from [`DRIFT_LEAST_SHARE_OF_RANGE`] where its
/// rate moves it by at least this share of itself over [`OFFSET_WINDOW_S`]
/// (1); a slower one from [`OFFSET_LEAST_SHARE_OF_RANGE`], as a standing one.
/// A healthy model's error fitted as a drift moves fast: 250-600 kPa a minute
/// at 160-170 kPa on the in-repo lift, a quarter of itself and more.
pub const DRIFT_LEAST_MOVE_SHARE: f64 = 0.1;
/// An offset on p1 or p2 is named only where its fit leaves less than this
/// share of what the best misreading of the other pressure channel leaves
/// (1), and that leaves more than [`OFFSET_CLEAN_UNEXPLAINED`](super::OFFSET_CLEAN_UNEXPLAINED) of the rises'
/// energy: the two channels' responses often fit alike (on a double-rod
/// press, p1 reading high as p2 reading low), and the channel named is the
/// transducer the operator checks.
pub const CHANNEL_FIT_RATIO: f64 = 0.5;
/// An offset on x is fitted in place of the pressures' misreadings where it
/// leaves less than this share of what the best of them leaves (1): a drift
/// of p1 or p2 moves the leak sizes in patterns an offset on x can partly fit.
pub const POSITION_FIT_RATIO: f64 = 0.5;
/// Fastest drift of a pressure transducer's zero fitted, MPa/s (600 kPa a
/// minute: twice the fastest a failing transducer is tested at). A leak that
/// opens over seconds moves the sizes as an offset growing far faster would.
pub const MOST_DRIFT_MPA_PER_S: f64 = 0.01;
/// Fastest drift of the position transducer's zero, mm/s (4 mm a minute:
/// twice the fastest a failing transducer is tested at). Once a leak is
/// named, an offset on x that grew faster is the leak's imprint.
pub const MOST_POSITION_DRIFT_MM_PER_S: f64 = 4.0 / 60.0;
/// Largest offset on x fitted, mm: a transducer's zero drifts by a few mm at
/// most. Where the filter's response to an offset on x is small, model error
/// alone fits offsets of tens of mm.
pub const POSITION_MOST_OFFSET_MM: f64 = 15.0;
/// Least offset on x named, mm: a position transducer's accuracy is a
/// fraction of it, and the chambers' volumes the model reads move by less
/// than their tolerance.
pub const POSITION_LEAST_OFFSET_MM: f64 = 1.0;
