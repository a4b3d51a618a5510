//! A rig's state as the OPC UA server shows it, kept from the bus's
//! estimates, health frames and events: the state variables of the rig's
//! object ([`VARIABLES`]), in order, with their types, units and meaning.
//! Pure: no OPC UA, no bus; the caller gives the wall-clock instants.

use std::collections::BTreeMap;
use std::time::{Duration, Instant};

use frames::{code_name, event_kind, event_phase, health_status, EstimateFrame, HealthFrame, LeakEventFrame};

/// The type of a state variable.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Ty {
    /// Boolean.
    Bool,
    /// Double (empty while absent).
    Double,
    /// String.
    Str,
    /// UInt32.
    U32,
    /// UInt64.
    U64,
}

/// A state variable's value (a NaN `Double` is shown empty).
#[derive(Debug, Clone, PartialEq)]
pub enum Value {
    /// A Boolean.
    Bool(bool),
    /// A Double; NaN: absent (the variable is empty).
    Double(f64),
    /// A String.
    Str(String),
    /// A UInt32.
    U32(u32),
    /// A UInt64.
    U64(u64),
}

/// A unit of the UNECE Recommendation 20 (the OPC UA `EUInformation`):
/// symbol, common code, description.
pub type Unit = (&'static str, &'static str, &'static str);

/// Litres per minute.
const LPM: Option<Unit> = Some(("L/min", "L2", "litre per minute"));
/// Seconds.
const SEC: Option<Unit> = Some(("s", "SEC", "second"));
/// Degrees Celsius.
const CEL: Option<Unit> = Some(("°C", "CEL", "degree Celsius"));
/// Kelvin (a temperature difference).
const KEL: Option<Unit> = Some(("K", "KEL", "kelvin"));

/// One state variable: browse name (its unit in the name's last part), type,
/// unit, and what it means (its OPC UA Description).
#[derive(Debug, Clone, Copy)]
pub struct VarSpec {
    /// The browse name (and display name).
    pub name: &'static str,
    /// Its type.
    pub ty: Ty,
    /// Its engineering unit, if it has one.
    pub unit: Option<Unit>,
    /// What it means.
    pub doc: &'static str,
}

const fn v(name: &'static str, ty: Ty, unit: Option<Unit>, doc: &'static str) -> VarSpec {
    VarSpec { name, ty, unit, doc }
}

/// The state variables of a rig's object, in the order of [`RigState::values`].
pub const VARIABLES: [VarSpec; 22] = [
    v("Running", Ty::Bool, None, "estimates arrive: the pipeline runs (none for 0.5 s: false)"),
    v("Armed", Ty::Bool, None, "the detector has learned the healthy state and its thresholds"),
    v("Watched", Ty::Bool, None, "running, armed and no sensor fault active: a leak would be seen"),
    v("BlindSinceS", Ty::Double, SEC, "sample time since which the rig is not watched, s; empty while watched"),
    v("HealthStatus", Ty::Str, None, "the classifier's status: warming-up, healthy, leak or sensor-fault"),
    v("HealthAgeS", Ty::Double, SEC, "time since the classifier's last health frame (10 Hz), s: the stage's health"),
    v("ActiveEvents", Ty::U32, None, "events active in the classifier (leaks and faults)"),
    v("AlarmKind", Ty::Str, None, "the active leak alarm's kind: ext1, ext2, int or leak (kind pending); empty: none"),
    v("AlarmEventId", Ty::U64, None, "the active leak alarm's event id (as in events.json); 0: none"),
    v("LeakSizeLpm", Ty::Double, LPM, "the active leak's flow at the measured pressures, L/min"),
    v("LeakSizeSigmaLpm", Ty::Double, LPM, "one standard deviation of LeakSizeLpm, L/min"),
    v("OnsetTimeS", Ty::Double, SEC, "the active leak's estimated onset, sample time, s"),
    v("DetectTimeS", Ty::Double, SEC, "when the active leak was decided, sample time, s"),
    v("Confidence", Ty::Double, None, "the active leak's confidence, 0 to 1"),
    v("SmallestDetectableExt1Lpm", Ty::Double, LPM, "smallest chamber-1 external leak detected now (the detector's threshold), L/min at p_s/2"),
    v("SmallestDetectableExt2Lpm", Ty::Double, LPM, "smallest chamber-2 external leak detected now, L/min at p_s/2"),
    v("SmallestDetectableIntLpm", Ty::Double, LPM, "smallest internal leak detected now, L/min at p_s/2"),
    v("OilTemperatureC", Ty::Double, CEL, "the oil temperature the leak filter works with (measured, or estimated from the oil's stiffness), °C"),
    v("OilTemperatureSigmaK", Ty::Double, KEL, "one standard deviation of OilTemperatureC, K"),
    v("SensorFaults", Ty::Str, None, "the active sensor faults, `kind channel` separated by commas; empty: none"),
    v("SensorFaultCount", Ty::U32, None, "the number of active sensor faults"),
    v("SampleTimeS", Ty::Double, SEC, "sample time of the latest estimate, s"),
];

/// No estimate for this long: not running.
pub const STALE: Duration = Duration::from_millis(500);

/// Whether `kind` is a leak (ext1, ext2, int, or one whose kind is pending).
pub fn is_leak(kind: u32) -> bool {
    matches!(
        kind,
        event_kind::EXT1 | event_kind::EXT2 | event_kind::INTERNAL | event_kind::LEAK_PENDING
    )
}

/// Whether `kind` is a sensor fault.
pub fn is_sensor_fault(kind: u32) -> bool {
    matches!(
        kind,
        event_kind::SENSOR_STUCK
            | event_kind::SENSOR_SATURATED
            | event_kind::SENSOR_DEAD
            | event_kind::SENSOR_OFFSET
            | event_kind::SENSOR_SPIKES
    )
}

/// The rig's state: the latest estimate's and health frame's figures and the
/// active events.
#[derive(Debug, Default)]
pub struct RigState {
    last_estimate: Option<(Instant, f64, f64, f64)>,
    health: Option<(Instant, HealthFrame)>,
    /// Active events by id, in the order raised (leaks and sensor faults).
    active: BTreeMap<u64, LeakEventFrame>,
    /// The latest sample time at which the rig was watched (NaN: never), and
    /// whether it was watched at the last look.
    blind_since_s: f64,
    watched: bool,
}

impl RigState {
    /// A state before any message.
    pub fn new() -> Self {
        RigState {
            blind_since_s: f64::NAN,
            ..RigState::default()
        }
    }

    /// An estimate received at `at`.
    pub fn on_estimate(&mut self, e: &EstimateFrame, at: Instant) {
        self.last_estimate = Some((at, e.t_s, e.oil_temp_c, e.oil_temp_sigma_k));
    }

    /// A health frame received at `at`.
    pub fn on_health(&mut self, h: &HealthFrame, at: Instant) {
        self.health = Some((at, *h));
    }

    /// An event: a raised or updated one is active, a cleared one no longer.
    pub fn on_event(&mut self, e: &LeakEventFrame) {
        if !(is_leak(e.kind) || is_sensor_fault(e.kind)) {
            return;
        }
        if e.phase == event_phase::CLEARED {
            self.active.remove(&e.event_id);
        } else {
            self.active.insert(e.event_id, *e);
        }
    }

    fn running(&self, now: Instant) -> bool {
        self.last_estimate
            .is_some_and(|(at, ..)| now.saturating_duration_since(at) < STALE)
    }

    fn armed(&self) -> bool {
        self.health
            .as_ref()
            .is_some_and(|(_, h)| h.leak_threshold_lpm.iter().any(|t| t.is_finite()))
    }

    fn sensor_faults(&self) -> Vec<&LeakEventFrame> {
        self.active.values().filter(|e| is_sensor_fault(e.kind)).collect()
    }

    /// The active leak shown: the one raised or updated last.
    fn alarm(&self) -> Option<&LeakEventFrame> {
        self.active
            .values()
            .filter(|e| is_leak(e.kind))
            .max_by(|a, b| a.t_detect_s.total_cmp(&b.t_detect_s).then(a.seq.cmp(&b.seq)))
    }

    /// Every state variable's value at `now`, in [`VARIABLES`] order.
    pub fn values(&mut self, now: Instant) -> Vec<Value> {
        let running = self.running(now);
        let armed = self.armed();
        let faults = self.sensor_faults();
        let n_faults = faults.len() as u32;
        let fault_text = faults
            .iter()
            .map(|e| {
                let kind = code_name(&event_kind::NAMES, e.kind);
                format!("{kind} {}", frames::text(&e.channel)).trim().to_string()
            })
            .collect::<Vec<_>>()
            .join(", ");
        let watched = running && armed && n_faults == 0;
        let t_s = self.last_estimate.map_or(f64::NAN, |(_, t, ..)| t);
        if watched {
            self.blind_since_s = f64::NAN;
        } else if self.watched || self.blind_since_s.is_nan() {
            // blind from now on (or from the first sample seen)
            self.blind_since_s = t_s;
        }
        self.watched = watched;
        let (status, age_s, active, thr) = match &self.health {
            Some((at, h)) => (
                code_name(&health_status::NAMES, h.status).into_owned(),
                now.saturating_duration_since(*at).as_secs_f64(),
                h.active_events,
                h.leak_threshold_lpm,
            ),
            None => (String::new(), f64::NAN, 0, [f64::NAN; 3]),
        };
        let alarm = self.alarm();
        let a = |f: fn(&LeakEventFrame) -> f64| Value::Double(alarm.map_or(f64::NAN, f));
        let (oil_c, oil_sd) = self
            .last_estimate
            .map_or((f64::NAN, f64::NAN), |(_, _, c, s)| (c, s));
        vec![
            Value::Bool(running),
            Value::Bool(armed),
            Value::Bool(watched),
            Value::Double(if watched { f64::NAN } else { self.blind_since_s }),
            Value::Str(status),
            Value::Double(age_s),
            Value::U32(active),
            Value::Str(alarm.map_or(String::new(), |e| {
                code_name(&event_kind::NAMES, e.kind).into_owned()
            })),
            Value::U64(alarm.map_or(0, |e| e.event_id)),
            a(|e| e.size_lpm),
            a(|e| e.size_lpm_sigma),
            a(|e| e.t_onset_s),
            a(|e| e.t_detect_s),
            a(|e| e.confidence),
            Value::Double(thr[0]),
            Value::Double(thr[1]),
            Value::Double(thr[2]),
            Value::Double(oil_c),
            Value::Double(oil_sd),
            Value::Str(fault_text),
            Value::U32(n_faults),
            Value::Double(t_s),
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn event(id: u64, kind: u32, phase: u32, t: f64) -> LeakEventFrame {
        LeakEventFrame {
            event_id: id,
            kind,
            phase,
            t_detect_s: t,
            t_onset_s: t - 1.0,
            size_lpm: 0.5,
            size_lpm_sigma: 0.05,
            confidence: 0.9,
            ..LeakEventFrame::default()
        }
    }

    #[test]
    fn the_values_follow_estimates_health_and_events() {
        let t0 = Instant::now();
        let mut s = RigState::new();
        let v = s.values(t0);
        assert_eq!(v.len(), VARIABLES.len());
        for (spec, value) in VARIABLES.iter().zip(&v) {
            let ty = match value {
                Value::Bool(_) => Ty::Bool,
                Value::Double(_) => Ty::Double,
                Value::Str(_) => Ty::Str,
                Value::U32(_) => Ty::U32,
                Value::U64(_) => Ty::U64,
            };
            assert_eq!(ty, spec.ty, "{}", spec.name);
        }
        assert_eq!((&v[0], &v[2]), (&Value::Bool(false), &Value::Bool(false)));
        let est = EstimateFrame {
            t_s: 12.0,
            oil_temp_c: 41.0,
            ..EstimateFrame::default()
        };
        s.on_estimate(&est, t0);
        let health = HealthFrame {
            status: health_status::HEALTHY,
            leak_threshold_lpm: [0.1, 0.2, 0.3],
            ..HealthFrame::default()
        };
        s.on_health(&health, t0);
        let v = s.values(t0);
        assert_eq!(v[..3], [Value::Bool(true), Value::Bool(true), Value::Bool(true)]);
        assert!(matches!(v[3], Value::Double(t) if t.is_nan()), "{:?}", v[3]);
        assert_eq!(v[4], Value::Str("healthy".into()));
        assert_eq!(v[14], Value::Double(0.1));
        assert_eq!(v[17], Value::Double(41.0));
        s.on_event(&event(7, event_kind::EXT2, event_phase::RAISED, 12.5));
        let v = s.values(t0);
        assert_eq!(
            (&v[7], &v[8], &v[9]),
            (&Value::Str("ext2".into()), &Value::U64(7), &Value::Double(0.5))
        );
        // a sensor fault blinds the rig from the latest sample time
        let mut fault = event(8, event_kind::SENSOR_STUCK, event_phase::RAISED, 12.6);
        fault.channel[..2].copy_from_slice(b"p1");
        s.on_event(&fault);
        let v = s.values(t0);
        assert_eq!((&v[2], &v[3]), (&Value::Bool(false), &Value::Double(12.0)));
        assert_eq!(
            (&v[19], &v[20]),
            (&Value::Str("sensor-stuck p1".into()), &Value::U32(1))
        );
        s.on_event(&event(7, event_kind::EXT2, event_phase::CLEARED, 13.0));
        s.on_event(&event(8, event_kind::SENSOR_STUCK, event_phase::CLEARED, 13.0));
        let v = s.values(t0);
        assert_eq!((&v[2], &v[7]), (&Value::Bool(true), &Value::Str(String::new())));
        // no estimate for 0.5 s: not running
        let v = s.values(t0 + STALE);
        assert_eq!((&v[0], &v[2]), (&Value::Bool(false), &Value::Bool(false)));
    }
}
