//! `[udp]`: the scaling of a real rig's UDP stream from raw values to SI, and
//! the addresses it is received on and from.

use std::net::SocketAddr;

use schema::num;
use serde::{Deserialize, Serialize};

schema::config_struct! {
    /// Linear scaling of one channel from what the sender sends to SI:
    /// `SI = gain · raw + offset`. Gain 1, offset 0 (the default): the sender sends SI.
    #[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
    #[serde(default, deny_unknown_fields)]
    pub struct ChannelScale {
        /// SI units per raw unit (e.g. Pa per count); negative for an inverted sensor.
        pub gain: f64 = 1.0 => [
            "SI units per raw unit",
            num!("a number of magnitude", 1e-12, 1e12, "(negative for an inverted sensor)")
        ],
        /// SI value at raw 0, in the channel's SI unit (V, m, Pa, N or °C).
        pub offset: f64 = 0.0 => ["(the channel's SI unit)", num!("a number", -1e9, 1e9)],
    }
}

impl ChannelScale {
    /// The SI value of `raw` (NaN stays NaN).
    #[inline]
    pub fn apply(&self, raw: f64) -> f64 {
        self.gain * raw + self.offset
    }
}

schema::config_struct! {
    /// The `[udp]` section of the configuration: the scaling of each channel of
    /// the UDP stream from raw values to SI (`[udp.p1] gain = 250.0, offset =
    /// -1.0e6` for a pressure sent in counts of 250 Pa from −1 MPa), and the
    /// expected sender (`sender = "192.168.10.20:5005"`). The default, gain 1 and
    /// offset 0 everywhere, means the sender already sends SI. The sample time is
    /// never scaled (seconds).
    #[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
    #[serde(default, deny_unknown_fields)]
    pub struct UdpScaling {
        /// The only address datagrams are taken from, `IP:PORT` of the rig's DAQ
        /// or PLC (its source port must then be fixed); datagrams from any other
        /// address are dropped and counted foreign. `None` (the default): the
        /// first sender of a valid datagram. The acquisition passes it on as
        /// `acquisition::UdpOptions::sender`.
        #[serde(
            deserialize_with = "deserialize_sender",
            skip_serializing_if = "Option::is_none"
        )]
        pub sender: Option<SocketAddr> = None,
        /// Valve command, to V.
        pub u: ChannelScale = ChannelScale::default(),
        /// Rod position, to m.
        pub x: ChannelScale = ChannelScale::default(),
        /// Chamber-1 pressure, to Pa.
        pub p1: ChannelScale = ChannelScale::default(),
        /// Chamber-2 pressure, to Pa.
        pub p2: ChannelScale = ChannelScale::default(),
        /// Spool position, to m.
        pub x_sp: ChannelScale = ChannelScale::default(),
        /// Load force, to N.
        pub f_load: ChannelScale = ChannelScale::default(),
        /// Oil temperature, to °C.
        pub temp_c: ChannelScale = ChannelScale::default(),
    }
}

impl UdpScaling {
    /// Every channel with its name and SI unit.
    fn channels(&self) -> [(&'static str, &'static str, ChannelScale); 7] {
        [
            ("u", "V", self.u),
            ("x", "m", self.x),
            ("p1", "Pa", self.p1),
            ("p2", "Pa", self.p2),
            ("x_sp", "m", self.x_sp),
            ("f_load", "N", self.f_load),
            ("temp_c", "°C", self.temp_c),
        ]
    }

    /// Checks every gain (finite, |gain| within its declared range) and offset
    /// (finite, within its declared range, in the channel's unit), and the
    /// sender (a fixed port, not the unspecified address); the error names the
    /// field, its range and the channel's unit ([`UdpScaling::range_text`]).
    pub fn validate(&self) -> Result<(), String> {
        if let Some(sender) = self.sender {
            parse_sender_address(&sender.to_string())?;
        }
        for (name, _, c) in self.channels() {
            for (field, value, checked) in [("gain", c.gain, c.gain.abs()), ("offset", c.offset, c.offset)] {
                let Some(f) = ChannelScale::SCHEMA.find(&[field]) else {
                    continue;
                };
                if !f.range.holds_number(checked) {
                    return Err(format!(
                        "[udp] {name}.{field} = {value:?}: must be {}",
                        Self::range_text(name, field).unwrap_or_default()
                    ));
                }
            }
        }
        Ok(())
    }

    /// The range of `[udp.<channel>] <field>` (`gain` or `offset`) as its check
    /// states it, in the channel's SI unit (`a number from -1e9 to 1e9 Pa`);
    /// `None` for another channel or field.
    pub fn range_text(channel: &str, field: &str) -> Option<String> {
        let (_, unit, _) = UdpScaling::default()
            .channels()
            .into_iter()
            .find(|(name, _, _)| *name == channel)?;
        let range = ChannelScale::SCHEMA.find(&[field])?.range;
        Some(match field {
            "gain" => range.text(&format!("{unit} per raw unit")),
            _ => range.text(unit),
        })
    }

    /// True if every channel passes through unchanged (gain 1, offset 0).
    pub fn is_identity(&self) -> bool {
        self.channels()
            .iter()
            .all(|(_, _, c)| *c == ChannelScale::default())
    }
}

/// Parses the listening address of a UDP stream, `IP:PORT` (e.g.
/// `0.0.0.0:5005` for every interface, `127.0.0.1:5005`, `[::1]:5005`), with
/// or without a `udp://` prefix. The error names the problem.
pub fn parse_udp_address(text: &str) -> Result<SocketAddr, String> {
    let addr = text.strip_prefix("udp://").unwrap_or(text);
    let parsed: SocketAddr = addr.parse().map_err(|_| {
        format!(
            "`{text}` is not a UDP listening address: expected IP:PORT such as 0.0.0.0:5005 (every interface) \
             or 127.0.0.1:5005 (IPv6: [::1]:5005); host names are not looked up"
        )
    })?;
    if parsed.port() == 0 {
        return Err(format!(
            "`{text}`: port 0 is not a fixed port, the sender could not find it; name a port from 1 to 65535"
        ));
    }
    Ok(parsed)
}

/// Parses the `[udp] sender` of the configuration: the `IP:PORT` datagrams
/// are expected from (e.g. `192.168.10.20:5005`, `[fe80::1]:5005`). The error
/// names the field and the problem: not IP:PORT (host names are not looked
/// up), port 0, or an unspecified address (0.0.0.0, ::), which no datagram comes from.
pub fn parse_sender_address(text: &str) -> Result<SocketAddr, String> {
    let parsed: SocketAddr = text.parse().map_err(|_| {
        format!(
            "[udp] sender = {text:?}: expected the IP:PORT the rig's DAQ or PLC sends from, such as \
             192.168.10.20:5005 (IPv6: [fe80::1]:5005); host names are not looked up"
        )
    })?;
    if parsed.port() == 0 {
        return Err(format!(
            "[udp] sender = {text:?}: port 0 is no sender's port; name the port the sender sends from (1 to 65535)"
        ));
    }
    if parsed.ip().is_unspecified() {
        return Err(format!(
            "[udp] sender = {text:?}: {} is no sender's address; name the address the sender sends from",
            parsed.ip()
        ));
    }
    Ok(parsed)
}

/// `[udp] sender` from its text, checked by [`parse_sender_address`].
fn deserialize_sender<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Option<SocketAddr>, D::Error> {
    let text = String::deserialize(d)?;
    parse_sender_address(&text)
        .map(Some)
        .map_err(serde::de::Error::custom)
}
