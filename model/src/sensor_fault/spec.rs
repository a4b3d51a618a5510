//! The text form of a sensor fault: `CHANNEL:KIND[=VALUE][,KEY=VALUE]@ONSET`.

use super::{Channel, SensorFault, SensorFaultKind, SensorFaultSpecError};

const PRESSURE_UNITS: [(&str, f64); 4] = [("Pa", 1.0), ("kPa", 1e3), ("MPa", 1e6), ("bar", 1e5)];
const LENGTH_UNITS: [(&str, f64); 4] = [("m", 1.0), ("mm", 1e-3), ("um", 1e-6), ("µm", 1e-6)];
const TIME_UNITS: [(&str, f64); 2] = [("s", 1.0), ("min", 60.0)];

/// Splits `text` into its leading number and the rest (its unit).
fn split_number(text: &str) -> (&str, &str) {
    let end = text
        .find(|c: char| !(c.is_ascii_digit() || matches!(c, '.' | '+' | '-' | 'e' | 'E')))
        .unwrap_or(text.len());
    text.split_at(end)
}

fn number(text: &str, what: &str) -> Result<f64, String> {
    let v: f64 = text
        .trim()
        .parse()
        .map_err(|_| format!("{what} `{text}` is not a number"))?;
    if v.is_finite() {
        Ok(v)
    } else {
        Err(format!("{what} `{text}` is not a finite number"))
    }
}

/// `text` (e.g. `500kPa`, `1.5mm`) in channel `ch`'s SI unit, Pa or m.
fn quantity(text: &str, ch: Channel, what: &str) -> Result<f64, String> {
    let (num, unit) = split_number(text.trim());
    let (units, reads, examples) = if ch.is_pressure() {
        (&PRESSURE_UNITS, "a pressure", "Pa, kPa, MPa or bar")
    } else {
        (&LENGTH_UNITS, "a position", "m, mm or um")
    };
    if num.is_empty() {
        return Err(format!("{what} `{text}` does not start with a number"));
    }
    if unit.is_empty() {
        return Err(format!("{what} `{text}` needs a unit: {examples}"));
    }
    let Some(&(_, factor)) = units.iter().find(|(u, _)| *u == unit) else {
        let other = if ch.is_pressure() {
            &LENGTH_UNITS
        } else {
            &PRESSURE_UNITS
        };
        if other.iter().any(|(u, _)| *u == unit) {
            return Err(format!(
                "{what} `{text}`: {} reads {reads}, so the unit is one of {examples}, not `{unit}`",
                ch.name()
            ));
        }
        return Err(format!(
            "{what} `{text}`: unknown unit `{unit}`: expected {examples}"
        ));
    };
    Ok(number(num, what)? * factor)
}

/// `text` as a rate per second: `QUANTITY/s` or `QUANTITY/min` (a quantity of
/// channel `ch`, or a bare count when `ch` is None).
fn per_second(text: &str, ch: Option<Channel>, what: &str) -> Result<f64, String> {
    let text = text.trim();
    if ch.is_none() {
        if let Some(hz) = text.strip_suffix("Hz") {
            return number(hz, what);
        }
    }
    let Some((amount, time)) = text.rsplit_once('/') else {
        let example = match ch {
            Some(c) if c.is_pressure() => "200kPa/min",
            Some(_) => "1mm/min",
            None => "0.5/s",
        };
        return Err(format!(
            "{what} `{text}` needs a time unit: /s or /min, e.g. {example}"
        ));
    };
    let Some(&(_, seconds)) = TIME_UNITS.iter().find(|(u, _)| *u == time.trim()) else {
        return Err(format!(
            "{what} `{text}`: unknown time unit `/{time}`: expected /s or /min"
        ));
    };
    let amount = match ch {
        Some(ch) => quantity(amount, ch, what)?,
        None => number(amount, what)?,
    };
    Ok(amount / seconds)
}

fn onset(text: &str) -> Result<f64, String> {
    let t = text.trim();
    let v = number(t.strip_suffix('s').unwrap_or(t), "onset")?;
    if v < 0.0 {
        return Err(format!("onset `{t}` must be 0 s or later"));
    }
    Ok(v)
}

/// The options `KEY=VALUE` of a spec, each taken once.
struct Options<'a>(Vec<(&'a str, &'a str)>);

impl<'a> Options<'a> {
    fn take(&mut self, key: &str) -> Option<&'a str> {
        let i = self.0.iter().position(|(k, _)| *k == key)?;
        Some(self.0.remove(i).1)
    }

    fn none_left(&self, kind: &str, allowed: &str) -> Result<(), String> {
        match self.0.first() {
            None => Ok(()),
            Some((k, _)) => Err(format!("unknown option `{k}` for {kind}: {allowed}")),
        }
    }
}

fn kind(name: &str, value: Option<&str>, opts: &mut Options, ch: Channel) -> Result<SensorFaultKind, String> {
    let need = |example: &str| value.ok_or_else(|| format!("{name} needs a value, e.g. {example}"));
    let kind = match name {
        "drift" => {
            let example = if ch.is_pressure() {
                "drift=200kPa/min"
            } else {
                "drift=1mm/min"
            };
            let rate_si_per_s = per_second(need(example)?, Some(ch), "drift rate")?;
            let max_abs_si = match opts.take("max") {
                Some(m) => quantity(m, ch, "max")?.abs(),
                None => f64::INFINITY,
            };
            opts.none_left("drift", "expected max")?;
            SensorFaultKind::Drift {
                rate_si_per_s,
                max_abs_si,
            }
        }
        "span" => {
            let v = need("span=+2%")?.trim();
            let Some(pct) = v.strip_suffix('%') else {
                return Err(format!("span `{v}` needs a unit: a percentage, e.g. +2%"));
            };
            let ramp_s = match opts.take("ramp") {
                Some(r) => {
                    let r = r.trim();
                    let secs = r.strip_suffix('s').unwrap_or(r);
                    number(secs, "span ramp")?
                }
                None => 0.0,
            };
            opts.none_left("span", "expected ramp")?;
            SensorFaultKind::Span {
                gain_error: number(pct, "span")? / 100.0,
                ramp_s,
            }
        }
        "stuck" => {
            if let Some(v) = value {
                return Err(format!("stuck takes no value (`stuck={v}`): e.g. p1:stuck@40s"));
            }
            opts.none_left("stuck", "it has none")?;
            SensorFaultKind::Stuck
        }
        "spikes" => {
            let example = if ch.is_pressure() {
                "spikes=2MPa,rate=0.5/s"
            } else {
                "spikes=5mm,rate=0.5/s"
            };
            let amplitude_si = quantity(need(example)?, ch, "spike amplitude")?;
            let rate = opts
                .take("rate")
                .ok_or_else(|| format!("spikes need a rate, e.g. {example}"))?;
            let rate_hz = per_second(rate, None, "spike rate")?;
            opts.none_left("spikes", "expected rate")?;
            SensorFaultKind::Spikes {
                amplitude_si,
                rate_hz,
            }
        }
        other => {
            return Err(format!(
                "unknown sensor fault `{other}`: expected drift, span, stuck or spikes"
            ))
        }
    };
    Ok(kind)
}

impl SensorFault {
    /// Parses `CHANNEL:KIND[=VALUE][,KEY=VALUE]@ONSET` (options may also follow
    /// the onset): CHANNEL is `p1`, `p2` or `x`; KIND is `drift=RATE[,max=SIZE]`,
    /// `span=±PERCENT%[,ramp=SECONDS]`, `stuck` or `spikes=SIZE,rate=COUNT/s`. Pressures in Pa,
    /// kPa, MPa or bar, positions in m, mm or um, rates per s or per min; the
    /// onset in s. The values are checked ([`SensorFault::validate`]).
    pub fn parse(spec: &str) -> Result<SensorFault, SensorFaultSpecError> {
        let err = |message: String| SensorFaultSpecError {
            spec: spec.to_string(),
            message,
        };
        let (channel, rest) = spec.split_once(':').ok_or_else(|| {
            err("expected CHANNEL:KIND@ONSET, e.g. p1:drift=200kPa/min,max=500kPa@30s".into())
        })?;
        let channel = Channel::from_name(channel.trim())
            .ok_or_else(|| err(format!("unknown channel `{channel}`: expected p1, p2 or x")))?;
        let (body, tail) = rest
            .split_once('@')
            .ok_or_else(|| err("missing `@ONSET` (e.g. @30s)".into()))?;
        let mut tail_parts = tail.split(',');
        let onset_s = onset(tail_parts.next().unwrap_or("")).map_err(&err)?;
        let mut parts = body.split(',');
        let head = parts.next().unwrap_or("").trim();
        let (name, value) = match head.split_once('=') {
            Some((n, v)) => (n.trim(), Some(v)),
            None => (head, None),
        };
        let mut opts = Vec::new();
        for opt in parts.chain(tail_parts) {
            let (k, v) = opt
                .split_once('=')
                .ok_or_else(|| err(format!("option `{opt}` should be KEY=VALUE")))?;
            opts.push((k.trim(), v));
        }
        let kind = kind(name, value, &mut Options(opts), channel).map_err(err)?;
        let fault = SensorFault {
            channel,
            kind,
            onset_s,
        };
        fault.validate().map_err(|e| err(e.to_string()))?;
        Ok(fault)
    }
}

/// The spec in SI units (Pa, m, per second), which [`SensorFault::parse`] reads back.
impl std::fmt::Display for SensorFault {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let unit = self.channel.si_unit();
        write!(f, "{}:", self.channel.name())?;
        match self.kind {
            SensorFaultKind::Drift {
                rate_si_per_s,
                max_abs_si,
            } => {
                write!(f, "drift={rate_si_per_s}{unit}/s")?;
                if max_abs_si.is_finite() {
                    write!(f, ",max={max_abs_si}{unit}")?;
                }
            }
            SensorFaultKind::Span { gain_error, ramp_s } => {
                write!(f, "span={:+}%", gain_error * 100.0)?;
                if ramp_s > 0.0 {
                    write!(f, ",ramp={ramp_s}s")?;
                }
            }
            SensorFaultKind::Stuck => write!(f, "stuck")?,
            SensorFaultKind::Spikes {
                amplitude_si,
                rate_hz,
            } => write!(f, "spikes={amplitude_si}{unit},rate={rate_hz}/s")?,
        }
        write!(f, "@{}s", self.onset_s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_documented_specs_parse_to_si_and_round_trip() {
        let f = SensorFault::parse("p1:drift=200kPa/min,max=500kPa@30s").unwrap();
        assert_eq!((f.channel, f.onset_s), (Channel::P1, 30.0));
        let SensorFaultKind::Drift {
            rate_si_per_s,
            max_abs_si,
        } = f.kind
        else {
            panic!("{f:?}")
        };
        assert!((rate_si_per_s - 200e3 / 60.0).abs() < 1e-9 && max_abs_si == 500e3);
        let f = SensorFault::parse("x:drift=-1mm/min@10s").unwrap();
        assert_eq!(f.drift_offset_si(9.0), 0.0);
        assert!(
            (f.drift_offset_si(70.0) + 1e-3).abs() < 1e-15,
            "{}",
            f.drift_offset_si(70.0)
        );
        assert_eq!(
            SensorFault::parse("p1:span=+3%,ramp=90s@5s").unwrap().kind,
            SensorFaultKind::Span {
                gain_error: 0.03,
                ramp_s: 90.0
            }
        );
        assert_eq!(
            SensorFault::parse("p2:span=-1.5%@20").unwrap().kind,
            SensorFaultKind::Span {
                gain_error: -0.015,
                ramp_s: 0.0
            }
        );
        assert_eq!(
            SensorFault::parse("p2:spikes=20bar,rate=30/min@0s").unwrap().kind,
            SensorFaultKind::Spikes {
                amplitude_si: 2e6,
                rate_hz: 0.5
            }
        );
        // options may follow the onset, as in a leak fault's spec
        assert_eq!(
            SensorFault::parse("p1:drift=200kPa/min@30s,max=0.5MPa"),
            SensorFault::parse("p1:drift=200kPa/min,max=500kPa@30s")
        );
        for spec in [
            "p1:drift=200kPa/min,max=500kPa@30s",
            "p2:span=+2%@20s",
            "p1:span=-1.5%,ramp=60s@10s",
            "p1:stuck@40s",
            "x:drift=1mm/min@10s",
            "p2:spikes=2MPa,rate=0.5/s@0s",
            "x:spikes=5mm,rate=2Hz@1.5s",
        ] {
            let f = SensorFault::parse(spec).unwrap();
            let text = f.to_string();
            assert_eq!(SensorFault::parse(&text), Ok(f), "{spec} -> {text}");
        }
        assert_eq!(
            SensorFault::parse("p1:drift=200kPa/min,max=500kPa@30s")
                .unwrap()
                .to_string(),
            "p1:drift=3333.3333333333335Pa/s,max=500000Pa@30s"
        );
        assert_eq!(
            SensorFault::parse("p2:span=+2%@20s").unwrap().to_string(),
            "p2:span=+2%@20s"
        );
    }

    #[test]
    fn bad_specs_name_the_bad_part() {
        for (spec, needle) in [
            ("p1", "expected CHANNEL:KIND@ONSET"),
            ("p3:stuck@1s", "unknown channel `p3`"),
            ("p1:stuck", "missing `@ONSET`"),
            ("p1:stuck@soon", "onset `soon` is not a number"),
            ("p1:stuck@-3s", "onset `-3s` must be 0 s or later"),
            ("p1:wobble@3s", "unknown sensor fault `wobble`"),
            ("p1:stuck=2@3s", "stuck takes no value"),
            ("p1:drift@3s", "drift needs a value, e.g. drift=200kPa/min"),
            (
                "p1:drift=200@3s",
                "`200` needs a time unit: /s or /min, e.g. 200kPa/min",
            ),
            ("p1:drift=200kPa/h@3s", "unknown time unit `/h`"),
            (
                "p1:drift=200psi/min@3s",
                "unknown unit `psi`: expected Pa, kPa, MPa or bar",
            ),
            (
                "x:drift=200kPa/min@3s",
                "x reads a position, so the unit is one of m, mm or um, not `kPa`",
            ),
            (
                "p2:drift=1mm/min@3s",
                "p2 reads a pressure, so the unit is one of Pa, kPa, MPa or bar",
            ),
            ("p1:drift=abckPa/min@3s", "`abckPa` does not start with a number"),
            ("p1:drift=1.2.3kPa/min@3s", "drift rate `1.2.3` is not a number"),
            (
                "p1:drift=200kPa/min,max=0kPa@3s",
                "sensor_fault.p1.drift.max_abs_si",
            ),
            (
                "p1:drift=200kPa/min,top=5kPa@3s",
                "unknown option `top` for drift: expected max",
            ),
            ("p1:drift=200kPa/min,max@3s", "option `max` should be KEY=VALUE"),
            ("p1:span=2@3s", "span `2` needs a unit: a percentage"),
            ("p1:span=+80%@3s", "sensor_fault.p1.span.gain_error"),
            ("p1:spikes=2MPa@0s", "spikes need a rate"),
            ("p1:spikes=2MPa,rate=0.5@0s", "spike rate `0.5` needs a time unit"),
            ("p1:spikes=2MPa,rate=1000/s@0s", "sensor_fault.p1.spikes.rate_hz"),
            (
                "p1:spikes=-2MPa,rate=1/s@0s",
                "sensor_fault.p1.spikes.amplitude_si",
            ),
        ] {
            let e = SensorFault::parse(spec).unwrap_err().to_string();
            assert!(e.starts_with(&format!("bad sensor fault spec `{spec}`: ")), "{e}");
            assert!(e.contains(needle), "{spec}: {e}");
        }
    }
}
