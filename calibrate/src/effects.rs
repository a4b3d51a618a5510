//! The library of candidate effects: physical extensions of the model, each
//! with its parameters (SI), the resolution the fit must reach, bounds, and
//! the signature it leaves in the residuals.

use model::leakage::{LeakLaw, LeakPath};
use model::params::{ActuatorParams, BuiltInLeak, FrictionParams};
use serde::{Deserialize, Serialize};

/// One candidate effect of the library. Two forms share the name
/// `bulk-modulus` (a lower β, or entrained air that lowers it at low pressure).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Effect {
    /// `friction-asymmetry`: the retracting seal's static and Coulomb friction
    /// differ from the extending one's (scaled together), viscous unchanged.
    FrictionAsymmetry,
    /// `friction-asymmetry` with its own retracting viscous coefficient too.
    FrictionAsymmetryViscous,
    /// `friction`, fitted only on request ([`Effect::ON_REQUEST`]): static
    /// and Coulomb (scaled together) and viscous friction per direction, and
    /// the Stribeck velocity.
    Friction,
    /// `spool-bias`: the spool sits off centre at zero command.
    SpoolBias,
    /// `spring-load`: a spring in front of the rod (stiffness and contact position).
    SpringLoad,
    /// `bulk-modulus`, constant form: a lower effective bulk modulus β.
    BulkModulus,
    /// `bulk-modulus`, pressure-dependent form: entrained air (β falls at low pressure).
    EntrainedAir,
    /// `supply-sag`: the supply pressure falls with the flow drawn.
    SupplySag,
    /// `valve-bandwidth`: a slower spool (lower natural frequency).
    ValveBandwidth,
    /// `leak-ext1`: square-root-law leak from chamber 1 to return.
    LeakExt1,
    /// `leak-ext2`: square-root-law leak from chamber 2 to return.
    LeakExt2,
    /// `leak-int`: square-root-law leak from chamber 1 to chamber 2.
    LeakInt,
}

/// Typical leak coefficient used as the resolution scale, m³/(s·√Pa)
/// (about 0.05 L/min at 6.9 MPa).
const LEAK_RESOLUTION: f64 = 3.0e-10;

impl Effect {
    /// Every candidate, in the library's order.
    pub const ALL: [Effect; 11] = [
        Effect::FrictionAsymmetry,
        Effect::FrictionAsymmetryViscous,
        Effect::SpoolBias,
        Effect::SpringLoad,
        Effect::BulkModulus,
        Effect::EntrainedAir,
        Effect::SupplySag,
        Effect::ValveBandwidth,
        Effect::LeakExt1,
        Effect::LeakExt2,
        Effect::LeakInt,
    ];

    /// Effects fitted only when asked for by name (`fit_effect`, or
    /// [`crate::CalibrateOptions::candidates`]), not searched by default.
    pub const ON_REQUEST: [Effect; 1] = [Effect::Friction];

    /// The effect names of the library (docs/calibration/README.md; `friction` on request).
    pub const NAMES: [&'static str; 10] = [
        "friction",
        "friction-asymmetry",
        "spool-bias",
        "spring-load",
        "bulk-modulus",
        "supply-sag",
        "valve-bandwidth",
        "leak-ext1",
        "leak-ext2",
        "leak-int",
    ];

    /// The effect's name (`bulk-modulus` for both of its forms).
    pub fn name(self) -> &'static str {
        match self {
            Effect::FrictionAsymmetry | Effect::FrictionAsymmetryViscous => "friction-asymmetry",
            Effect::Friction => "friction",
            Effect::SpoolBias => "spool-bias",
            Effect::SpringLoad => "spring-load",
            Effect::BulkModulus | Effect::EntrainedAir => "bulk-modulus",
            Effect::SupplySag => "supply-sag",
            Effect::ValveBandwidth => "valve-bandwidth",
            Effect::LeakExt1 => "leak-ext1",
            Effect::LeakExt2 => "leak-ext2",
            Effect::LeakInt => "leak-int",
        }
    }

    /// Which form of the named effect this is, for reports.
    pub fn form(self) -> &'static str {
        match self {
            Effect::FrictionAsymmetry => "retracting static and Coulomb friction differ (scaled together)",
            Effect::FrictionAsymmetryViscous => {
                "retracting static, Coulomb (scaled together) and viscous friction differ"
            }
            Effect::Friction => {
                "static and Coulomb (scaled together) and viscous friction per direction, Stribeck velocity"
            }
            Effect::SpoolBias => "spool null bias",
            Effect::SpringLoad => "spring with contact position",
            Effect::BulkModulus => "lower constant bulk modulus",
            Effect::EntrainedAir => "entrained air (pressure-dependent bulk modulus)",
            Effect::SupplySag => "supply pressure sags with flow",
            Effect::ValveBandwidth => "slower spool",
            Effect::LeakExt1 => "external leak at chamber 1, square-root law",
            Effect::LeakExt2 => "external leak at chamber 2, square-root law",
            Effect::LeakInt => "internal leak, square-root law",
        }
    }

    /// The candidates with this name (both forms for `bulk-modulus`), or
    /// none if the name is unknown.
    pub fn by_name(name: &str) -> Vec<Effect> {
        Effect::ALL
            .iter()
            .chain(Effect::ON_REQUEST.iter())
            .copied()
            .filter(|e| e.name() == name)
            .collect()
    }

    /// The residual signature the effect leaves, for reports.
    pub fn signature(self) -> &'static str {
        match self {
            Effect::FrictionAsymmetry | Effect::FrictionAsymmetryViscous => {
                "Δp error of one sign while retracting only; none while extending"
            }
            Effect::Friction => "force-balance error depending on the direction and speed of motion",
            Effect::SpoolBias => "position drift and p1/p2 offsets of opposite sign near zero command",
            Effect::SpringLoad => "p1 − p2 error growing with stroke beyond a contact position",
            Effect::BulkModulus | Effect::EntrainedAir => {
                "pressure transients too fast / too stiff in the model, largest at reversals (and low pressure for air)"
            }
            Effect::SupplySag => "chamber fed from supply under-predicted at high flow (fast strokes)",
            Effect::ValveBandwidth => "lag growing with input frequency, after command steps",
            Effect::LeakExt1 => "p1 over-predicted, position drifts towards retracting",
            Effect::LeakExt2 => "p2 over-predicted, position drifts towards extending",
            Effect::LeakInt => "p1 over- and p2 under-predicted, a velocity-like offset",
        }
    }

    /// Names of the parameters, as dotted field paths of `ActuatorParams`.
    pub fn parameter_names(self) -> &'static [&'static str] {
        match self {
            Effect::FrictionAsymmetry => &["friction.retract.slip_n"],
            Effect::FrictionAsymmetryViscous => {
                &["friction.retract.slip_n", "friction.retract.viscous_n_s_per_m"]
            }
            Effect::Friction => &[
                "friction.slip_n",
                "friction.viscous_n_s_per_m",
                "friction.retract.slip_n",
                "friction.retract.viscous_n_s_per_m",
                "friction.stribeck_velocity_m_s",
            ],
            Effect::SpoolBias => &["spool_null_bias_m"],
            Effect::SpringLoad => &["load.stiffness_n_per_m", "load.contact_m"],
            Effect::BulkModulus => &["bulk_modulus_pa"],
            Effect::EntrainedAir => &["entrained_air_fraction"],
            Effect::SupplySag => &["supply_sag_pa_per_m3_s"],
            Effect::ValveBandwidth => &["spool_natural_freq_rad_s"],
            Effect::LeakExt1 => &["leaks.ext1.sqrt_m3_s_sqrt_pa"],
            Effect::LeakExt2 => &["leaks.ext2.sqrt_m3_s_sqrt_pa"],
            Effect::LeakInt => &["leaks.int.sqrt_m3_s_sqrt_pa"],
        }
    }

    /// The change of each parameter the data must be able to resolve (the
    /// fit's scaling unit and the yardstick of identifiability), SI.
    pub fn resolution(self, base: &ActuatorParams) -> Vec<f64> {
        match self {
            Effect::FrictionAsymmetry => vec![0.1 * base.friction.slip_n.max(100.0)],
            Effect::Friction => vec![
                0.1 * base.friction.slip_n.max(100.0),
                0.1 * base.friction.viscous_n_s_per_m.max(100.0),
                0.1 * base.friction.slip_n.max(100.0),
                0.1 * base.friction.viscous_n_s_per_m.max(100.0),
                0.1 * base.friction.stribeck_velocity_m_s.max(0.005),
            ],
            Effect::FrictionAsymmetryViscous => vec![
                0.1 * base.friction.slip_n.max(100.0),
                0.1 * base.friction.viscous_n_s_per_m.max(100.0),
            ],
            Effect::SpoolBias => vec![0.01 * 3.0 * base.spool_gain_m_per_v],
            // a tenth of the model's own spring, as for the other effects' scales
            // (a workpiece of 2e6 N/m is not resolved to 2e3 N/m); without one 2e3 N/m
            Effect::SpringLoad => vec![(0.1 * base.load.stiffness_n_per_m).max(2.0e3), 0.01],
            Effect::BulkModulus => vec![0.1 * base.bulk_modulus_pa],
            Effect::EntrainedAir => {
                // the air fraction that lowers β by 10 % at the nominal chamber pressure
                const P_ATM: f64 = 101_325.0;
                let p_abs = base.nominal_chamber_pressure_pa() + P_ATM;
                vec![(0.1 * p_abs * p_abs / (base.bulk_modulus_pa * P_ATM)).clamp(1.0e-3, 0.05)]
            }
            Effect::SupplySag => vec![2.0e9],
            Effect::ValveBandwidth => vec![0.1 * base.spool_natural_freq_rad_s],
            Effect::LeakExt1 | Effect::LeakExt2 | Effect::LeakInt => vec![LEAK_RESOLUTION],
        }
    }

    /// Physical bounds of each parameter, SI.
    pub fn bounds(self, base: &ActuatorParams) -> Vec<(f64, f64)> {
        match self {
            Effect::FrictionAsymmetry => vec![(0.0, 2.0e4)],
            Effect::FrictionAsymmetryViscous => vec![(0.0, 2.0e4), (0.0, 1.0e4)],
            Effect::Friction => vec![
                (0.0, 2.0e4),
                (0.0, 1.0e4),
                (0.0, 2.0e4),
                (0.0, 1.0e4),
                (0.002, 0.5),
            ],
            Effect::SpoolBias => {
                let b = 5.0 * base.spool_gain_m_per_v;
                vec![(-b, b)]
            }
            Effect::SpringLoad => vec![(0.0, 1.0e7), (base.x_min_m, base.x_max_m)],
            Effect::BulkModulus => vec![(0.15 * base.bulk_modulus_pa, 3.0 * base.bulk_modulus_pa)],
            Effect::EntrainedAir => vec![(0.0, 0.5)],
            Effect::SupplySag => vec![(0.0, 1.0e12)],
            Effect::ValveBandwidth => vec![(2.0 * std::f64::consts::PI, 5.0 * base.spool_natural_freq_rad_s)],
            Effect::LeakExt1 | Effect::LeakExt2 | Effect::LeakInt => vec![(0.0, 1.0e-7)],
        }
    }

    /// The parameter values `base` already has (the fit's starting point,
    /// except where [`Effect::starting_points`] says otherwise), SI.
    pub fn read(self, base: &ActuatorParams) -> Vec<f64> {
        match self {
            Effect::FrictionAsymmetry => vec![base.friction.for_direction(-1.0).slip_n],
            Effect::FrictionAsymmetryViscous => {
                let r = base.friction.for_direction(-1.0);
                vec![r.slip_n, r.viscous_n_s_per_m]
            }
            Effect::Friction => {
                let e = base.friction.for_direction(1.0);
                let r = base.friction.for_direction(-1.0);
                vec![
                    e.slip_n,
                    e.viscous_n_s_per_m,
                    r.slip_n,
                    r.viscous_n_s_per_m,
                    e.stribeck_velocity_m_s,
                ]
            }
            Effect::SpoolBias => vec![base.spool_null_bias_m],
            Effect::SpringLoad => vec![base.load.stiffness_n_per_m, base.load.contact_m],
            Effect::BulkModulus => vec![base.bulk_modulus_pa],
            Effect::EntrainedAir => vec![base.entrained_air_fraction],
            Effect::SupplySag => vec![base.supply_sag_pa_per_m3_s],
            Effect::ValveBandwidth => vec![base.spool_natural_freq_rad_s],
            Effect::LeakExt1 | Effect::LeakExt2 | Effect::LeakInt => {
                let path = self.leak_path().unwrap_or(LeakPath::Internal);
                vec![base
                    .leaks
                    .iter()
                    .filter(|l| l.path == path && l.law == LeakLaw::SquareRoot)
                    .map(|l| l.coefficient)
                    .sum()]
            }
        }
    }

    /// Starting points for the fit: the current values, plus a grid over the
    /// contact position for a spring the model does not have yet (its
    /// contact is invisible while the stiffness is zero), and coarse grids
    /// for the parameters that shape resonances. `x_range_m` is the measured
    /// stroke range.
    pub fn starting_points(self, base: &ActuatorParams, x_range_m: (f64, f64)) -> Vec<Vec<f64>> {
        let cur = self.read(base);
        // the resonance-shaping parameters make the cost multimodal (the
        // ringing of the hydraulic resonance and of the spool): a coarse grid
        match self {
            Effect::SpringLoad if cur[0] <= 0.0 => {
                let (lo, hi) = x_range_m;
                (1..=4)
                    .map(|i| vec![0.0, lo + (hi - lo) * i as f64 / 5.0])
                    .collect()
            }
            Effect::BulkModulus | Effect::ValveBandwidth => {
                [1.0, 0.7, 0.45, 0.25].iter().map(|f| vec![cur[0] * f]).collect()
            }
            Effect::EntrainedAir => [cur[0], cur[0] + 0.02, cur[0] + 0.06, cur[0] + 0.15]
                .iter()
                .map(|a| vec![*a])
                .collect(),
            Effect::FrictionAsymmetry => [1.0, 1.5, 0.6].iter().map(|f| vec![cur[0] * f]).collect(),
            Effect::FrictionAsymmetryViscous => {
                [1.0, 1.5, 0.6].iter().map(|f| vec![cur[0] * f, cur[1]]).collect()
            }
            _ => vec![cur],
        }
    }

    /// The leak path of a leak effect.
    pub fn leak_path(self) -> Option<LeakPath> {
        match self {
            Effect::LeakExt1 => Some(LeakPath::External1),
            Effect::LeakExt2 => Some(LeakPath::External2),
            Effect::LeakInt => Some(LeakPath::Internal),
            _ => None,
        }
    }

    /// `base` with this effect's parameters set to `theta` (SI, in the order of
    /// [`Effect::parameter_names`]).
    pub fn apply(self, base: &ActuatorParams, theta: &[f64]) -> ActuatorParams {
        let mut p = base.clone();
        let t0 = theta.first().copied().unwrap_or(0.0);
        match self {
            Effect::FrictionAsymmetry | Effect::FrictionAsymmetryViscous => {
                // the retracting seal: static and Coulomb friction scaled
                // together from the extending ones, its own viscous term
                let ext = p.friction.extend();
                let slip = t0.max(0.0);
                let ratio = if ext.slip_n > 0.0 {
                    ext.static_n / ext.slip_n
                } else {
                    1.0
                };
                p.friction.retract = Some(FrictionParams {
                    static_n: slip * ratio,
                    slip_n: slip,
                    viscous_n_s_per_m: match self {
                        Effect::FrictionAsymmetryViscous => {
                            theta.get(1).copied().unwrap_or(ext.viscous_n_s_per_m)
                        }
                        _ => p.friction.for_direction(-1.0).viscous_n_s_per_m,
                    }
                    .max(0.0),
                    ..ext
                });
            }
            Effect::Friction => {
                // each direction: static and Coulomb scaled together (the
                // model's static/Coulomb ratio kept), its own viscous term;
                // one Stribeck velocity
                let th = |i: usize| theta.get(i).copied();
                let scale = |f: FrictionParams, slip: Option<f64>, visc: Option<f64>, alpha: Option<f64>| {
                    let ratio = if f.slip_n > 0.0 {
                        f.static_n / f.slip_n
                    } else {
                        1.0
                    };
                    let slip = slip.unwrap_or(f.slip_n).max(0.0);
                    FrictionParams {
                        static_n: slip * ratio,
                        slip_n: slip,
                        viscous_n_s_per_m: visc.unwrap_or(f.viscous_n_s_per_m).max(0.0),
                        stribeck_velocity_m_s: alpha.unwrap_or(f.stribeck_velocity_m_s).max(1.0e-4),
                    }
                };
                let e = scale(p.friction.for_direction(1.0), th(0), th(1), th(4));
                let r = scale(p.friction.for_direction(-1.0), th(2), th(3), th(4));
                p.friction.set_extend(e);
                p.friction.retract = Some(r);
            }
            Effect::SpoolBias => p.spool_null_bias_m = t0,
            Effect::SpringLoad => {
                p.load.stiffness_n_per_m = t0.max(0.0);
                p.load.contact_m = theta.get(1).copied().unwrap_or(p.load.contact_m);
            }
            Effect::BulkModulus => p.bulk_modulus_pa = t0,
            Effect::EntrainedAir => p.entrained_air_fraction = t0.max(0.0),
            Effect::SupplySag => p.supply_sag_pa_per_m3_s = t0.max(0.0),
            Effect::ValveBandwidth => p.spool_natural_freq_rad_s = t0,
            Effect::LeakExt1 | Effect::LeakExt2 | Effect::LeakInt => {
                let path = self.leak_path().unwrap_or(LeakPath::Internal);
                p.leaks
                    .retain(|l| !(l.path == path && l.law == LeakLaw::SquareRoot));
                if t0 > 0.0 {
                    p.leaks.push(BuiltInLeak {
                        path,
                        law: LeakLaw::SquareRoot,
                        coefficient: t0,
                    });
                }
            }
        }
        p
    }
}

impl std::fmt::Display for Effect {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}
