//! How each frame type is written as JSON (with its JSON Schema) and as CSV.
//! JSON was the log's message encoding before CDR ([`crate::msg`]): logs of
//! that encoding are read with it, and [`crate::Encoding::Json`] still writes it.
//!
//! JSON numbers carry f64 exactly (shortest round-trip form, parsed with
//! serde_json's `float_roundtrip`); NaN ("absent") is written as `null`, and
//! the infinities as the strings `"inf"` and `"-inf"`. Integers are JSON
//! integers (u64 exact). Explicit padding fields are not written (read back as 0).
//! The detector name is a string.

use std::fmt::Write as _;

use frames::{EstimateFrame, Frame, HealthFrame, LeakEventFrame, SensorFrame, StatsFrame};
use serde_json::{json, Map, Value};

/// One field's encoding.
pub trait Field: Sized {
    /// The JSON value.
    fn to_json(&self) -> Value;
    /// From the JSON value (`None`: the key is missing); the error names the problem.
    fn from_json(v: Option<&Value>) -> Result<Self, String>;
    /// The JSON Schema of the value.
    fn schema() -> Value;
    /// CSV column names for a field called `name` (one column, `name`, unless overridden).
    fn csv_names(name: &str, out: &mut Vec<String>) {
        out.push(name.to_string());
    }
    /// Appends the CSV cells, each preceded by a comma.
    fn csv_write(&self, out: &mut String);
}

fn float_json(x: f64) -> Value {
    if x.is_nan() {
        Value::Null
    } else if x.is_infinite() {
        Value::String(if x > 0.0 { "inf" } else { "-inf" }.into())
    } else {
        serde_json::Number::from_f64(x)
            .map(Value::Number)
            .unwrap_or(Value::Null)
    }
}

fn float_from(v: &Value) -> Result<f64, String> {
    match v {
        Value::Null => Ok(f64::NAN),
        Value::Number(n) => n.as_f64().ok_or_else(|| format!("{n} is not a float")),
        Value::String(s) if s == "inf" => Ok(f64::INFINITY),
        Value::String(s) if s == "-inf" => Ok(f64::NEG_INFINITY),
        other => Err(format!(
            "expected a number, null, \"inf\" or \"-inf\", found {other}"
        )),
    }
}

impl Field for f64 {
    fn to_json(&self) -> Value {
        float_json(*self)
    }
    fn from_json(v: Option<&Value>) -> Result<Self, String> {
        float_from(v.ok_or("missing")?)
    }
    fn schema() -> Value {
        json!({"type": ["number", "null", "string"], "description": "null = NaN (absent); \"inf\"/\"-inf\" = infinities"})
    }
    fn csv_write(&self, out: &mut String) {
        let _ = write!(out, ",{self:?}");
    }
}

impl Field for u64 {
    fn to_json(&self) -> Value {
        Value::from(*self)
    }
    fn from_json(v: Option<&Value>) -> Result<Self, String> {
        let v = v.ok_or("missing")?;
        v.as_u64()
            .ok_or_else(|| format!("expected an unsigned integer, found {v}"))
    }
    fn schema() -> Value {
        json!({"type": "integer", "minimum": 0})
    }
    fn csv_write(&self, out: &mut String) {
        let _ = write!(out, ",{self}");
    }
}

impl Field for u32 {
    fn to_json(&self) -> Value {
        Value::from(*self)
    }
    fn from_json(v: Option<&Value>) -> Result<Self, String> {
        let v = v.ok_or("missing")?;
        v.as_u64()
            .and_then(|x| u32::try_from(x).ok())
            .ok_or_else(|| format!("expected a 32-bit unsigned integer, found {v}"))
    }
    fn schema() -> Value {
        json!({"type": "integer", "minimum": 0, "maximum": u32::MAX})
    }
    fn csv_write(&self, out: &mut String) {
        let _ = write!(out, ",{self}");
    }
}

impl<const N: usize> Field for [f64; N] {
    fn to_json(&self) -> Value {
        Value::Array(self.iter().map(|&x| float_json(x)).collect())
    }
    fn from_json(v: Option<&Value>) -> Result<Self, String> {
        let v = v.ok_or("missing")?;
        let a = v
            .as_array()
            .ok_or_else(|| format!("expected an array, found {v}"))?;
        if a.len() != N {
            return Err(format!("expected {N} elements, found {}", a.len()));
        }
        let mut out = [0.0; N];
        for (o, x) in out.iter_mut().zip(a) {
            *o = float_from(x)?;
        }
        Ok(out)
    }
    fn schema() -> Value {
        json!({"type": "array", "items": f64::schema(), "minItems": N, "maxItems": N})
    }
    fn csv_names(name: &str, out: &mut Vec<String>) {
        out.extend((0..N).map(|i| format!("{name}_{i}")));
    }
    fn csv_write(&self, out: &mut String) {
        for x in self {
            x.csv_write(out);
        }
    }
}

impl<const N: usize> Field for [u8; N] {
    fn to_json(&self) -> Value {
        Value::String(frames::text(self).to_string())
    }
    fn from_json(v: Option<&Value>) -> Result<Self, String> {
        let v = v.ok_or("missing")?;
        let s = v
            .as_str()
            .ok_or_else(|| format!("expected a string, found {v}"))?;
        Ok(frames::text_bytes(s))
    }
    fn schema() -> Value {
        json!({"type": "string", "description": format!("UTF-8, at most {N} bytes")})
    }
    fn csv_write(&self, out: &mut String) {
        // names are ASCII without commas by convention; quote anything else
        let s = frames::text(self);
        if s.contains([',', '"', '\n']) {
            let _ = write!(out, ",\"{}\"", s.replace('"', "\"\""));
        } else {
            let _ = write!(out, ",{s}");
        }
    }
}

/// A frame type as a log record.
pub trait Record: Frame {
    /// The schema name (the iceoryx2 type name, e.g. `leakwatch.SensorFrame.v1`).
    const SCHEMA_NAME: &'static str;
    /// The JSON object of the frame.
    fn to_json(&self) -> Value;
    /// The frame from its JSON object; the error names the field.
    fn from_json(v: &Value) -> Result<Self, String>;
    /// The JSON Schema of [`Record::to_json`].
    fn schema() -> Value;
    /// The CSV header (column names).
    fn csv_header() -> Vec<String>;
    /// One CSV line without the newline.
    fn csv_row(&self, out: &mut String);
}

macro_rules! record {
    // `@unpadded`: the fields of `frames::frame_fields!` (the second list) are
    // taken over into the first without the explicit padding (not written, read back as 0).
    (@unpadded $ty:ty, $name:literal, [$($kept:ident),*] [_pad $(, $rest:ident)*]) => {
        record!(@unpadded $ty, $name, [$($kept),*] [$($rest),*]);
    };
    (@unpadded $ty:ty, $name:literal, [$($kept:ident),*] [$next:ident $(, $rest:ident)*]) => {
        record!(@unpadded $ty, $name, [$($kept,)* $next] [$($rest),*]);
    };
    (@unpadded $ty:ty, $name:literal, [$($kept:ident),*] []) => {
        record!($ty, $name, [$($kept),*]);
    };
    ($ty:ty, $name:literal, [$($field:ident),* $(,)?]) => {
        record!($ty, $name, [$($field),*], added []);
    };
    // `added`: fields a later version of the type brought; a record of an
    // earlier version without them reads with their defaults (NaN, empty).
    ($ty:ty, $name:literal, [$($field:ident),* $(,)?], added [$($added:ident),* $(,)?]) => {
        impl Record for $ty {
            const SCHEMA_NAME: &'static str = $name;
            fn to_json(&self) -> Value {
                let mut m = Map::new();
                $( m.insert(stringify!($field).into(), Field::to_json(&self.$field)); )*
                $( m.insert(stringify!($added).into(), Field::to_json(&self.$added)); )*
                Value::Object(m)
            }
            fn from_json(v: &Value) -> Result<Self, String> {
                let mut f = <$ty>::default();
                $( f.$field = Field::from_json(v.get(stringify!($field)))
                    .map_err(|e| format!("{}.{}: {e}", $name, stringify!($field)))?; )*
                $( if let Some(v) = v.get(stringify!($added)) {
                    f.$added = Field::from_json(Some(v))
                        .map_err(|e| format!("{}.{}: {e}", $name, stringify!($added)))?;
                } )*
                Ok(f)
            }
            fn schema() -> Value {
                let mut props = Map::new();
                $( props.insert(stringify!($field).into(), field_schema(&<$ty>::default().$field)); )*
                $( props.insert(stringify!($added).into(), field_schema(&<$ty>::default().$added)); )*
                json!({
                    "$schema": "https://json-schema.org/draft/2020-12/schema",
                    "title": $name,
                    "description": "leakwatch wire frame; units are in the field names (SI, _lpm = L/min, _ns = ns), see frames/README.md",
                    "type": "object",
                    "properties": Value::Object(props),
                })
            }
            fn csv_header() -> Vec<String> {
                let mut out = Vec::new();
                $( field_csv_names(&<$ty>::default().$field, stringify!($field), &mut out); )*
                $( field_csv_names(&<$ty>::default().$added, stringify!($added), &mut out); )*
                out
            }
            fn csv_row(&self, out: &mut String) {
                let start = out.len();
                $( Field::csv_write(&self.$field, out); )*
                $( Field::csv_write(&self.$added, out); )*
                // drop the leading comma of the first cell
                out.remove(start);
            }
        }
    };
}

fn field_schema<F: Field>(_: &F) -> Value {
    F::schema()
}

fn field_csv_names<F: Field>(_: &F, name: &str, out: &mut Vec<String>) {
    F::csv_names(name, out)
}

// The fields are the frames crate's lists (frames::frame_fields!); the
// SensorFrame's, EstimateFrame's, LeakEventFrame's and HealthFrame's are written
// out here, split by the version that brought them.
record!(
    SensorFrame,
    "leakwatch.SensorFrame.v2",
    [
        seq,
        acq_mono_ns,
        t_s,
        u_v,
        x_m,
        p1_pa,
        p2_pa,
        x_sp_m,
        f_load_n,
        ref_m,
        q_leak_lpm,
        flags
    ],
    added[temp_c]
);
record!(
    EstimateFrame,
    "leakwatch.EstimateFrame.v2",
    [
        seq,
        acq_mono_ns,
        est_recv_mono_ns,
        est_done_mono_ns,
        t_s,
        n_states,
        flags,
        state,
        state_sigma,
        residual,
        innovation,
        innovation_sigma,
        measured,
        u_v,
        nis,
        mae_pa,
        th_flags,
        th_state,
        th_residual,
        th_innovation,
        th_mae_pa,
        th_nis
    ],
    added[
        bulk_scale,
        bulk_scale_sigma,
        oil_temp_c,
        oil_temp_sigma_k,
        laminar_factor_sigma,
        null_leakage_band_lpm,
        offset_response_p1_lpm_per_mpa,
        offset_response_p2_lpm_per_mpa,
        span_response_p1_lpm,
        span_response_p2_lpm,
        offset_response_x_lpm_per_mm,
        delay_response_p1_lpm_per_ms,
        delay_response_p2_lpm_per_ms
    ]
);
record!(
    LeakEventFrame,
    "leakwatch.LeakEventFrame.v2",
    [
        seq,
        acq_mono_ns,
        cls_done_mono_ns,
        event_id,
        kind,
        phase,
        t_detect_s,
        t_onset_s,
        size_lpm,
        size_lpm_sigma,
        confidence,
        detector
    ],
    added [
        size_nominal_lpm,
        coefficient_m3_s_sqrt_pa,
        statistic,
        threshold,
        channel,
        detail
    ]
);
record!(
    HealthFrame,
    "leakwatch.HealthFrame.v2",
    [
        seq,
        mono_ns,
        t_s,
        status,
        active_events,
        leak_flow_lpm,
        leak_flow_sigma_lpm
    ],
    added[leak_threshold_lpm]
);
frames::frame_fields!(
    StatsFrame,
    record!(@unpadded StatsFrame, "leakwatch.StatsFrame.v1", [])
);
