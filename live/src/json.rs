//! The JSON messages of the live view and the fleet gateway, one per bus
//! topic, with their JSON Schemas (what Foxglove reads to offer the fields
//! for plotting). Flat objects: every field is plottable as
//! `/leakwatch/<rig>/<topic>.<field>`; SI units in the names; codes as names;
//! NaN ("absent") as `null`.

use frames::{
    code_name, estimate_flags, event_kind, event_phase, health_status, sensor_flags, EstimateFrame,
    HealthFrame, LeakEventFrame, SensorFrame,
};
use serde::Serialize;
use serde_json::{json, Value};

/// m³/s → L/min.
const LPM_PER_M3_S: f64 = 60_000.0;

/// A sensor frame: one rig sample as the acquisition published it.
#[derive(Debug, Clone, Serialize)]
pub struct FrameMsg {
    /// Sequence number of the sample.
    pub seq: u64,
    /// Sample time, s.
    pub t_s: f64,
    /// Valve command, V.
    pub u_v: f64,
    /// Rod position, m.
    pub x_m: f64,
    /// Chamber-1 pressure, Pa.
    pub p1_pa: f64,
    /// Chamber-2 pressure, Pa.
    pub p2_pa: f64,
    /// Spool position, m (null: absent).
    pub x_sp_m: f64,
    /// Load force, N (null: absent).
    pub f_load_n: f64,
    /// Position reference, m (null: open loop or absent).
    pub ref_m: f64,
    /// Leak flow (flow meter or simulator truth), L/min (null: absent).
    pub q_leak_lpm: f64,
    /// Oil temperature, °C (null: absent).
    pub temp_c: f64,
    /// Samples were missing before this one.
    pub after_gap: bool,
    /// The last sample of the stream.
    pub end_of_stream: bool,
}

impl From<&SensorFrame> for FrameMsg {
    fn from(f: &SensorFrame) -> Self {
        FrameMsg {
            seq: f.seq,
            t_s: f.t_s,
            u_v: f.u_v,
            x_m: f.x_m,
            p1_pa: f.p1_pa,
            p2_pa: f.p2_pa,
            x_sp_m: f.x_sp_m,
            f_load_n: f.f_load_n,
            ref_m: f.ref_m,
            q_leak_lpm: f.q_leak_lpm,
            temp_c: f.temp_c,
            after_gap: f.flags & sensor_flags::AFTER_GAP != 0,
            end_of_stream: f.flags & sensor_flags::END_OF_STREAM != 0,
        }
    }
}

/// An estimate of the leak filter (with the thesis filter's load and MAE).
#[derive(Debug, Clone, Serialize)]
pub struct EstimateMsg {
    /// Sequence number of the sample.
    pub seq: u64,
    /// Sample time, s.
    pub t_s: f64,
    /// Estimated rod position, m.
    pub x_m: f64,
    /// Estimated rod velocity, m/s.
    pub v_m_s: f64,
    /// Estimated chamber-1 pressure, Pa.
    pub p1_pa: f64,
    /// Estimated chamber-2 pressure, Pa.
    pub p2_pa: f64,
    /// Estimated spool position, m.
    pub x_sp_m: f64,
    /// Estimated effective load F_e, N.
    pub f_e_n: f64,
    /// Chamber-1 external leak size at the nominal drop p_s/2, L/min.
    pub leak_ext1_lpm: f64,
    /// Chamber-2 external leak size at p_s/2, L/min.
    pub leak_ext2_lpm: f64,
    /// Internal leak size at p_s/2, L/min.
    pub leak_int_lpm: f64,
    /// One standard deviation of `leak_ext1_lpm`, L/min.
    pub leak_ext1_sigma_lpm: f64,
    /// One standard deviation of `leak_ext2_lpm`, L/min.
    pub leak_ext2_sigma_lpm: f64,
    /// One standard deviation of `leak_int_lpm`, L/min.
    pub leak_int_sigma_lpm: f64,
    /// Measured rod position, m.
    pub measured_x_m: f64,
    /// Measured chamber-1 pressure, Pa.
    pub measured_p1_pa: f64,
    /// Measured chamber-2 pressure, Pa.
    pub measured_p2_pa: f64,
    /// Residual of the rod position, m.
    pub residual_x_m: f64,
    /// Residual of p1, Pa.
    pub residual_p1_pa: f64,
    /// Residual of p2, Pa.
    pub residual_p2_pa: f64,
    /// Normalised innovation squared.
    pub nis: f64,
    /// Thesis filter: effective load F_e, N.
    pub thesis_f_e_n: f64,
    /// Thesis filter: MAE of the p1 residual, Pa.
    pub thesis_mae_p1_pa: f64,
    /// Thesis filter: MAE of the p2 residual, Pa.
    pub thesis_mae_p2_pa: f64,
    /// The filter was reset at this sample.
    pub reset: bool,
    /// The filter is still converging.
    pub converging: bool,
    /// Bit set of the estimate flags (1 reset, 2 skipped, 4 clamped, 16 converging, 32 after a gap).
    pub flags: u32,
}

impl From<&EstimateFrame> for EstimateMsg {
    fn from(e: &EstimateFrame) -> Self {
        let s = |i: usize| e.state.get(i).copied().unwrap_or(f64::NAN);
        let sd = |i: usize| e.state_sigma.get(i).copied().unwrap_or(f64::NAN);
        EstimateMsg {
            seq: e.seq,
            t_s: e.t_s,
            x_sp_m: s(0),
            p1_pa: s(1),
            p2_pa: s(2),
            x_m: s(3),
            v_m_s: s(4),
            f_e_n: s(6),
            leak_ext1_lpm: s(7) * LPM_PER_M3_S,
            leak_ext2_lpm: s(8) * LPM_PER_M3_S,
            leak_int_lpm: s(9) * LPM_PER_M3_S,
            leak_ext1_sigma_lpm: sd(7) * LPM_PER_M3_S,
            leak_ext2_sigma_lpm: sd(8) * LPM_PER_M3_S,
            leak_int_sigma_lpm: sd(9) * LPM_PER_M3_S,
            measured_x_m: e.measured[0],
            measured_p1_pa: e.measured[1],
            measured_p2_pa: e.measured[2],
            residual_x_m: e.residual[0],
            residual_p1_pa: e.residual[1],
            residual_p2_pa: e.residual[2],
            nis: e.nis,
            thesis_f_e_n: e.th_state[6],
            thesis_mae_p1_pa: e.th_mae_pa[0],
            thesis_mae_p2_pa: e.th_mae_pa[1],
            reset: e.flags & estimate_flags::RESET != 0,
            converging: e.flags & estimate_flags::CONVERGING != 0,
            flags: e.flags,
        }
    }
}

/// A leak or fault event (raised, updated, cleared), as in events.json.
#[derive(Debug, Clone, Serialize)]
pub struct EventMsg {
    /// The event's id, the same for its raised, updated and cleared messages.
    pub event_id: u64,
    /// `ext1`, `ext2`, `int`, `leak` (kind pending), `sensor-stuck`, ...
    pub kind: String,
    /// `raised`, `updated` or `cleared`.
    pub phase: String,
    /// The detector that decided.
    pub detector: String,
    /// Sample time of the decision, s.
    pub t_detect_s: f64,
    /// Estimated onset, s.
    pub t_onset_s: f64,
    /// Leak flow at the measured pressures, L/min.
    pub size_lpm: f64,
    /// One standard deviation of `size_lpm`, L/min.
    pub size_lpm_sigma: f64,
    /// The leak at the nominal drop p_s/2, L/min.
    pub size_nominal_lpm: f64,
    /// Leak coefficient, m³/(s·√Pa).
    pub coefficient_m3_s_sqrt_pa: f64,
    /// Decision statistic, healthy spreads.
    pub statistic: f64,
    /// Its threshold, healthy spreads.
    pub threshold: f64,
    /// Confidence, 0..1.
    pub confidence: f64,
    /// Sensor events: the channel (`x`, `p1`, `p2`), else empty.
    pub channel: String,
    /// Human-readable detail.
    pub detail: String,
}

impl From<&LeakEventFrame> for EventMsg {
    fn from(e: &LeakEventFrame) -> Self {
        EventMsg {
            event_id: e.event_id,
            kind: code_name(&event_kind::NAMES, e.kind).into_owned(),
            phase: code_name(&event_phase::NAMES, e.phase).into_owned(),
            detector: frames::detector_name(&e.detector).to_string(),
            t_detect_s: e.t_detect_s,
            t_onset_s: e.t_onset_s,
            size_lpm: e.size_lpm,
            size_lpm_sigma: e.size_lpm_sigma,
            size_nominal_lpm: e.size_nominal_lpm,
            coefficient_m3_s_sqrt_pa: e.coefficient_m3_s_sqrt_pa,
            statistic: e.statistic,
            threshold: e.threshold,
            confidence: e.confidence,
            channel: frames::text(&e.channel).to_string(),
            detail: frames::text(&e.detail).to_string(),
        }
    }
}

/// The classifier's health summary (10 Hz).
#[derive(Debug, Clone, Serialize)]
pub struct HealthMsg {
    /// Sequence number of the health stream.
    pub seq: u64,
    /// Sample time, s.
    pub t_s: f64,
    /// `warming-up`, `healthy`, `leak` or `sensor-fault`.
    pub status: String,
    /// Number of active events.
    pub active_events: u32,
    /// Chamber-1 external leak: its size's rise above the healthy state, L/min at p_s/2.
    pub leak_ext1_lpm: f64,
    /// Chamber-2 external leak: as `leak_ext1_lpm`, L/min at p_s/2.
    pub leak_ext2_lpm: f64,
    /// Internal leak: as `leak_ext1_lpm`, L/min at p_s/2.
    pub leak_int_lpm: f64,
    /// One standard deviation of `leak_ext1_lpm`, L/min.
    pub leak_ext1_sigma_lpm: f64,
    /// One standard deviation of `leak_ext2_lpm`, L/min.
    pub leak_ext2_sigma_lpm: f64,
    /// One standard deviation of `leak_int_lpm`, L/min.
    pub leak_int_sigma_lpm: f64,
    /// The detector's threshold on `leak_ext1_lpm`, L/min at p_s/2 (NaN before it armed).
    pub leak_ext1_threshold_lpm: f64,
    /// The detector's threshold on `leak_ext2_lpm`, L/min at p_s/2 (NaN before it armed).
    pub leak_ext2_threshold_lpm: f64,
    /// The detector's threshold on `leak_int_lpm`, L/min at p_s/2 (NaN before it armed).
    pub leak_int_threshold_lpm: f64,
}

impl From<&HealthFrame> for HealthMsg {
    fn from(h: &HealthFrame) -> Self {
        HealthMsg {
            seq: h.seq,
            t_s: h.t_s,
            status: code_name(&health_status::NAMES, h.status).into_owned(),
            active_events: h.active_events,
            leak_ext1_lpm: h.leak_flow_lpm[0],
            leak_ext2_lpm: h.leak_flow_lpm[1],
            leak_int_lpm: h.leak_flow_lpm[2],
            leak_ext1_sigma_lpm: h.leak_flow_sigma_lpm[0],
            leak_ext2_sigma_lpm: h.leak_flow_sigma_lpm[1],
            leak_int_sigma_lpm: h.leak_flow_sigma_lpm[2],
            leak_ext1_threshold_lpm: h.leak_threshold_lpm[0],
            leak_ext2_threshold_lpm: h.leak_threshold_lpm[1],
            leak_int_threshold_lpm: h.leak_threshold_lpm[2],
        }
    }
}

/// Field types of a schema.
#[derive(Clone, Copy)]
enum Ty {
    /// A float; `null` when absent (NaN).
    Num,
    /// An unsigned integer.
    Int,
    /// A string.
    Str,
    /// A boolean.
    Bool,
}

fn schema(title: &str, fields: &[(&str, Ty, &str)]) -> Value {
    let props: serde_json::Map<String, Value> = fields
        .iter()
        .map(|(name, ty, doc)| {
            let t = match ty {
                Ty::Num => json!(["number", "null"]),
                Ty::Int => json!("integer"),
                Ty::Str => json!("string"),
                Ty::Bool => json!("boolean"),
            };
            (name.to_string(), json!({ "type": t, "description": doc }))
        })
        .collect();
    json!({
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        "title": title,
        "type": "object",
        "properties": props,
    })
}

use Ty::{Bool, Int, Num, Str};

/// The JSON Schema of the messages of a topic (`frames`, `estimates`, `events`, `health`).
pub fn schema_of(topic: crate::LiveTopic) -> Value {
    use crate::LiveTopic as T;
    match topic {
        T::Frames => schema("leakwatch.SensorFrame", SENSOR_FRAME_FIELDS),
        T::Estimates => schema("leakwatch.Estimate", ESTIMATE_FIELDS),
        T::Events => schema("leakwatch.LeakEvent", LEAK_EVENT_FIELDS),
        T::Health => schema("leakwatch.Health", HEALTH_FIELDS),
    }
}

/// The fields of a `frames` message ([`FrameMsg`]): one sample, SI units.
const SENSOR_FRAME_FIELDS: &[(&str, Ty, &str)] = &[
    ("seq", Int, "sequence number of the sample"),
    ("t_s", Num, "sample time, s"),
    ("u_v", Num, "valve command, V"),
    ("x_m", Num, "rod position, m"),
    ("p1_pa", Num, "chamber-1 pressure, Pa"),
    ("p2_pa", Num, "chamber-2 pressure, Pa"),
    ("x_sp_m", Num, "spool position, m (null: absent)"),
    ("f_load_n", Num, "load force, N (null: absent)"),
    ("ref_m", Num, "position reference, m (null: absent)"),
    ("q_leak_lpm", Num, "leak flow, L/min (null: absent)"),
    ("temp_c", Num, "oil temperature, °C (null: absent)"),
    ("after_gap", Bool, "samples were missing before this one"),
    ("end_of_stream", Bool, "the last sample of the stream"),
];

/// The fields of an `estimates` message ([`EstimateMsg`]): the filters' estimates, residuals and leak sizes (SI, L/min).
const ESTIMATE_FIELDS: &[(&str, Ty, &str)] = &[
    ("seq", Int, "sequence number of the sample"),
    ("t_s", Num, "sample time, s"),
    ("x_m", Num, "estimated rod position, m"),
    ("v_m_s", Num, "estimated rod velocity, m/s"),
    ("p1_pa", Num, "estimated chamber-1 pressure, Pa"),
    ("p2_pa", Num, "estimated chamber-2 pressure, Pa"),
    ("x_sp_m", Num, "estimated spool position, m"),
    ("f_e_n", Num, "estimated effective load F_e, N"),
    ("leak_ext1_lpm", Num, "chamber-1 external leak at p_s/2, L/min"),
    ("leak_ext2_lpm", Num, "chamber-2 external leak at p_s/2, L/min"),
    ("leak_int_lpm", Num, "internal leak at p_s/2, L/min"),
    (
        "leak_ext1_sigma_lpm",
        Num,
        "one standard deviation of leak_ext1_lpm, L/min",
    ),
    (
        "leak_ext2_sigma_lpm",
        Num,
        "one standard deviation of leak_ext2_lpm, L/min",
    ),
    (
        "leak_int_sigma_lpm",
        Num,
        "one standard deviation of leak_int_lpm, L/min",
    ),
    ("measured_x_m", Num, "measured rod position, m"),
    ("measured_p1_pa", Num, "measured chamber-1 pressure, Pa"),
    ("measured_p2_pa", Num, "measured chamber-2 pressure, Pa"),
    ("residual_x_m", Num, "position residual, m"),
    ("residual_p1_pa", Num, "p1 residual, Pa"),
    ("residual_p2_pa", Num, "p2 residual, Pa"),
    ("nis", Num, "normalised innovation squared"),
    ("thesis_f_e_n", Num, "thesis filter: effective load, N"),
    (
        "thesis_mae_p1_pa",
        Num,
        "thesis filter: MAE of the p1 residual, Pa",
    ),
    (
        "thesis_mae_p2_pa",
        Num,
        "thesis filter: MAE of the p2 residual, Pa",
    ),
    ("reset", Bool, "the filter was reset at this sample"),
    ("converging", Bool, "the filter is still converging"),
    (
        "flags",
        Int,
        "estimate flags: 1 reset, 2 skipped, 4 clamped, 16 converging, 32 after a gap",
    ),
];

/// The fields of an `events` message ([`EventMsg`]): a leak or sensor event as raised, updated or cleared.
const LEAK_EVENT_FIELDS: &[(&str, Ty, &str)] = &[
    (
        "event_id",
        Int,
        "the event's id (same for raised, updated, cleared)",
    ),
    (
        "kind",
        Str,
        "ext1, ext2, int, leak (kind pending), sensor-stuck, ...",
    ),
    ("phase", Str, "raised, updated or cleared"),
    ("detector", Str, "the detector that decided"),
    ("t_detect_s", Num, "sample time of the decision, s"),
    ("t_onset_s", Num, "estimated onset, s"),
    ("size_lpm", Num, "leak flow at the measured pressures, L/min"),
    ("size_lpm_sigma", Num, "one standard deviation of size_lpm, L/min"),
    ("size_nominal_lpm", Num, "the leak at p_s/2, L/min"),
    ("coefficient_m3_s_sqrt_pa", Num, "leak coefficient, m³/(s·√Pa)"),
    ("statistic", Num, "decision statistic, healthy spreads"),
    ("threshold", Num, "its threshold, healthy spreads"),
    ("confidence", Num, "confidence, 0..1"),
    ("channel", Str, "sensor events: x, p1 or p2"),
    ("detail", Str, "human-readable detail"),
];

/// The fields of a `health` message ([`HealthMsg`]): the status, active events and leak sizes with thresholds (L/min).
const HEALTH_FIELDS: &[(&str, Ty, &str)] = &[
    ("seq", Int, "sequence number of the health stream"),
    ("t_s", Num, "sample time, s"),
    ("status", Str, "warming-up, healthy, leak or sensor-fault"),
    ("active_events", Int, "number of active events"),
    (
        "leak_ext1_lpm",
        Num,
        "chamber-1 external leak: its size's rise above the healthy state, L/min at p_s/2",
    ),
    (
        "leak_ext2_lpm",
        Num,
        "chamber-2 external leak, as leak_ext1_lpm, L/min",
    ),
    ("leak_int_lpm", Num, "internal leak, as leak_ext1_lpm, L/min"),
    (
        "leak_ext1_sigma_lpm",
        Num,
        "one standard deviation of leak_ext1_lpm, L/min",
    ),
    (
        "leak_ext2_sigma_lpm",
        Num,
        "one standard deviation of leak_ext2_lpm, L/min",
    ),
    (
        "leak_int_sigma_lpm",
        Num,
        "one standard deviation of leak_int_lpm, L/min",
    ),
    (
        "leak_ext1_threshold_lpm",
        Num,
        "the detector's threshold on leak_ext1_lpm, L/min (null before it armed)",
    ),
    (
        "leak_ext2_threshold_lpm",
        Num,
        "the detector's threshold on leak_ext2_lpm, L/min (null before it armed)",
    ),
    (
        "leak_int_threshold_lpm",
        Num,
        "the detector's threshold on leak_int_lpm, L/min (null before it armed)",
    ),
];

#[cfg(test)]
mod tests {
    use super::*;
    use crate::LiveTopic;

    fn keys(v: &Value) -> Vec<String> {
        let mut k: Vec<String> = v.as_object().unwrap().keys().cloned().collect();
        k.sort();
        k
    }

    /// Every message has exactly the fields its schema names; NaN is null; codes are names.
    #[test]
    fn messages_match_their_schemas() {
        let mut e = EstimateFrame {
            n_states: 11,
            ..EstimateFrame::default()
        };
        e.state[1] = 7.5e6;
        e.state[7] = 0.5 / 60_000.0;
        let mut ev = LeakEventFrame {
            kind: event_kind::EXT1,
            phase: event_phase::RAISED,
            size_lpm: 0.5,
            ..LeakEventFrame::default()
        };
        ev.detector = frames::detector_bytes("leak-size");
        let h = HealthFrame {
            status: health_status::LEAK,
            ..HealthFrame::default()
        };
        let f = SensorFrame {
            p1_pa: 1e6,
            flags: sensor_flags::END_OF_STREAM,
            ..SensorFrame::default()
        };
        let msgs = [
            (
                LiveTopic::Frames,
                serde_json::to_value(FrameMsg::from(&f)).unwrap(),
            ),
            (
                LiveTopic::Estimates,
                serde_json::to_value(EstimateMsg::from(&e)).unwrap(),
            ),
            (
                LiveTopic::Events,
                serde_json::to_value(EventMsg::from(&ev)).unwrap(),
            ),
            (
                LiveTopic::Health,
                serde_json::to_value(HealthMsg::from(&h)).unwrap(),
            ),
        ];
        for (topic, msg) in &msgs {
            assert_eq!(keys(msg), keys(&schema_of(*topic)["properties"]), "{topic:?}");
        }
        assert_eq!(msgs[0].1["p1_pa"], 1e6);
        assert_eq!(msgs[0].1["x_m"], Value::Null);
        assert_eq!(msgs[0].1["end_of_stream"], true);
        assert_eq!(msgs[1].1["p1_pa"], 7.5e6);
        assert!((msgs[1].1["leak_ext1_lpm"].as_f64().unwrap() - 0.5).abs() < 1e-12);
        assert_eq!(msgs[2].1["kind"], "ext1");
        assert_eq!(msgs[2].1["phase"], "raised");
        assert_eq!(msgs[2].1["detector"], "leak-size");
        assert_eq!(msgs[3].1["status"], "leak");
    }
}
