//! Rig instances drawn over a datasheet's tolerances: what one real rig of a
//! catalogue build differs by from its nominal instance (the valve's rated
//! flow, null leakage and bandwidth, the oil's stiffness, the friction, the
//! hoses, the mass), and what its installation adds (transducer lag, offsets
//! and span errors, the line's drop, the pump's ripple). Seeded and
//! deterministic ([`crate::rng::Rng`]).

use serde::Serialize;

use crate::datasheet::{Datasheet, TransducerLocation};
use crate::params::{viscosity_100c_of_grade, ActuatorParams, STATED_VISCOSITY_100C_TOLERANCE};
use crate::rng::Rng;
use crate::sensors::SensorParams;

/// A rig to draw instances of: its catalogue datasheet, its nominal instance
/// (the datasheet's facts derived, the rest assumed) and its nominal sensors.
#[derive(Debug, Clone, PartialEq)]
pub struct NominalRig {
    /// Short name (`press`, `lift`).
    pub name: &'static str,
    /// What the catalogues give, as a user writes it in `[datasheet]`.
    pub datasheet: Datasheet,
    /// The nominal instance: [`Datasheet::model`] of the datasheet.
    pub model: ActuatorParams,
    /// The nominal sensors: [`Datasheet::sensors`] of the datasheet.
    pub sensors: SensorParams,
}

impl NominalRig {
    /// The double-rod press ([`Datasheet::press`], [`ActuatorParams::press`]),
    /// its oil's data sheet giving ν at 40 and 100 °C.
    pub fn press() -> Self {
        let mut datasheet = Datasheet::press();
        datasheet.oil.viscosity_100c_mm2_s = Some(viscosity_100c_of_grade(datasheet.oil.viscosity_40c_mm2_s));
        NominalRig {
            name: "press",
            model: datasheet.model(&ActuatorParams::press()),
            sensors: datasheet.sensors(&SensorParams::default()),
            datasheet,
        }
    }

    /// The vertical single-rod lift ([`Datasheet::vertical_lift`]) as a
    /// catalogue gives it: its valve's null leakage at most 0.3 L/min at
    /// 21 MPa, its transducers at the valve manifold, its oil's data sheet
    /// giving ν at 40 and 100 °C.
    pub fn lift() -> Self {
        let mut datasheet = Datasheet::vertical_lift();
        datasheet.valve.null_leakage_l_min = 0.3;
        datasheet.oil.viscosity_100c_mm2_s = Some(viscosity_100c_of_grade(datasheet.oil.viscosity_40c_mm2_s));
        datasheet.pressure_transducers.location = TransducerLocation::Manifold;
        NominalRig {
            name: "lift",
            model: datasheet.model(&ActuatorParams::vertical_lift()),
            sensors: datasheet.sensors(&SensorParams::default()),
            datasheet,
        }
    }
}

/// One drawn quantity: its name (the field it sets), unit, nominal value,
/// the range it was drawn from and the value drawn.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Drawn {
    /// The field it sets (`model.mass_kg`, `sensors.pressure_lag_s`, `sim.supply_ripple_hz`).
    pub name: String,
    /// Its unit.
    pub unit: &'static str,
    /// The nominal instance's value (0 where the nominal rig has none, e.g. a lag or a ripple).
    pub nominal: f64,
    /// The lower end of the range it was drawn from.
    pub low: f64,
    /// The upper end of the range it was drawn from.
    pub high: f64,
    /// The value drawn, uniform in [low, high).
    pub value: f64,
}

/// The tolerances instances are drawn over: relative ones as ± fractions of
/// the nominal value, absolute ones as ranges.
pub mod tolerance {
    /// Rated flow (each port's area gradient), ± fraction.
    pub const RATED_FLOW: f64 = 0.10;
    /// Bulk modulus at the oil law's reference temperature, Pa.
    pub const BULK_MODULUS_PA: (f64, f64) = (1.1e9, 1.6e9);
    /// Static, Coulomb and viscous friction, each, ± fraction.
    pub const FRICTION: f64 = 0.25;
    /// Dead volumes, each side, ± fraction.
    pub const DEAD_VOLUME: f64 = 0.15;
    /// Spool natural frequency, ± fraction.
    pub const SPOOL_BANDWIDTH: f64 = 0.10;
    /// Moving mass, ± fraction.
    pub const MASS: f64 = 0.08;
    /// Transducers' first-order lag, s.
    pub const PRESSURE_LAG_S: (f64, f64) = (0.2e-3, 1.0e-3);
    /// Transducers' zero offsets, each, Pa.
    pub const PRESSURE_OFFSET_PA: (f64, f64) = (-50e3, 50e3);
    /// Transducers' span errors, each, relative.
    pub const PRESSURE_SPAN: (f64, f64) = (-0.005, 0.005);
    /// Laminar resistance of the line between manifold and chamber, Pa/(m³/s)
    /// (0.08-0.21 MPa at 50 L/min).
    pub const LINE_RESISTANCE_PA_S_PER_M3: (f64, f64) = (1.0e8, 2.5e8);
    /// The pump's ripple, fraction of the supply pressure.
    pub const SUPPLY_RIPPLE_FRACTION: (f64, f64) = (0.002, 0.006);
    /// The pump's ripple frequency, Hz (pistons × shaft speed).
    pub const SUPPLY_RIPPLE_HZ: (f64, f64) = (200.0, 300.0);
}

/// One rig instance: the simulated rig, its sensors and pump, and what was drawn.
#[derive(Debug, Clone, PartialEq)]
pub struct Instance {
    /// The seed it was drawn with.
    pub seed: u64,
    /// The rig's parameters (laminar terms at the oil law's reference temperature).
    pub rig: ActuatorParams,
    /// Its sensors, with the installation's lag, offsets, span errors and line drop.
    pub sensors: SensorParams,
    /// The pump's ripple, fraction of the supply pressure.
    pub supply_ripple_fraction: f64,
    /// The pump's ripple frequency, Hz.
    pub supply_ripple_hz: f64,
    drawn: Vec<Drawn>,
}

/// Draws uniformly in [low, high) and records the draw.
struct Drawer {
    rng: Rng,
    drawn: Vec<Drawn>,
}

impl Drawer {
    fn range(&mut self, name: &str, unit: &'static str, nominal: f64, (low, high): (f64, f64)) -> f64 {
        let value = self.rng.uniform_in(low, high);
        self.drawn.push(Drawn {
            name: name.to_string(),
            unit,
            nominal,
            low,
            high,
            value,
        });
        value
    }

    fn relative(&mut self, name: &str, unit: &'static str, nominal: f64, spread: f64) -> f64 {
        self.range(
            name,
            unit,
            nominal,
            (nominal * (1.0 - spread), nominal * (1.0 + spread)),
        )
    }
}

impl Instance {
    /// Draws one instance of `nominal` from `seed`: the rated flow ±10 % (each
    /// port's area gradient), the valve's null leakage uniform from 0 to the
    /// catalogue's maximum (a laminar coefficient at the oil law's reference
    /// temperature; the simulator scales it with the viscosity), the bulk
    /// modulus in 1.1-1.6 GPa, static, Coulomb and viscous friction ±25 %
    /// each, dead volumes ±15 % each, the spool's bandwidth ±10 %, the mass
    /// ±8 %; and its installation: the transducers' lag 0.2-1 ms, offsets
    /// ±50 kPa and span errors ±0.5 % each, the line's resistance and the
    /// pump's ripple ([`tolerance`]); last, where the oil's data sheet gives
    /// its ν at 100 °C, the batch's within
    /// [`STATED_VISCOSITY_100C_TOLERANCE`] of it (the draws before are
    /// those of an oil without it).
    pub fn draw(nominal: &NominalRig, seed: u64) -> Instance {
        use tolerance as tol;
        let mut d = Drawer {
            rng: Rng::new(seed ^ 0x1D57_A9C3_0F4B_2E61),
            drawn: Vec::new(),
        };
        let n = &nominal.model;
        let mut rig = n.clone();
        rig.area_gradient_m2_per_m = d.relative(
            "model.area_gradient_m2_per_m",
            "m²/m",
            n.area_gradient_m2_per_m,
            tol::RATED_FLOW,
        );
        if let Some(wb) = n.area_gradient_b_m2_per_m {
            rig.area_gradient_b_m2_per_m =
                Some(d.relative("model.area_gradient_b_m2_per_m", "m²/m", wb, tol::RATED_FLOW));
        }
        rig.valve_null_leakage_m3_s_pa = d.range(
            "model.valve_null_leakage_m3_s_pa",
            "m³/(s·Pa)",
            n.valve_null_leakage_m3_s_pa,
            (0.0, n.valve_null_leakage_m3_s_pa),
        );
        rig.bulk_modulus_pa = d.range(
            "model.bulk_modulus_pa",
            "Pa",
            n.bulk_modulus_pa,
            tol::BULK_MODULUS_PA,
        );
        let f = &n.friction;
        rig.friction.static_n = d.relative("model.friction.static_n", "N", f.static_n, tol::FRICTION);
        rig.friction.slip_n = d.relative("model.friction.slip_n", "N", f.slip_n, tol::FRICTION);
        // stiction is never below the sliding friction
        rig.friction.static_n = rig.friction.static_n.max(rig.friction.slip_n);
        rig.friction.viscous_n_s_per_m = d.relative(
            "model.friction.viscous_n_s_per_m",
            "N·s/m",
            f.viscous_n_s_per_m,
            tol::FRICTION,
        );
        rig.dead_volume_1_m3 = d.relative(
            "model.dead_volume_1_m3",
            "m³",
            n.dead_volume_1_m3,
            tol::DEAD_VOLUME,
        );
        rig.dead_volume_2_m3 = d.relative(
            "model.dead_volume_2_m3",
            "m³",
            n.dead_volume_2_m3,
            tol::DEAD_VOLUME,
        );
        rig.spool_natural_freq_rad_s = d.relative(
            "model.spool_natural_freq_rad_s",
            "rad/s",
            n.spool_natural_freq_rad_s,
            tol::SPOOL_BANDWIDTH,
        );
        rig.mass_kg = d.relative("model.mass_kg", "kg", n.mass_kg, tol::MASS);
        let s = &nominal.sensors;
        let mut sensors = *s;
        sensors.pressure_lag_s = d.range(
            "sensors.pressure_lag_s",
            "s",
            s.pressure_lag_s,
            tol::PRESSURE_LAG_S,
        );
        for i in 0..2 {
            sensors.pressure_offset_pa[i] = d.range(
                &format!("sensors.pressure_offset_pa[{i}]"),
                "Pa",
                s.pressure_offset_pa[i],
                tol::PRESSURE_OFFSET_PA,
            );
            sensors.pressure_gain_error[i] = d.range(
                &format!("sensors.pressure_gain_error[{i}]"),
                "1",
                s.pressure_gain_error[i],
                tol::PRESSURE_SPAN,
            );
        }
        sensors.line_resistance_pa_s_per_m3 = d.range(
            "sensors.line_resistance_pa_s_per_m3",
            "Pa/(m³/s)",
            s.line_resistance_pa_s_per_m3,
            tol::LINE_RESISTANCE_PA_S_PER_M3,
        );
        let supply_ripple_fraction = d.range(
            "sim.supply_ripple_fraction",
            "1",
            0.0,
            tol::SUPPLY_RIPPLE_FRACTION,
        );
        let supply_ripple_hz = d.range("sim.supply_ripple_hz", "Hz", 0.0, tol::SUPPLY_RIPPLE_HZ);
        if let Some(nu100) = n.oil_temperature.viscosity_100c_mm2_s {
            rig.oil_temperature.viscosity_100c_mm2_s = Some(d.relative(
                "model.oil_temperature.viscosity_100c_mm2_s",
                "mm²/s",
                nu100,
                STATED_VISCOSITY_100C_TOLERANCE,
            ));
        }
        Instance {
            seed,
            rig,
            sensors,
            supply_ripple_fraction,
            supply_ripple_hz,
            drawn: d.drawn,
        }
    }

    /// What was drawn, in the order drawn: each quantity's field, unit,
    /// nominal value, range and value (for a truth file).
    pub fn describe(&self) -> &[Drawn] {
        &self.drawn
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn draws_are_within_their_tolerances_and_differ_between_seeds() {
        for nominal in [NominalRig::press(), NominalRig::lift()] {
            nominal.model.validate().expect("nominal");
            // the nominal instance is what its datasheet derives
            assert_eq!(nominal.datasheet.model(&nominal.model), nominal.model);
            let a = Instance::draw(&nominal, 7);
            a.rig.validate().expect("a valid rig");
            a.sensors.validate().expect("valid sensors");
            let ports = usize::from(nominal.model.area_gradient_b_m2_per_m.is_some());
            assert_eq!(a.describe().len(), 19 + ports, "{:#?}", a.describe());
            for d in a.describe() {
                assert!(d.low <= d.value && d.value <= d.high, "{d:?}");
            }
            let w = a.rig.area_gradient_m2_per_m / nominal.model.area_gradient_m2_per_m;
            assert!((0.9..=1.1).contains(&w), "{w}");
            assert!((1.1e9..1.6e9).contains(&a.rig.bulk_modulus_pa));
            // null leakage from 0 to 0.3 L/min at 21 MPa
            let cl_max = 0.3 / 60_000.0 / 21.0e6;
            assert!((0.0..cl_max * (1.0 + 1e-12)).contains(&a.rig.valve_null_leakage_m3_s_pa));
            assert!((a.rig.mass_kg / nominal.model.mass_kg - 1.0).abs() <= 0.08);
            assert!((2e-4..1e-3).contains(&a.sensors.pressure_lag_s));
            assert!(a.sensors.pressure_offset_pa.iter().all(|o| o.abs() <= 50e3));
            assert!(a.sensors.pressure_gain_error.iter().all(|g| g.abs() <= 0.005));
            assert!((200.0..300.0).contains(&a.supply_ripple_hz));
            // the oil's data sheet gives ν at 100 °C; the batch lies within ±7 % of it
            let nu100 = a.rig.oil_temperature.viscosity_100c_mm2_s.expect("stated");
            assert!((nu100 / 6.8 - 1.0).abs() <= 0.07, "{nu100}");
            assert_eq!(nominal.datasheet.oil.viscosity_100c_mm2_s, Some(6.8));
            // what is not drawn stays nominal
            assert_eq!(a.rig.piston_area_m2, nominal.model.piston_area_m2);
            assert_eq!(a.rig.supply_pressure_pa, nominal.model.supply_pressure_pa);
            assert_eq!(a.sensors.pressure_noise_pa, nominal.sensors.pressure_noise_pa);
            // deterministic per seed, different between seeds, in every drawn value
            assert_eq!(a, Instance::draw(&nominal, 7));
            let b = Instance::draw(&nominal, 8);
            for (x, y) in a.describe().iter().zip(b.describe()) {
                assert_ne!(x.value, y.value, "{}", x.name);
            }
        }
    }

    #[test]
    fn an_oil_without_its_viscosity_at_100_c_draws_the_same_rig_without_the_batch() {
        // the batch's ν at 100 °C is drawn last: without it, every other draw is the same
        let stated = NominalRig::press();
        let mut unstated = NominalRig::press();
        unstated.datasheet.oil.viscosity_100c_mm2_s = None;
        unstated.model.oil_temperature.viscosity_100c_mm2_s = None;
        let (a, b) = (Instance::draw(&stated, 3), Instance::draw(&unstated, 3));
        assert_eq!(a.describe().len(), b.describe().len() + 1);
        assert_eq!(&a.describe()[..b.describe().len()], b.describe());
        assert_eq!(
            a.describe().last().map(|d| d.name.as_str()),
            Some("model.oil_temperature.viscosity_100c_mm2_s")
        );
        assert_eq!(b.rig.oil_temperature.viscosity_100c_mm2_s, None);
        // the batch's ν at 100 °C is the instance's truth; the sheet keeps its own
        let nu100 = a.rig.oil_temperature.viscosity_100c_mm2_s.expect("drawn");
        assert_ne!(nu100, 6.8);
        assert_eq!(stated.datasheet.oil.viscosity_100c_mm2_s, Some(6.8));
    }

    #[test]
    fn the_spread_over_many_draws_fills_the_tolerance() {
        let nominal = NominalRig::press();
        let masses: Vec<f64> = (0..400)
            .map(|s| Instance::draw(&nominal, s).rig.mass_kg)
            .collect();
        let lo = masses.iter().cloned().fold(f64::MAX, f64::min);
        let hi = masses.iter().cloned().fold(f64::MIN, f64::max);
        // 27.5 kg ± 8 %: 25.3-29.7 kg, reached to within 0.1 kg by 400 draws
        assert!((25.3..25.4).contains(&lo) && hi > 29.6 && hi <= 29.7, "{lo} {hi}");
    }
}
