//! The sheets a [`Datasheet`](super::Datasheet) is made of, each field
//! declared once with its unit, range and doc (`schema::config_struct!`):
//! cylinder, hoses, oil, valve, supply, transducers and position sensor.

use schema::{int, num, Range};
use serde::{Deserialize, Serialize};

use crate::params::OilTemperature;

/// Which cylinder: a rod through both ends (one piston area) or a rod on one end.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum CylinderKind {
    /// A rod through both ends: both chambers push on the annulus π/4·(D² − d²).
    DoubleRod,
    /// A rod on one end: chamber 1 (port A, the cap side) pushes on π/4·D²,
    /// chamber 2 (port B) on the annulus π/4·(D² − d²).
    SingleRod,
}

impl schema::FieldType for CylinderKind {
    const KIND: schema::Kind = schema::Kind::Choice(&["double-rod", "single-rod"]);
}

schema::config_struct! {
    /// The cylinder and what it moves.
    #[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
    #[serde(deny_unknown_fields)]
    pub struct CylinderSheet {
        /// `double-rod` or `single-rod`.
        pub kind: CylinderKind,
        /// Bore (piston diameter) D, m.
        pub bore_m: f64 => ["m", num!("a bore", 1e-3, 2)],
        /// Rod diameter d, m.
        pub rod_m: f64 => ["m", Range::Stated("a rod diameter below 0.99 of the bore: from 0 m")],
        /// Stroke, m: the rod moves from 0 (retracted) to this.
        pub stroke_m: f64 => ["m", num!("a stroke", 1e-3, 20)],
        /// Angle of the direction of extension above the horizontal, degrees: 0
        /// horizontal, 90 vertical with extension lifting the load, −90 vertical
        /// with extension lowering it.
        pub mounting_angle_deg: f64 => ["degrees", num!("an angle", -90, 90)],
        /// Everything that moves with the rod (piston, rod, tool, payload), kg.
        pub moving_mass_kg: f64 => ["kg", num!("a mass", 1e-3, 1e6)],
    }
}

schema::config_struct! {
    /// The lines between the valve and the cylinder.
    #[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
    #[serde(deny_unknown_fields)]
    pub struct HoseSheet {
        /// Inner diameter of both hoses, m.
        pub inner_diameter_m: f64 => ["m", num!("a diameter", 1e-3, 0.2)],
        /// Length of the hose to port A (chamber 1), m.
        pub length_a_m: f64 => ["m", num!("a length", 0, 100)],
        /// Length of the hose to port B (chamber 2), m.
        pub length_b_m: f64 => ["m", num!("a length", 0, 100)],
        /// Further oil volume on the port-A side (manifold bores, the cylinder's
        /// end volume), m³. Default 0.
        #[serde(default)]
        pub extra_volume_a_m3: f64 => ["m³", num!("a volume", 0, 1)],
        /// Further oil volume on the port-B side, m³. Default 0.
        #[serde(default)]
        pub extra_volume_b_m3: f64 => ["m³", num!("a volume", 0, 1)],
    }
}

schema::config_struct! {
    /// The oil.
    #[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
    #[serde(deny_unknown_fields)]
    pub struct OilSheet {
        /// Density, kg/m³.
        pub density_kg_m3: f64 => ["kg/m³", num!("a density", 500, 2000)],
        /// Bulk modulus of the oil without air, Pa (commissioning identifies the
        /// effective one, with the hoses and the air).
        pub bulk_modulus_pa: f64 => ["Pa", num!("a bulk modulus", 1e7, 1e10)],
        /// Kinematic viscosity at 40 °C, mm²/s (the ISO VG grade). Default 46 (HLP 46).
        #[serde(default = "default_viscosity_40c")]
        pub viscosity_40c_mm2_s: f64 => ["mm²/s", num!("a kinematic viscosity", 1, 10000)],
        /// Kinematic viscosity at 100 °C, mm²/s, where the oil's data sheet
        /// gives it. Absent: its grade's at viscosity index 100 (6.8 for an HLP 46), and the
        /// oil's change with temperature is known less well
        /// ([`crate::params::OilTemperature::law_uncertainty`]).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        pub viscosity_100c_mm2_s: Option<f64> => ["mm²/s", num!("a kinematic viscosity", 0.5, 10000)],
        /// Relative change of the bulk modulus per kelvin, 1/K. Default −0.0045 (mineral oil).
        #[serde(default = "default_bulk_modulus_per_k")]
        pub bulk_modulus_per_k: f64 => ["(1/K)", num!("a relative change per kelvin", -0.02, 0)],
        /// The lowest oil temperature the rig runs at, °C. Default 20.
        #[serde(default = "default_operating_min_c")]
        pub operating_min_c: f64 => ["°C", num!("an oil temperature", -40, 150)],
        /// The highest oil temperature the rig runs at, °C. Default 60.
        #[serde(default = "default_operating_max_c")]
        pub operating_max_c: f64 => ["°C", num!("an oil temperature", -40, 150)],
    }
}

impl OilSheet {
    /// A mineral oil of density `density_kg_m3` (kg/m³) and bulk modulus
    /// `bulk_modulus_pa` (Pa), with the defaults' viscosities and temperature coefficient.
    pub fn mineral(density_kg_m3: f64, bulk_modulus_pa: f64) -> OilSheet {
        OilSheet {
            density_kg_m3,
            bulk_modulus_pa,
            viscosity_40c_mm2_s: default_viscosity_40c(),
            viscosity_100c_mm2_s: None,
            bulk_modulus_per_k: default_bulk_modulus_per_k(),
            operating_min_c: default_operating_min_c(),
            operating_max_c: default_operating_max_c(),
        }
    }
}

fn default_viscosity_40c() -> f64 {
    OilTemperature::default().viscosity_40c_mm2_s
}

fn default_bulk_modulus_per_k() -> f64 {
    OilTemperature::default().bulk_modulus_per_k
}

fn default_operating_min_c() -> f64 {
    OilTemperature::default().operating_min_c
}

fn default_operating_max_c() -> f64 {
    OilTemperature::default().operating_max_c
}

schema::config_struct! {
    /// The servovalve, from its catalogue sheet.
    #[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
    #[serde(deny_unknown_fields)]
    pub struct ValveSheet {
        /// Rated flow of port A at the rated signal and rated valve drop, L/min.
        pub rated_flow_l_min: f64 => ["L/min", num!("a flow", 0.01, 1e5)],
        /// Rated flow of port B, L/min, for a valve whose port B is matched to a
        /// single-rod cylinder's area ratio. Absent: port A's.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        pub rated_flow_b_l_min: Option<f64> => ["L/min", num!("a flow", 0.01, 1e5)],
        /// Valve pressure drop at which the rated flow is given (both metering
        /// lands together, e.g. 7 MPa = 3.5 MPa per land), Pa.
        pub rated_pressure_drop_pa: f64 => [
            "Pa",
            num!("a pressure drop", 1e4, 1e8, "(both lands together)")
        ],
        /// Rated command signal, V.
        pub rated_signal_v: f64 => ["V", num!("a signal", 1e-3, 1e3)],
        /// Spool stroke at the rated signal, m.
        pub spool_stroke_m: f64 => ["m", num!("a spool stroke", 1e-6, 0.05)],
        /// Frequency at which the valve's phase lag reaches 90°, Hz.
        pub phase_90_hz: f64 => ["Hz", num!("a frequency", 0.1, 1e4)],
        /// Internal (null) leakage with the ports blocked, at the supply pressure,
        /// L/min. Default 0: a critical-centre valve (commissioning identifies it).
        #[serde(default)]
        pub null_leakage_l_min: f64 => ["L/min", num!("a flow", 0, 100)],
    }
}

schema::config_struct! {
    /// The hydraulic supply.
    #[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
    #[serde(deny_unknown_fields)]
    pub struct SupplySheet {
        /// Supply pressure at zero flow (the pump's setting), Pa.
        pub pressure_pa: f64 => ["Pa", num!("a pressure", 1e5, 1e9)],
    }
}

schema::config_struct! {
    /// The two chamber-pressure transducers and their DAQ channels.
    #[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
    #[serde(deny_unknown_fields)]
    pub struct TransducerSheet {
        /// Full scale (the range is 0 to this), Pa.
        pub full_scale_pa: f64 => ["Pa", num!("a full scale", 1e5, 1e9)],
        /// ADC resolution over the full scale, bits.
        pub adc_bits: u32 => ["bits", int!(1, 24)],
        /// Noise of a reading (standard deviation), Pa.
        pub noise_pa: f64 => ["Pa", num!("a noise", 0, 1e7)],
        /// Where they sit. Default: at the cylinder's ports.
        #[serde(default)]
        pub location: TransducerLocation,
        /// Their 10-90 % response time, the datasheet's maximum, s (0: not given, the default).
        #[serde(default)]
        pub response_time_s: f64 => ["s", num!("a time", 0, 1)],
        /// Each one's zero offset, the datasheet's maximum, Pa (0: not given, the default).
        #[serde(default)]
        pub zero_offset_max_pa: f64 => ["Pa", num!("an offset", 0, 1e7)],
        /// Each one's span error, the datasheet's maximum, as a fraction of the
        /// reading (0.005: 0.5 %; 0: not given, the default).
        #[serde(default)]
        pub span_error_max_fraction: f64 => ["", num!("a fraction", 0, 0.5)],
    }
}

/// Where the pressure transducers sit.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum TransducerLocation {
    /// At the cylinder's ports (`"cylinder-ports"`): they read the chambers.
    #[default]
    CylinderPorts,
    /// At the valve's manifold (`"manifold"`): they read a chamber plus the
    /// hose's drop, which grows with the flow.
    Manifold,
}

impl schema::FieldType for TransducerLocation {
    const KIND: schema::Kind = schema::Kind::Choice(&["cylinder-ports", "manifold"]);
}

impl TransducerSheet {
    /// The longest first-order lag the response time allows, s: a first-order
    /// lag τ rises from 10 to 90 % in τ·ln 9. `None` when no response time is given.
    pub fn lag_bound_s(&self) -> Option<f64> {
        (self.response_time_s > 0.0).then(|| self.response_time_s / 9f64.ln())
    }
}

schema::config_struct! {
    /// The rod's position sensor.
    #[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
    #[serde(deny_unknown_fields)]
    pub struct PositionSensorSheet {
        /// Resolution (one count), m.
        pub resolution_m: f64 => ["m", num!("a resolution", 1e-9, 1e-2)],
        /// Noise of a reading (standard deviation), m.
        pub noise_m: f64 => ["m", num!("a noise", 0, 1e-2)],
    }
}
