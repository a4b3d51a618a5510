//! detector.csv: the leak-size detector's view of a replay at 100 Hz, what
//! `leakwatch plot` draws as the leak panel: each kind's rise above its
//! healthy baseline and the threshold it is held against, and whether the
//! detector was blind (gathering no evidence).

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

use detect::Classifier;
use filter::Estimate;

/// The file's name in a replay's output directory.
pub const FILE_NAME: &str = "detector.csv";

/// The header: time, the ext1/ext2/int rises and thresholds (L/min at the
/// nominal drop), blind (1) or watching (0).
pub const HEADER: &str =
    "t,rise_e1_lpm,rise_e2_lpm,rise_i_lpm,threshold_e1_lpm,threshold_e2_lpm,threshold_i_lpm,blind";

/// One row every this many estimates (100 Hz at 1 kHz).
const EVERY: u64 = 10;

/// Writes detector.csv from the armed detector, one row every [`EVERY`] estimates.
pub struct DetectorTrace {
    /// The open file.
    out: BufWriter<File>,
    /// Estimates seen.
    seen: u64,
    /// The detector's blind seconds after the estimate before, s.
    blind_before_s: f64,
    /// Whether an estimate since the last row was blind.
    blind_since_row: bool,
}

impl DetectorTrace {
    /// A trace into `file`, its header written.
    pub fn new(file: File) -> std::io::Result<DetectorTrace> {
        let mut out = BufWriter::new(file);
        writeln!(out, "{HEADER}")?;
        Ok(DetectorTrace {
            out,
            seen: 0,
            blind_before_s: 0.0,
            blind_since_row: false,
        })
    }

    /// Takes the detectors `cls` after they read estimate `e`: a row every
    /// [`EVERY`] estimates once armed (blind if any estimate since the last row was).
    pub fn push(&mut self, e: &Estimate, cls: &Classifier) -> std::io::Result<()> {
        let det = &cls.leak_size;
        self.seen += 1;
        let blind_s = det.blind_s();
        self.blind_since_row |= blind_s > self.blind_before_s;
        self.blind_before_s = blind_s;
        if !det.is_armed() || !self.seen.is_multiple_of(EVERY) {
            return Ok(());
        }
        let r = det.rise_lpm(e);
        // the thresholds in force: those learned, widened as the detector
        // widened them on this estimate
        let th = det.thresholds_in_force_lpm();
        writeln!(
            self.out,
            "{},{},{},{},{},{},{},{}",
            e.t_s,
            r[0],
            r[1],
            r[2],
            th[0],
            th[1],
            th[2],
            u8::from(self.blind_since_row)
        )?;
        self.blind_since_row = false;
        Ok(())
    }

    /// Flushes the file.
    pub fn finish(mut self) -> std::io::Result<()> {
        self.out.flush()
    }
}

/// The path of detector.csv in `dir`.
pub fn path_in(dir: &Path) -> std::path::PathBuf {
    dir.join(FILE_NAME)
}
