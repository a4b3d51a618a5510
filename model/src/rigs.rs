//! The in-repo plant rigs beside the thesis rig and the vertical lift
//! ([`ActuatorParams::vertical_lift`], [`Datasheet::vertical_lift`]): a
//! horizontal double-rod press, as its catalogue datasheet gives it and as
//! its nominal instance.

use crate::datasheet::{
    CylinderKind, CylinderSheet, Datasheet, HoseSheet, OilSheet, PositionSensorSheet, SupplySheet,
    TransducerLocation, TransducerSheet, ValveSheet,
};
use crate::params::{ActuatorParams, Friction};

impl Datasheet {
    /// A horizontal double-rod press as its datasheets give it: bore 50.5 mm,
    /// rod 32 mm, stroke 0.3 m, 27.5 kg moving; 0.55 m hoses of 12.7 mm each
    /// side; HLP 46 oil of 870 kg/m³ and 1.6 GPa; a valve of 32 L/min at 7 MPa
    /// (3.5 MPa per land) at 10 V over a 0.3 mm spool stroke, −90° at 130 Hz,
    /// null leakage at most 0.3 L/min at 21 MPa; a 21 MPa supply; transducers
    /// of 0-25 MPa, 16 bits, 8 kPa noise at the valve manifold; a position
    /// sensor of 2 µm resolution and 3 µm noise.
    pub fn press() -> Self {
        Datasheet {
            cylinder: CylinderSheet {
                kind: CylinderKind::DoubleRod,
                bore_m: 0.0505,
                rod_m: 0.032,
                stroke_m: 0.3,
                mounting_angle_deg: 0.0,
                moving_mass_kg: 27.5,
            },
            hoses: HoseSheet {
                inner_diameter_m: 0.0127,
                length_a_m: 0.55,
                length_b_m: 0.55,
                extra_volume_a_m3: 0.0,
                extra_volume_b_m3: 0.0,
            },
            oil: OilSheet::mineral(870.0, 1.6e9),
            valve: ValveSheet {
                rated_flow_l_min: 32.0,
                rated_flow_b_l_min: None,
                rated_pressure_drop_pa: 7.0e6,
                rated_signal_v: 10.0,
                spool_stroke_m: 3.0e-4,
                phase_90_hz: 130.0,
                null_leakage_l_min: 0.3,
            },
            supply: SupplySheet { pressure_pa: 21.0e6 },
            pressure_transducers: TransducerSheet {
                full_scale_pa: 25.0e6,
                adc_bits: 16,
                noise_pa: 8.0e3,
                location: TransducerLocation::Manifold,
                response_time_s: 0.0,
                zero_offset_max_pa: 50.0e3,
                span_error_max_fraction: 0.005,
            },
            position_sensor: PositionSensorSheet {
                resolution_m: 2.0e-6,
                noise_m: 3.0e-6,
            },
        }
    }
}

impl ActuatorParams {
    /// The press of [`Datasheet::press`] as its nominal instance: every
    /// datasheet fact derived ([`Datasheet::model`]; the null leakage at the
    /// catalogue's maximum), and what no datasheet gives assumed: the thesis
    /// rig's friction scaled to this cylinder (1.7 kN static, 1 kN Coulomb,
    /// Stribeck velocity 0.02 m/s, 700 N·s/m viscous), the thesis' C_d (0.6),
    /// spool damping (0.7), underlap (5 µm) and end stops. No load: the
    /// workpiece is the `press` scenario's.
    pub fn press() -> Self {
        let base = ActuatorParams {
            friction: Friction {
                static_n: 1.7e3,
                slip_n: 1.0e3,
                stribeck_velocity_m_s: 0.02,
                viscous_n_s_per_m: 700.0,
                ..Friction::default()
            },
            ..ActuatorParams::default()
        };
        Datasheet::press().model(&base)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_press_sheet_derives_its_nominal_instance() {
        let sheet = Datasheet::press();
        sheet.validate().expect("valid");
        let press = ActuatorParams::press();
        press.validate().expect("valid");
        // the sheet applied to the instance changes nothing: every derived field agrees
        assert_eq!(sheet.model(&press), press);
        // annulus of 50.5/32 mm: π/4·(0.0505² − 0.032²) = 1.19871e-3 m²
        assert!((press.piston_area_m2 - 1.198_713_946_89e-3).abs() < 1e-14);
        assert_eq!(press.rod_side_area_m2, None);
        // 0.55 m of 12.7 mm: 6.967e-5 m³ a side
        assert!((press.dead_volume_1_m3 - 6.967_227_837_59e-5).abs() < 1e-15);
        // 0.3 L/min at 21 MPa over both paths: C_L = 2.381e-13 m³/(s·Pa)
        assert!((press.valve_null_leakage_m3_s_pa - 0.3 / 60_000.0 / 21.0e6).abs() < 1e-27);
        assert!((press.spool_natural_freq_rad_s - 816.814_089_933).abs() < 1e-8);
        assert_eq!(
            (
                press.friction.static_n,
                press.friction.slip_n,
                press.friction.viscous_n_s_per_m
            ),
            (1.7e3, 1.0e3, 700.0)
        );
        // what the sheet does not give stays the instance's own
        let thesis_based = sheet.model(&ActuatorParams::default());
        assert_eq!(thesis_based.friction.static_n, 2.4e3);
        assert_eq!(thesis_based.piston_area_m2, press.piston_area_m2);
    }
}
