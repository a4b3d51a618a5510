//! Which rows are usable: the physical range of every column ([`Limits`]) and
//! how many unusable rows a file may have.

use crate::{IssueKind, Sample, REQUIRED};

/// The default largest fraction of a file's rows that may be unusable (1 %);
/// beyond it replay reports the file as bad (non-zero exit).
pub const DEFAULT_MAX_BAD_FRACTION: f64 = 0.01;

/// Limits that decide which rows are usable: the physical range of every
/// column, from the actuator's parameters (see [`Limits::for_model`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Limits {
    /// Lowest accepted pressure, Pa (−0.02 p_s: noise and offset near tank pressure).
    pub min_pressure_pa: f64,
    /// Highest accepted pressure, Pa (MODEL: 1.5 p_s).
    pub max_pressure_pa: f64,
    /// Nominal sample period, s, used to detect gaps and too short steps
    /// (None: learned from the first two rows).
    pub sample_period_s: Option<f64>,
    /// A time step shorter than `(1 - step_tolerance)` sample periods is refused
    /// (a duplicated or jittered time stamp), dimensionless in [0, 1).
    pub step_tolerance: f64,
    /// Largest accepted |t|, s (1e10 s: Unix time stamps pass, 1e308 does not).
    pub max_abs_time_s: f64,
    /// Lowest accepted rod position (and position reference `ref`), m.
    pub min_position_m: f64,
    /// Highest accepted rod position (and position reference `ref`), m.
    pub max_position_m: f64,
    /// Largest accepted |u|, V.
    pub max_command_v: f64,
    /// Largest accepted |x_sp|, m.
    pub max_spool_m: f64,
    /// Largest accepted |f_load|, N.
    pub max_force_n: f64,
    /// Largest accepted |q_leak|, L/min.
    pub max_leak_lpm: f64,
    /// Accepted oil temperatures `temp_c`, °C (lowest, highest).
    pub oil_temp_range_c: (f64, f64),
}

/// The oil temperatures a row may carry, °C: a mineral oil's working range
/// with margin (below −40 °C it is a solid, above 150 °C it is ruined).
pub const OIL_TEMP_RANGE_C: (f64, f64) = (-40.0, 150.0);

impl Limits {
    /// The physical ranges of an actuator with parameters `p`, sampled every
    /// `sample_period_s` seconds:
    /// - position x and reference within the stroke [x_min, x_max] plus 10 % of
    ///   the stroke on each side, m;
    /// - command |u| within 1.5 × the valve's ±10 V range, V;
    /// - pressures in [−0.02 p_s, 1.5 p_s] inclusive, Pa
    ///   ([`model::ActuatorParams::measured_pressure_range_pa`], the range the
    ///   estimator uses too): sensor noise and offset around tank pressure read
    ///   slightly below 0, down to 2 % of the supply pressure (−0.276 MPa at 13.8 MPa);
    /// - spool |x_sp| within 2 × the opening at 10 V, m;
    /// - load |f_load| within 10 × the force of 1.5 p_s on the piston, N;
    /// - leak |q_leak| within 10 × the valve's flow at full opening and 1.5 p_s, L/min;
    /// - oil temperature `temp_c` within [`OIL_TEMP_RANGE_C`], °C;
    /// - time steps no shorter than half a sample period, |t| ≤ 1e10 s.
    pub fn for_model(p: &model::ActuatorParams, sample_period_s: f64) -> Limits {
        let u_max = model::scenario::U_MAX_V;
        let stroke = p.x_max_m - p.x_min_m;
        let (p_min, p_max) = p.measured_pressure_range_pa();
        let spool_open = u_max * p.spool_gain_m_per_v;
        let q_valve_m3_s = p.discharge_coefficient
            * p.area_gradients_m2_per_m().0.max(p.area_gradients_m2_per_m().1)
            * spool_open
            * (2.0 * p_max / p.oil_density_kg_m3).sqrt();
        Limits {
            min_pressure_pa: p_min,
            max_pressure_pa: p_max,
            sample_period_s: Some(sample_period_s),
            step_tolerance: 0.5,
            max_abs_time_s: 1.0e10,
            min_position_m: p.x_min_m - 0.1 * stroke,
            max_position_m: p.x_max_m + 0.1 * stroke,
            max_command_v: 1.5 * u_max,
            max_spool_m: 2.0 * spool_open,
            max_force_n: 10.0 * p_max * p.piston_area_m2,
            max_leak_lpm: 10.0 * model::units::m3_s_to_lpm(q_valve_m3_s),
            oil_temp_range_c: OIL_TEMP_RANGE_C,
        }
    }

    /// The supply pressure these limits were made from, Pa (the highest
    /// accepted pressure over [`model::params::PRESSURE_MAX_PER_SUPPLY`]).
    pub fn supply_pa(&self) -> f64 {
        self.max_pressure_pa / model::params::PRESSURE_MAX_PER_SUPPLY
    }

    /// The default actuator's ranges with supply pressure `supply_pa` (pressures
    /// in [−0.02 p_s, 1.5 p_s], Pa), 1 kHz.
    pub fn for_supply(supply_pa: f64) -> Limits {
        let p = model::ActuatorParams {
            supply_pressure_pa: supply_pa,
            ..model::ActuatorParams::default()
        };
        Limits::for_model(&p, 1.0e-3)
    }

    /// The first value of `s` outside its range, as (column index in
    /// [`COLUMNS`](crate::COLUMNS), kind, message); `None` if every value is usable. NaN in an
    /// optional column means "absent" and passes.
    pub fn check(&self, s: &Sample) -> Option<(usize, IssueKind, String)> {
        let values = s.columns();
        for (j, v) in values.into_iter().enumerate() {
            let optional = j >= REQUIRED.len();
            if optional && v.is_nan() {
                continue;
            }
            if !v.is_finite() {
                let what = if optional { "value" } else { "required value" };
                return Some((j, IssueKind::NonFinite, format!("{what} is {v:?} (not finite)")));
            }
            let (lo, hi, unit) = match j {
                0 => (-self.max_abs_time_s, self.max_abs_time_s, "s"),
                1 => (-self.max_command_v, self.max_command_v, "V"),
                2 | 7 => (self.min_position_m, self.max_position_m, "m"),
                3 | 4 => (self.min_pressure_pa, self.max_pressure_pa, "Pa"),
                5 => (-self.max_spool_m, self.max_spool_m, "m"),
                6 => (-self.max_force_n, self.max_force_n, "N"),
                8 => (-self.max_leak_lpm, self.max_leak_lpm, "L/min"),
                _ => (self.oil_temp_range_c.0, self.oil_temp_range_c.1, "°C"),
            };
            if !(lo..=hi).contains(&v) {
                let what = match j {
                    0 => "time",
                    1 => "command",
                    2 => "position",
                    3 | 4 => "pressure",
                    5 => "spool position",
                    6 => "load",
                    7 => "position reference",
                    8 => "leak flow",
                    _ => "oil temperature",
                };
                let mut msg = format!("{what} {v:?} {unit} is outside [{lo:?}, {hi:?}] {unit}");
                if what == "pressure" {
                    msg += " (from 2 % of the supply pressure below 0 to 1.5 × the supply pressure)";
                }
                return Some((j, IssueKind::OutOfRange, msg));
            }
        }
        None
    }
}

impl Default for Limits {
    fn default() -> Self {
        Limits::for_model(&model::ActuatorParams::default(), 1.0e-3)
    }
}

/// Checks that at most `max_fraction` of `rows` were unusable; the error says
/// how many were and the limit (a message for the user).
pub fn check_bad_fraction(rows: u64, skipped: u64, max_fraction: f64) -> Result<(), String> {
    if rows > 0 && skipped as f64 > max_fraction * rows as f64 {
        return Err(format!(
            "{skipped} of {rows} rows ({:.2} %) are unusable, more than the {:.2} % accepted",
            100.0 * skipped as f64 / rows as f64,
            100.0 * max_fraction
        ));
    }
    Ok(())
}
