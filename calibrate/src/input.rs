//! The inputs: reading a measured record, and checking and
//! preparing them for a calibration (windows, fitting and validation parts).

use std::path::Path;

use model::params::ActuatorParams;
use model::Sample;

use crate::shoot::{Prepared, ShootSettings};
use crate::{CalibrateError, CalibrateOptions, NOT_IDENTIFIABLE};

/// Reads a measured CSV (dataset format; `.csv.gz` is decompressed on the
/// fly); missing columns and unusable files are errors. Rows that cannot be
/// used (NaN, out of range) are skipped by the reader; a gap they leave ends
/// the stretch used.
pub fn load_measured(path: &Path) -> Result<Vec<Sample>, CalibrateError> {
    if path.extension().is_some_and(|e| e == "gz") {
        let file = std::fs::File::open(path).map_err(|source| CalibrateError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        let reader = std::io::BufReader::new(flate2::read::GzDecoder::new(file));
        let mut r = dataset::CsvReader::new(reader, path, dataset::Limits::default())?;
        let mut samples = Vec::new();
        let mut first_issue = None;
        let mut skipped = 0usize;
        while let Some(row) = r.next_row() {
            match row {
                dataset::Row::Sample(s) | dataset::Row::AfterGap(s, _) => samples.push(s),
                dataset::Row::Skipped(issue) => {
                    skipped += 1;
                    first_issue.get_or_insert(issue.to_string());
                }
            }
        }
        if samples.is_empty() {
            return Err(CalibrateError::Dataset(dataset::DatasetError::NoUsableSamples {
                path: path.to_path_buf(),
                detail: match first_issue {
                    Some(f) => format!("{skipped} rows skipped; first: {f}"),
                    None => "the file has a header but no rows".to_string(),
                },
            }));
        }
        return Ok(samples);
    }
    let ds = dataset::read_csv(path, dataset::Limits::default())?;
    Ok(ds.samples)
}

/// Prepared inputs of a calibration.
pub(crate) struct Setup {
    pub(crate) data: Prepared,
    pub(crate) set: ShootSettings,
    pub(crate) seconds: f64,
    pub(crate) warnings: Vec<String>,
}

/// A pressure channel whose whole range is within this is taken as flat (a
/// disconnected transducer), Pa.
pub const FLAT_PRESSURE_PA: f64 = 1.0e3;

/// Below this stroke the record is said not to excite effects that need motion, m.
pub const MIN_STROKE_M: f64 = 1.0e-3;

pub(crate) fn setup(
    measured: &[Sample],
    model: &ActuatorParams,
    opts: &CalibrateOptions,
) -> Result<Setup, CalibrateError> {
    model.validate().map_err(CalibrateError::InvalidModel)?;
    for (i, s) in measured.iter().enumerate() {
        for (v, c) in [
            (s.t_s, "t"),
            (s.u_v, "u"),
            (s.x_m, "x"),
            (s.p1_pa, "p1"),
            (s.p2_pa, "p2"),
        ] {
            if !v.is_finite() {
                return Err(CalibrateError::NonFinite { index: i, column: c });
            }
        }
    }
    let n = measured.len();
    let span = if n >= 2 {
        measured[n - 1].t_s - measured[0].t_s
    } else {
        0.0
    };
    if n < 10 || span < opts.min_seconds {
        return Err(CalibrateError::TooLittleData {
            samples: n,
            seconds: span.max(0.0),
            needed_seconds: opts.min_seconds,
        });
    }
    let mut diffs: Vec<f64> = measured.windows(2).map(|w| w[1].t_s - w[0].t_s).collect();
    diffs.sort_by(|a, b| a.total_cmp(b));
    let dt = diffs[diffs.len() / 2];
    if dt <= 0.0 || !dt.is_finite() {
        return Err(CalibrateError::BadSampling(
            "time does not increase from one sample to the next".into(),
        ));
    }
    let mut warnings = Vec::new();
    // Every sample (up to max_seconds); gaps in time (rows the reader skipped:
    // NaN, out of range, ...) are left out of the comparison windows.
    let mut end = n;
    if opts.max_seconds > 0.0 {
        let t_end = measured[0].t_s + opts.max_seconds;
        end = measured.iter().position(|s| s.t_s >= t_end).unwrap_or(n);
        if end < n {
            warnings.push(format!(
                "only the first {:.1} s of the record are used (max_seconds)",
                opts.max_seconds
            ));
        }
    }
    let gaps = measured[..end]
        .windows(2)
        .filter(|w| w[1].t_s - w[0].t_s >= 1.5 * dt)
        .count();
    if gaps > 0 {
        warnings.push(format!(
            "the record has {gaps} gap(s) in time (rows skipped or missing); comparison windows that \
             straddle one are left out"
        ));
    }
    let first = 0;
    let used = &measured[first..end];
    let end = end - first;
    let seconds = end as f64 * dt;
    // Pressures written in bar, MPa or psi read as a flat channel: said first.
    let mut reach = dataset::PressureReach::default();
    used.iter().for_each(|s| reach.add(s));
    reach
        .check(model.supply_pressure_pa)
        .map_err(CalibrateError::Units)?;
    // A channel that never changes is a disconnected or broken transducer.
    for (name, get) in [
        ("p1", (|s: &Sample| s.p1_pa) as fn(&Sample) -> f64),
        ("p2", |s: &Sample| s.p2_pa),
    ] {
        let lo = used.iter().map(get).fold(f64::INFINITY, f64::min);
        let hi = used.iter().map(get).fold(f64::NEG_INFINITY, f64::max);
        if hi - lo <= FLAT_PRESSURE_PA {
            return Err(CalibrateError::FlatChannel {
                column: name,
                value: lo,
            });
        }
    }
    let x_lo = used.iter().map(|s| s.x_m).fold(f64::INFINITY, f64::min);
    let x_hi = used.iter().map(|s| s.x_m).fold(f64::NEG_INFINITY, f64::max);
    if x_hi - x_lo < MIN_STROKE_M {
        warnings.push(format!(
            "the rod moved only {:.3} mm: friction, a spring and anything that needs motion {NOT_IDENTIFIABLE} \
             (move the rod over some centimetres, e.g. an open-loop sine of 3 V at 1 Hz)",
            (x_hi - x_lo) * 1e3
        ));
    }
    if seconds < opts.min_seconds {
        return Err(CalibrateError::TooLittleData {
            samples: end,
            seconds,
            needed_seconds: opts.min_seconds,
        });
    }
    let w = ((opts.window_s / dt).round() as usize).max(10);
    let mut data = Prepared::new(
        used,
        dt,
        w,
        opts.fit_fraction.clamp(0.1, 0.95),
        opts.split_block_windows,
        opts.velocity_half_width,
    );
    let before = data.thin(opts.max_windows, opts.split_block_windows.max(1));
    if before > 0 {
        warnings.push(format!(
            "for speed, {} of the {before} windows are compared: whole blocks of {} spread evenly \
             from the start to the end of the record (max_windows)",
            data.windows.len(),
            opts.split_block_windows.max(1)
        ));
    }
    if data.fit_windows().len() < 2 || data.val_windows().is_empty() {
        return Err(CalibrateError::TooLittleData {
            samples: end,
            seconds,
            needed_seconds: opts.min_seconds,
        });
    }
    let set = ShootSettings {
        method: opts.method,
        scale_f_n: opts.scale_f_n,
        scale_sp_m: opts.scale_sp_m,
        substeps: opts.substeps_per_sample.max(1),
        stride: opts.compare_stride.max(1),
        scale_x_m: opts.scale_x_m,
        scale_p_pa: opts.scale_p_pa,
        velocity_noise_m_s: crate::shoot::velocity_noise_m_s(
            opts.position_noise_m,
            dt,
            opts.velocity_half_width,
        ),
    };
    Ok(Setup {
        data,
        set,
        seconds,
        warnings,
    })
}
