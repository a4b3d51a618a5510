//! Unit helpers. Everything inside leakwatch is SI (m, s, Pa, m³/s, N, V);
//! these convert the few engineering units users type or read.

/// Cubic metres per second in one litre per minute (1 L/min = 1e-3 m³ / 60 s).
pub const M3_S_PER_LPM: f64 = 1.0e-3 / 60.0;

/// Pascal in one pound per square inch.
pub const PA_PER_PSI: f64 = 6_894.757_293_168;

/// Converts a flow in litres per minute to m³/s.
pub fn lpm_to_m3_s(flow_lpm: f64) -> f64 {
    flow_lpm * M3_S_PER_LPM
}

/// Converts a flow in m³/s to litres per minute.
pub fn m3_s_to_lpm(flow_m3_s: f64) -> f64 {
    flow_m3_s / M3_S_PER_LPM
}

/// Converts a pressure in MPa to Pa.
pub fn mpa_to_pa(pressure_mpa: f64) -> f64 {
    pressure_mpa * 1.0e6
}

/// Signed square root: `sgn(v) * sqrt(|v|)`, so an orifice whose pressure drop
/// reverses gives back-flow instead of NaN.
#[inline]
pub fn signed_sqrt(v: f64) -> f64 {
    if v >= 0.0 {
        v.sqrt()
    } else {
        -(-v).sqrt()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lpm_round_trip_and_reference_value() {
        assert!((lpm_to_m3_s(1.0) - 1.6667e-5).abs() < 1e-9);
        for q in [0.0, 0.05, 0.5, 33.0] {
            assert!((m3_s_to_lpm(lpm_to_m3_s(q)) - q).abs() <= 1e-12 * q.max(1.0));
        }
        assert!((2000.0 * PA_PER_PSI - 13.79e6).abs() < 1e4);
    }

    #[test]
    fn signed_sqrt_is_odd() {
        assert_eq!(signed_sqrt(4.0), 2.0);
        assert_eq!(signed_sqrt(-9.0), -3.0);
        assert_eq!(signed_sqrt(0.0), 0.0);
    }
}
