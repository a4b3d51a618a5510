//! Sensor models of the rig (docs/model.md#sensors): optical encoder, pressure
//! transducers through a 12-bit ADC, spool position and load cell.

use schema::{int, num};
use serde::{Deserialize, Serialize};

use crate::rng::Rng;
use crate::sensor_fault::Distortion;

schema::config_struct! {
    /// Sensor characteristics of the simulated rig.
    #[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
    #[serde(default, deny_unknown_fields)]
    pub struct SensorParams {
        /// Encoder resolution (one count), m.
        pub encoder_resolution_m: f64 = 3.0e-5 => ["m", num!("a resolution", 1e-9, 1e-2)],
        /// Standard deviation of the position sensor's noise beyond its
        /// quantisation, m (0: an encoder that only counts, as on the thesis rig).
        pub position_noise_m: f64 = 0.0 => ["m", num!("a noise", 0, 1e-2)],
        /// Full scale of the pressure channels (0 to this), Pa.
        pub pressure_full_scale_pa: f64 = 20.7e6 => ["Pa", num!("a full scale", 1e5, 1e9)],
        /// ADC resolution of every analogue channel, bits.
        pub adc_bits: u32 = 12 => ["bits", int!(1, 24)],
        /// Standard deviation of the pressure transducer noise, Pa.
        pub pressure_noise_pa: f64 = 5.0e3 => ["Pa", num!("a noise", 0, 1e8)],
        /// Full scale of the spool position channel (±), m.
        pub spool_full_scale_m: f64 = 3.5e-4 => ["m", num!("a full scale", 1e-6, 0.1)],
        /// Standard deviation of the spool position noise, m.
        pub spool_noise_m: f64 = 2.0e-7 => ["m", num!("a noise", 0, 1e-2)],
        /// Full scale of the load cell (±), N.
        pub load_cell_full_scale_n: f64 = 22.0e3 => ["N", num!("a full scale", 1, 1e8)],
        /// Standard deviation of the load cell noise, N.
        pub load_cell_noise_n: f64 = 5.0 => ["N", num!("a noise", 0, 1e7)],
        /// Whether to add noise and quantisation at all (false gives the true states).
        pub enabled: bool = true,
        /// Zero offsets of the p1 and p2 transducers, Pa (an installation's; 0 by default).
        pub pressure_offset_pa: [f64; 2] = [0.0; 2] => ["Pa", num!("offsets", -1e7, 1e7)],
        /// Span errors of the p1 and p2 transducers, relative (0.005: reads 0.5 % high).
        pub pressure_gain_error: [f64; 2] = [0.0; 2] => ["", num!("span errors", -0.5, 0.5)],
        /// The largest zero offset of each pressure transducer, Pa (the datasheet's;
        /// 0: not given): `commission` holds the misreading it fits within it, and
        /// the detector names a standing offset past what a sound transducer may
        /// read off (this plus the span error times the reading) where that is
        /// under 0.5 % of the range.
        pub pressure_zero_offset_max_pa: f64 = 0.0 => ["Pa", num!("an offset", 0, 1e7)],
        /// The largest span error of each pressure transducer, as a fraction of
        /// the reading (the datasheet's; 0.005: 0.5 %; 0: not given): with the zero
        /// offset, what a sound transducer may read off.
        pub pressure_span_error_max: f64 = 0.0 => ["", num!("a fraction", 0, 0.5)],
        /// Time constant of both transducers' first-order lag, s (0: none).
        pub pressure_lag_s: f64 = 0.0 => ["s", num!("a time constant", 0, 1)],
        /// Laminar resistance of the line between the valve manifold, where the
        /// transducers sit, and each chamber, Pa/(m³/s) (0: transducers at the
        /// cylinder ports): the manifold reads p1 + R·Q1 and p2 − R·Q2, Q the valve's flows.
        pub line_resistance_pa_s_per_m3: f64 = 0.0 => ["Pa/(m³/s)", num!("a resistance", 0, 1e13)],
        /// Standard deviation of the DAQ's sample instants about their grid, s
        /// (0: none): every channel of a sample is read at t + δ, δ drawn
        /// normal, while the sample is stamped t.
        pub sample_jitter_s: f64 = 0.0 => ["s", num!("a time", 0, 1e-3)],
    }
}

impl SensorParams {
    /// Checks every field against its declared range, naming the first bad one
    /// (`sensors.<field>`) with its range and unit.
    pub fn validate(&self) -> Result<(), crate::params::InvalidParam> {
        Ok(self.check_ranges("sensors")?)
    }

    /// The plant rigs' sensors (plant_dev's datasheets): a position sensor
    /// of 2 µm counts with 3 µm noise, pressure transducers over 0-25 MPa
    /// through 16 bits with 8 kPa noise; no installation effects, no jitter.
    pub fn plant() -> Self {
        SensorParams {
            encoder_resolution_m: 2e-6,
            position_noise_m: 3e-6,
            pressure_full_scale_pa: 25e6,
            adc_bits: 16,
            pressure_noise_pa: 8e3,
            ..SensorParams::default()
        }
    }

    /// Ideal sensors: measurements equal the true states.
    pub fn ideal() -> Self {
        SensorParams {
            enabled: false,
            ..SensorParams::default()
        }
    }

    /// One ADC step of the pressure channels, Pa.
    pub fn pressure_lsb_pa(&self) -> f64 {
        self.pressure_full_scale_pa / ((1u64 << self.adc_bits) - 1) as f64
    }

    /// The standard deviation of the pressure measurement error (noise plus
    /// quantisation, LSB/√12), Pa.
    pub fn pressure_sigma_pa(&self) -> f64 {
        let q = self.pressure_lsb_pa();
        (self.pressure_noise_pa.powi(2) + q * q / 12.0).sqrt()
    }

    /// The standard deviation of the position measurement error (noise plus
    /// quantisation, count/√12), m.
    pub fn position_sigma_m(&self) -> f64 {
        let q = self.encoder_resolution_m;
        (self.position_noise_m.powi(2) + q * q / 12.0).sqrt()
    }

    /// Position reading of true position `x_m`, m: its noise (drawn only when
    /// there is any, so a rig without keeps its random sequence), then the count.
    #[inline]
    pub fn encoder(&self, x_m: f64, rng: &mut Rng) -> f64 {
        self.encoder_distorted(x_m, Distortion::NONE, rng)
    }

    /// [`SensorParams::encoder`] of a faulty transducer, m: the distortion's gain
    /// and offset before the noise, its spike after it, then the count (with
    /// ideal sensors: the true position distorted).
    #[inline]
    pub fn encoder_distorted(&self, x_m: f64, d: Distortion, rng: &mut Rng) -> f64 {
        let x = d.before_noise(x_m);
        if !self.enabled {
            return x + d.spike_si;
        }
        let x = if self.position_noise_m > 0.0 {
            x + self.position_noise_m * rng.normal()
        } else {
            x
        };
        ((x + d.spike_si) / self.encoder_resolution_m).round() * self.encoder_resolution_m
    }

    /// Quantises `value` over [lo, hi] with this ADC.
    #[inline]
    fn adc(&self, value: f64, lo: f64, hi: f64) -> f64 {
        let levels = ((1u64 << self.adc_bits) - 1) as f64;
        let code = ((value - lo) / (hi - lo) * levels).round().clamp(0.0, levels);
        lo + code / levels * (hi - lo)
    }

    /// Pressure reading of true pressure `p_pa`, Pa.
    #[inline]
    pub fn pressure(&self, p_pa: f64, rng: &mut Rng) -> f64 {
        if !self.enabled {
            return p_pa;
        }
        self.adc(
            p_pa + self.pressure_noise_pa * rng.normal(),
            0.0,
            self.pressure_full_scale_pa,
        )
    }

    /// Reading of channel `ch` (0: p1, 1: p2) for the pressure `p_pa` at the
    /// transducer, Pa: its span error and offset, then noise and the ADC.
    #[inline]
    pub fn pressure_channel(&self, ch: usize, p_pa: f64, rng: &mut Rng) -> f64 {
        self.pressure_channel_distorted(ch, p_pa, Distortion::NONE, rng)
    }

    /// [`SensorParams::pressure_channel`] of a faulty transducer, Pa: the
    /// installation's span error and offset, the distortion's gain and offset,
    /// the noise, the distortion's spike, then the ADC (with ideal sensors: the
    /// pressure at the transducer distorted).
    #[inline]
    pub fn pressure_channel_distorted(&self, ch: usize, p_pa: f64, d: Distortion, rng: &mut Rng) -> f64 {
        if !self.enabled {
            return d.before_noise(p_pa) + d.spike_si;
        }
        let p = d.before_noise(p_pa * (1.0 + self.pressure_gain_error[ch]) + self.pressure_offset_pa[ch]);
        self.adc(
            p + self.pressure_noise_pa * rng.normal() + d.spike_si,
            0.0,
            self.pressure_full_scale_pa,
        )
    }

    /// Whether any installation effect (offset, span error, lag, line) is set.
    pub fn has_installation_effects(&self) -> bool {
        self.pressure_offset_pa != [0.0; 2]
            || self.pressure_gain_error != [0.0; 2]
            || self.pressure_lag_s > 0.0
            || self.line_resistance_pa_s_per_m3 > 0.0
    }

    /// Spool position reading, m.
    #[inline]
    pub fn spool(&self, x_sp_m: f64, rng: &mut Rng) -> f64 {
        if !self.enabled {
            return x_sp_m;
        }
        let fs = self.spool_full_scale_m;
        self.adc(x_sp_m + self.spool_noise_m * rng.normal(), -fs, fs)
    }

    /// Load cell reading of true load `f_n`, N.
    #[inline]
    pub fn load_cell(&self, f_n: f64, rng: &mut Rng) -> f64 {
        if !self.enabled {
            return f_n;
        }
        let fs = self.load_cell_full_scale_n;
        self.adc(f_n + self.load_cell_noise_n * rng.normal(), -fs, fs)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_position_sensors_noise_is_drawn_and_counted_in_its_sigma() {
        let s = SensorParams {
            encoder_resolution_m: 2e-6,
            position_noise_m: 3e-6,
            ..SensorParams::default()
        };
        assert!((s.position_sigma_m() - (9e-12f64 + 4e-12 / 12.0).sqrt()).abs() < 1e-15);
        let mut rng = Rng::new(7);
        let n = 200_000;
        let (mut sum, mut sum2) = (0.0, 0.0);
        for _ in 0..n {
            let e = s.encoder(0.1234567, &mut rng) - 0.1234567;
            sum += e;
            sum2 += e * e;
        }
        let (mean, sd) = (
            sum / n as f64,
            (sum2 / n as f64 - (sum / n as f64).powi(2)).sqrt(),
        );
        assert!(mean.abs() < 5e-8, "mean {mean}");
        assert!(
            (sd / s.position_sigma_m() - 1.0).abs() < 0.01,
            "σ {sd} against {}",
            s.position_sigma_m()
        );
        // without noise the encoder draws nothing: the random sequence is the thesis rig's
        let (mut a, mut b) = (Rng::new(3), Rng::new(3));
        SensorParams::default().encoder(0.1, &mut a);
        assert_eq!(a.normal(), b.normal());
    }

    #[test]
    fn quantisation_steps() {
        let s = SensorParams::default();
        let mut rng = Rng::new(1);
        assert!((s.encoder(0.300_014, &mut rng) - 0.30).abs() < 1e-12);
        assert!((s.encoder(0.300_016, &mut rng) - 0.30003).abs() < 1e-12);
        assert!((s.pressure_lsb_pa() - 5054.9).abs() < 0.1);
        let quiet = SensorParams {
            pressure_noise_pa: 0.0,
            ..s
        };
        let p = quiet.pressure(6.9e6, &mut rng);
        assert!((p - 6.9e6).abs() <= 0.5 * s.pressure_lsb_pa() + 1e-6);
        assert_eq!(quiet.pressure(-1e6, &mut rng), 0.0);
        assert_eq!(quiet.pressure(30e6, &mut rng), 20.7e6);
        assert_eq!(SensorParams::ideal().pressure(1.234e6, &mut rng), 1.234e6);
    }

    #[test]
    fn an_installation_reads_its_offset_and_span() {
        let s = SensorParams {
            pressure_noise_pa: 0.0,
            adc_bits: 24,
            pressure_offset_pa: [30e3, -20e3],
            pressure_gain_error: [0.004, -0.003],
            ..SensorParams::default()
        };
        let mut rng = Rng::new(1);
        let lsb = s.pressure_lsb_pa();
        let p1 = s.pressure_channel(0, 10e6, &mut rng);
        let p2 = s.pressure_channel(1, 10e6, &mut rng);
        assert!((p1 - (10e6 * 1.004 + 30e3)).abs() <= lsb, "{p1}");
        assert!((p2 - (10e6 * 0.997 - 20e3)).abs() <= lsb, "{p2}");
        assert!(s.has_installation_effects() && !SensorParams::default().has_installation_effects());
        let bad = SensorParams {
            pressure_lag_s: -1e-3,
            ..SensorParams::default()
        };
        assert!(bad.validate().unwrap_err().to_string().contains("pressure_lag_s"));
    }
}
