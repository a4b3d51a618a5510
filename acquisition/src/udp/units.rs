//! The stream's units: its pressures checked once, after its first seconds.

use model::Sample;

use super::UdpSource;

/// How long a stream runs before its pressures are checked for their units
/// ([`dataset::PressureReach`]), s: once, with a warning that names `[udp]`'s scaling.
pub const UNITS_AFTER_S: f64 = 2.0;

impl UdpSource {
    /// Takes sample `s`'s pressures until [`UNITS_AFTER_S`] of samples have
    /// passed, then says once if none passed 1 % of the supply pressure.
    pub(super) fn check_units(&mut self, s: &Sample) {
        if self.units_checked {
            return;
        }
        self.reach.add(s);
        if (self.counts.samples as f64) * self.opts.sample_period_s >= UNITS_AFTER_S {
            self.units_checked = true;
            if let Err(e) = self.reach.check(self.opts.limits.supply_pa()) {
                bus::say!("udp: warning: {e}; check [udp]'s scaling (docs/live.md)");
            }
        }
    }
}
