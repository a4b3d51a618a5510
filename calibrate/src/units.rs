//! Effects in engineering terms: the fitted SI parameters restated in the
//! units a rig engineer reads (N, N·s/m, µm and % of spool stroke, kN/m,
//! % air and MPa, MPa per L/min, Hz, L/min), beside the SI values.

use model::dynamics::effective_bulk_modulus_pa;
use model::params::ActuatorParams;

use crate::effects::Effect;

/// Pressure at which an effective bulk modulus is quoted, Pa.
pub const BULK_MODULUS_QUOTE_PA: f64 = 6.9e6;
/// Atmospheric pressure, Pa.
pub const P_ATM_PA: f64 = 101_325.0;
/// One litre per minute, m³/s.
pub const LPM_M3_S: f64 = 1.0e-3 / 60.0;
/// The spool command range used to quote a spool offset as a fraction of the stroke, V.
pub const FULL_COMMAND_V: f64 = 10.0;

/// The effect `name` of the calibrated model `after` (the model before it
/// was added: `before`) in engineering units, one line per quantity.
/// `mean_p_pa` = the record's mean chamber pressures [p1, p2], Pa.
pub fn describe(
    name: &str,
    before: &ActuatorParams,
    after: &ActuatorParams,
    mean_p_pa: [f64; 2],
) -> Vec<String> {
    let mut out = Vec::new();
    match name {
        "friction-asymmetry" | "friction" => {
            let e = after.friction.for_direction(1.0);
            let r = after.friction.for_direction(-1.0);
            out.push(format!(
                "retracting: static {:.0} N, Coulomb {:.0} N, viscous {:.0} N·s/m, Stribeck velocity {:.3} m/s",
                r.static_n, r.slip_n, r.viscous_n_s_per_m, r.stribeck_velocity_m_s
            ));
            out.push(format!(
                "extending{}: static {:.0} N, Coulomb {:.0} N, viscous {:.0} N·s/m (retracting/extending Coulomb {:.2})",
                if name == "friction" { "" } else { " (the model's)" },
                e.static_n,
                e.slip_n,
                e.viscous_n_s_per_m,
                r.slip_n / e.slip_n.max(1e-9)
            ));
        }
        "spool-bias" => {
            let b = after.spool_null_bias_m;
            let stroke = after.spool_gain_m_per_v * FULL_COMMAND_V;
            out.push(format!(
                "spool null bias {:+.2} µm = {:+.2} % of the spool stroke at {FULL_COMMAND_V} V ({:+.1} % of a 3 V amplitude; {:+.3} V of command)",
                b * 1e6,
                100.0 * b / stroke,
                100.0 * b / (3.0 * after.spool_gain_m_per_v),
                b / after.spool_gain_m_per_v
            ));
        }
        "spring-load" => {
            out.push(format!(
                "spring contact at x = {:.4} m, stiffness {:.2} kN/m ({:.0} N per cm of compression)",
                after.load.contact_m,
                after.load.stiffness_n_per_m * 1e-3,
                after.load.stiffness_n_per_m * 0.01
            ));
        }
        "bulk-modulus" => {
            let b = effective_bulk_modulus_pa(after, BULK_MODULUS_QUOTE_PA);
            let oil = before.bulk_modulus_pa;
            // the free-air fraction at 1 atm that gives this effective modulus
            // at 6.9 MPa (isothermal): 1/β_eff = 1/β_oil + ε p_atm / p_abs²
            let p_abs = BULK_MODULUS_QUOTE_PA + P_ATM_PA;
            let air = if after.entrained_air_fraction > 0.0 && after.bulk_modulus_pa == oil {
                after.entrained_air_fraction
            } else {
                ((1.0 / b - 1.0 / oil) * p_abs * p_abs / P_ATM_PA).max(0.0)
            };
            // the same effective modulus from air compressed polytropically
            // (n = 1.4): 1/β_eff = 1/β_oil + ε p_atm^(1/n) / (n p_abs^(1+1/n))
            const N: f64 = 1.4;
            let air_poly =
                ((1.0 / b - 1.0 / oil) * N * p_abs.powf(1.0 + 1.0 / N) / P_ATM_PA.powf(1.0 / N)).max(0.0);
            out.push(format!(
                "effective bulk modulus {:.0} MPa at {:.1} MPa ({:.0} % of the model's {:.0} MPa); \
                 entrained air at 1 atm, by volume: {:.2} % if it is compressed isothermally (the model's law), \
                 {:.2} % if polytropically (n = 1.4)",
                b * 1e-6,
                BULK_MODULUS_QUOTE_PA * 1e-6,
                100.0 * b / oil,
                oil * 1e-6,
                100.0 * air,
                100.0 * air_poly
            ));
            let lo = effective_bulk_modulus_pa(after, 1.0e6);
            let hi = effective_bulk_modulus_pa(after, 12.0e6);
            out.push(format!(
                "effective bulk modulus {:.0} MPa at 1 MPa, {:.0} MPa at 12 MPa",
                lo * 1e-6,
                hi * 1e-6
            ));
        }
        "supply-sag" => {
            let r = after.supply_sag_pa_per_m3_s;
            out.push(format!(
                "supply pressure sags {:.3} MPa per L/min drawn ({:.3e} Pa per m³/s); {:.2} MPa at 8 L/min",
                r * LPM_M3_S * 1e-6,
                r,
                r * 8.0 * LPM_M3_S * 1e-6
            ));
        }
        "valve-bandwidth" => {
            let w = after.spool_natural_freq_rad_s;
            out.push(format!(
                "spool natural frequency {:.1} Hz ({:.0} rad/s; the model had {:.1} Hz), damping ratio {:.2}",
                w / (2.0 * std::f64::consts::PI),
                w,
                before.spool_natural_freq_rad_s / (2.0 * std::f64::consts::PI),
                after.spool_damping_ratio
            ));
        }
        "leak-ext1" | "leak-ext2" | "leak-int" => {
            let e = match name {
                "leak-ext1" => Effect::LeakExt1,
                "leak-ext2" => Effect::LeakExt2,
                _ => Effect::LeakInt,
            };
            let k = e.read(after).first().copied().unwrap_or(0.0);
            let dp = match name {
                "leak-ext1" => mean_p_pa[0] - after.return_pressure_pa,
                "leak-ext2" => mean_p_pa[1] - after.return_pressure_pa,
                _ => mean_p_pa[0] - mean_p_pa[1],
            };
            let q = k * dp.signum() * dp.abs().sqrt();
            out.push(format!(
                "{:.3} L/min at the record's mean Δp of {:.2} MPa; {:.3} L/min at 6.9 MPa ({:.3e} m³/(s·√Pa), square-root law)",
                q / LPM_M3_S,
                dp * 1e-6,
                k * 6.9e6f64.sqrt() / LPM_M3_S,
                k
            ));
        }
        _ => {}
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn engineering_units_of_each_effect() {
        let base = ActuatorParams::default();
        let mean = [7.0e6, 6.8e6];
        // 13.28 % of free air compressed polytropically gives 474.1 MPa at 6.9 MPa
        let after = Effect::BulkModulus.apply(&base, &[474.129e6]);
        let l = describe("bulk-modulus", &base, &after, mean).join("\n");
        assert!(l.contains("effective bulk modulus 474 MPa at 6.9 MPa"), "{l}");
        assert!(l.contains("13.28 % if polytropically"), "{l}");
        let after = Effect::SpoolBias.apply(&base, &[-5.2e-6]);
        let l = describe("spool-bias", &base, &after, mean).join("\n");
        assert!(l.contains("-5.20 µm = -1.86 % of the spool stroke"), "{l}");
        let after = Effect::SupplySag.apply(&base, &[6.0e9]);
        let l = describe("supply-sag", &base, &after, mean).join("\n");
        assert!(l.contains("0.100 MPa per L/min"), "{l}");
        let after = Effect::LeakExt1.apply(&base, &[4.0e-9]);
        let l = describe("leak-ext1", &base, &after, mean).join("\n");
        // 4e-9 · √7e6 m³/s = 0.635 L/min
        assert!(
            l.contains("0.635 L/min at the record's mean Δp of 7.00 MPa"),
            "{l}"
        );
        let after = Effect::ValveBandwidth.apply(&base, &[316.0]);
        let l = describe("valve-bandwidth", &base, &after, mean).join("\n");
        assert!(l.contains("spool natural frequency 50.3 Hz"), "{l}");
        let after = Effect::SpringLoad.apply(&base, &[3.8e4, 0.296]);
        let l = describe("spring-load", &base, &after, mean).join("\n");
        assert!(l.contains("x = 0.2960 m, stiffness 38.00 kN/m"), "{l}");
        let after = Effect::FrictionAsymmetry.apply(&base, &[822.0]);
        let l = describe("friction-asymmetry", &base, &after, mean).join("\n");
        assert!(
            l.contains("retracting: static 1793 N, Coulomb 822 N, viscous 350 N·s/m"),
            "{l}"
        );
    }
}
