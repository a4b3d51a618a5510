//! The UDP sensor-stream format: how a DAQ board or a PLC sends rig samples to
//! the acquisition stage (`acquisition --udp ADDR:PORT`, `leakwatch run
//! --source udp://ADDR:PORT`). One datagram carries one sample.
//!
//! The datagram is [`LEN`] = 80 bytes (version 2; version 1 is the first
//! [`LEN_V1`] = 72, without `temp_c`, and is read as well), **little-endian**,
//! fixed size, with no padding (table in `frames/README.md`, C header
//! `examples/udp/leakwatch_udp.h`, Python sender `examples/udp/send_csv.py`):
//!
//! | offset | field | type | meaning |
//! |---|---|---|---|
//! | 0 | magic | u8\[4\] | `LWUD` ([`MAGIC`]) |
//! | 4 | version | u16 | [`VERSION`] (2), or 1 |
//! | 6 | flags | u16 | [`flags`]: bit0 x_sp present, bit1 f_load present, bit2 end of stream, bit3 no sample, bit4 temp_c present (version 2) |
//! | 8 | seq | u64 | sequence number, +1 per datagram |
//! | 16 | t | f64 | sample time, s |
//! | 24 | u | f64 | valve command (V after scaling) |
//! | 32 | x | f64 | rod position (m after scaling) |
//! | 40 | p1 | f64 | chamber-1 pressure (Pa after scaling) |
//! | 48 | p2 | f64 | chamber-2 pressure (Pa after scaling) |
//! | 56 | x_sp | f64 | spool position (m after scaling), read only with flag bit0 |
//! | 64 | f_load | f64 | load force (N after scaling), read only with flag bit1 |
//! | 72 | temp_c | f64 | oil temperature (°C after scaling), read only with flag bit4; version 2 only |
//!
//! The channel values are what the sender measured: SI units, or raw counts
//! that the receiver scales (`SI = gain·raw + offset`, the `[udp]` section of
//! the configuration). The sample time is in seconds whatever the scaling.
//!
//! Decoding ([`UdpDatagram::try_from`]) never panics: a datagram of another
//! length, magic or version, with reserved flag bits set, or a non-finite
//! time or required channel is a [`DecodeError`] that names the problem.

use core::fmt;

/// Length of a datagram of this version, bytes.
pub const LEN: usize = 80;
/// Length of a version-1 datagram (no `temp_c`), bytes.
pub const LEN_V1: usize = 72;

/// The first four bytes of every datagram: `LWUD` ("leakwatch UDP").
pub const MAGIC: [u8; 4] = *b"LWUD";

/// The format version this code writes (it reads 1 and 2).
pub const VERSION: u16 = 2;

/// Bits of [`UdpDatagram::flags`].
pub mod flags {
    /// The spool position `x_sp` is present (else it is read as absent, NaN).
    pub const X_SP_PRESENT: u16 = 1 << 0;
    /// The load force `f_load` is present (else it is read as absent, NaN).
    pub const F_LOAD_PRESENT: u16 = 1 << 1;
    /// The stream ends with this datagram.
    pub const END_OF_STREAM: u16 = 1 << 2;
    /// The datagram carries no sample (its sample fields are ignored); only
    /// with [`END_OF_STREAM`], for a sender that learns of the end after its
    /// last sample.
    pub const NO_SAMPLE: u16 = 1 << 3;
    /// The oil temperature `temp_c` is present (version 2; else it is read as absent, NaN).
    pub const TEMP_PRESENT: u16 = 1 << 4;
    /// Every defined bit of version 1; the others are reserved and must be 0.
    pub const ALL_V1: u16 = X_SP_PRESENT | F_LOAD_PRESENT | END_OF_STREAM | NO_SAMPLE;
    /// Every defined bit of version 2; the others are reserved and must be 0.
    pub const ALL: u16 = ALL_V1 | TEMP_PRESENT;
}

/// Byte offset of each field in a datagram.
pub mod offset {
    /// `magic`, u8\[4\].
    pub const MAGIC: usize = 0;
    /// `version`, u16.
    pub const VERSION: usize = 4;
    /// `flags`, u16.
    pub const FLAGS: usize = 6;
    /// `seq`, u64.
    pub const SEQ: usize = 8;
    /// `t`, f64, s.
    pub const T: usize = 16;
    /// `u`, f64.
    pub const U: usize = 24;
    /// `x`, f64.
    pub const X: usize = 32;
    /// `p1`, f64.
    pub const P1: usize = 40;
    /// `p2`, f64.
    pub const P2: usize = 48;
    /// `x_sp`, f64.
    pub const X_SP: usize = 56;
    /// `f_load`, f64.
    pub const F_LOAD: usize = 64;
    /// `temp_c`, f64, °C (version 2).
    pub const TEMP: usize = 72;
}

/// One decoded datagram. The channel values are as sent (SI, or raw counts
/// that `config::udp::UdpScaling` turns into SI); absent optional channels
/// are NaN.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UdpDatagram {
    /// Bit set of [`flags`].
    pub flags: u16,
    /// Sequence number, +1 per datagram of a stream.
    pub seq: u64,
    /// Sample time, s.
    pub t_s: f64,
    /// Valve command: V, or raw counts.
    pub u: f64,
    /// Rod position: m, or raw counts.
    pub x: f64,
    /// Chamber-1 pressure: Pa, or raw counts.
    pub p1: f64,
    /// Chamber-2 pressure: Pa, or raw counts.
    pub p2: f64,
    /// Spool position: m, or raw counts (NaN = absent).
    pub x_sp: f64,
    /// Load force: N, or raw counts (NaN = absent).
    pub f_load: f64,
    /// Oil temperature: °C, or raw counts (NaN = absent).
    pub temp_c: f64,
}

/// Why a datagram was refused.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum DecodeError {
    /// The datagram is not as long as its version says ([`LEN`], [`LEN_V1`]).
    WrongLength {
        /// Its length, bytes.
        len: usize,
    },
    /// The first four bytes are not [`MAGIC`].
    BadMagic {
        /// The bytes found.
        found: [u8; 4],
    },
    /// A version this code does not read.
    UnsupportedVersion {
        /// The version found.
        found: u16,
    },
    /// Reserved flag bits are set, or [`flags::NO_SAMPLE`] without [`flags::END_OF_STREAM`].
    BadFlags {
        /// The flags found.
        found: u16,
    },
    /// The sample time or a channel that must be present is NaN or infinite.
    NonFinite {
        /// The field (`t`, `u`, `x`, `p1`, `p2`, `x_sp`, `f_load`, `temp_c`).
        field: &'static str,
        /// Its value.
        value: f64,
    },
}

impl fmt::Display for DecodeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            DecodeError::WrongLength { len } => {
                write!(
                    f,
                    "wrong length: {len} bytes, a leakwatch datagram has {LEN} (version 2) or {LEN_V1} (version 1)"
                )
            }
            DecodeError::BadMagic { found } => write!(
                f,
                "bad magic {:?} (expected \"LWUD\"): not a leakwatch datagram",
                found.escape_ascii().to_string()
            ),
            DecodeError::UnsupportedVersion { found } => {
                write!(
                    f,
                    "unsupported version {found} (this receiver reads versions 1 and {VERSION})"
                )
            }
            DecodeError::BadFlags { found } => write!(
                f,
                "bad flags {found:#06x} (reserved bits set, or no-sample without end-of-stream)"
            ),
            DecodeError::NonFinite { field, value } => {
                write!(f, "field `{field}` is {value:?} (not finite)")
            }
        }
    }
}

impl std::error::Error for DecodeError {}

fn u16_at(b: &[u8], at: usize) -> u16 {
    u16::from_le_bytes([b[at], b[at + 1]])
}

fn u64_at(b: &[u8], at: usize) -> u64 {
    let mut a = [0u8; 8];
    a.copy_from_slice(&b[at..at + 8]);
    u64::from_le_bytes(a)
}

fn f64_at(b: &[u8], at: usize) -> f64 {
    f64::from_bits(u64_at(b, at))
}

impl UdpDatagram {
    /// A datagram carrying `s` (SI units) with sequence number `seq`: its
    /// optional channels are flagged present where they are not NaN.
    pub fn from_sample(seq: u64, s: &model::Sample) -> UdpDatagram {
        let mut f = 0;
        if !s.x_sp_m.is_nan() {
            f |= flags::X_SP_PRESENT;
        }
        if !s.f_load_n.is_nan() {
            f |= flags::F_LOAD_PRESENT;
        }
        if !s.temp_c.is_nan() {
            f |= flags::TEMP_PRESENT;
        }
        UdpDatagram {
            flags: f,
            seq,
            t_s: s.t_s,
            u: s.u_v,
            x: s.x_m,
            p1: s.p1_pa,
            p2: s.p2_pa,
            x_sp: s.x_sp_m,
            f_load: s.f_load_n,
            temp_c: s.temp_c,
        }
    }

    /// The sample-less end-of-stream datagram with sequence number `seq`.
    pub fn end_of_stream(seq: u64) -> UdpDatagram {
        UdpDatagram {
            flags: flags::END_OF_STREAM | flags::NO_SAMPLE,
            seq,
            t_s: f64::NAN,
            u: f64::NAN,
            x: f64::NAN,
            p1: f64::NAN,
            p2: f64::NAN,
            x_sp: f64::NAN,
            f_load: f64::NAN,
            temp_c: f64::NAN,
        }
    }

    /// True if the stream ends with this datagram.
    pub fn is_end_of_stream(&self) -> bool {
        self.flags & flags::END_OF_STREAM != 0
    }

    /// True if the datagram carries a sample.
    pub fn has_sample(&self) -> bool {
        self.flags & flags::NO_SAMPLE == 0
    }

    /// The datagram's bytes (little-endian).
    pub fn encode(&self) -> [u8; LEN] {
        let mut b = [0u8; LEN];
        b[offset::MAGIC..offset::MAGIC + 4].copy_from_slice(&MAGIC);
        b[offset::VERSION..offset::VERSION + 2].copy_from_slice(&VERSION.to_le_bytes());
        b[offset::FLAGS..offset::FLAGS + 2].copy_from_slice(&self.flags.to_le_bytes());
        b[offset::SEQ..offset::SEQ + 8].copy_from_slice(&self.seq.to_le_bytes());
        for (at, v) in [
            (offset::T, self.t_s),
            (offset::U, self.u),
            (offset::X, self.x),
            (offset::P1, self.p1),
            (offset::P2, self.p2),
            (offset::X_SP, self.x_sp),
            (offset::F_LOAD, self.f_load),
            (offset::TEMP, self.temp_c),
        ] {
            b[at..at + 8].copy_from_slice(&v.to_le_bytes());
        }
        b
    }
}

/// The bytes of a datagram (little-endian).
impl From<&UdpDatagram> for [u8; LEN] {
    fn from(d: &UdpDatagram) -> Self {
        d.encode()
    }
}

/// Decodes and checks one datagram: its length, magic, version (1 or 2, each
/// at its length) and flags; unless it carries no sample, a finite time and
/// finite `u`, `x`, `p1`, `p2` and, where flagged present, `x_sp`, `f_load`
/// and `temp_c` (absent ones read NaN).
impl TryFrom<&[u8]> for UdpDatagram {
    type Error = DecodeError;

    fn try_from(b: &[u8]) -> Result<Self, Self::Error> {
        if b.len() != LEN && b.len() != LEN_V1 {
            return Err(DecodeError::WrongLength { len: b.len() });
        }
        let mut magic = [0u8; 4];
        magic.copy_from_slice(&b[offset::MAGIC..offset::MAGIC + 4]);
        if magic != MAGIC {
            return Err(DecodeError::BadMagic { found: magic });
        }
        let version = u16_at(b, offset::VERSION);
        let (len, defined) = match version {
            1 => (LEN_V1, flags::ALL_V1),
            VERSION => (LEN, flags::ALL),
            found => return Err(DecodeError::UnsupportedVersion { found }),
        };
        if b.len() != len {
            return Err(DecodeError::WrongLength { len: b.len() });
        }
        let fl = u16_at(b, offset::FLAGS);
        if fl & !defined != 0 || (fl & flags::NO_SAMPLE != 0 && fl & flags::END_OF_STREAM == 0) {
            return Err(DecodeError::BadFlags { found: fl });
        }
        let present = |bit: u16, at: usize| {
            if fl & bit != 0 {
                f64_at(b, at)
            } else {
                f64::NAN
            }
        };
        let d = UdpDatagram {
            flags: fl,
            seq: u64_at(b, offset::SEQ),
            t_s: f64_at(b, offset::T),
            u: f64_at(b, offset::U),
            x: f64_at(b, offset::X),
            p1: f64_at(b, offset::P1),
            p2: f64_at(b, offset::P2),
            x_sp: present(flags::X_SP_PRESENT, offset::X_SP),
            f_load: present(flags::F_LOAD_PRESENT, offset::F_LOAD),
            temp_c: present(flags::TEMP_PRESENT, offset::TEMP),
        };
        if d.has_sample() {
            let fields = [
                ("t", d.t_s, true),
                ("u", d.u, true),
                ("x", d.x, true),
                ("p1", d.p1, true),
                ("p2", d.p2, true),
                ("x_sp", d.x_sp, fl & flags::X_SP_PRESENT != 0),
                ("f_load", d.f_load, fl & flags::F_LOAD_PRESENT != 0),
                ("temp_c", d.temp_c, fl & flags::TEMP_PRESENT != 0),
            ];
            if let Some((field, value, _)) = fields
                .into_iter()
                .find(|(_, v, checked)| *checked && !v.is_finite())
            {
                return Err(DecodeError::NonFinite { field, value });
            }
        }
        Ok(d)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample_datagram() -> UdpDatagram {
        let mut s = model::Sample::new(12.345, -2.5, 0.125, 6.9e6, 3.1e6);
        s.f_load_n = -1500.0;
        UdpDatagram::from_sample(41, &s)
    }

    #[test]
    fn encode_then_decode_gives_the_datagram_back() {
        let d = sample_datagram();
        assert_eq!(d.flags, flags::F_LOAD_PRESENT);
        let b = d.encode();
        assert_eq!(&b[..4], b"LWUD");
        assert_eq!(&b[4..8], &[2, 0, 2, 0]);
        assert_eq!(&b[8..16], &41u64.to_le_bytes());
        let back = UdpDatagram::try_from(&b[..]).unwrap();
        assert_eq!(back.seq, 41);
        for (a, b) in [
            (back.t_s, d.t_s),
            (back.u, d.u),
            (back.x, d.x),
            (back.p1, d.p1),
            (back.p2, d.p2),
            (back.f_load, d.f_load),
        ] {
            assert_eq!(a.to_bits(), b.to_bits());
        }
        assert!(back.x_sp.is_nan() && back.temp_c.is_nan());
        assert!(!back.is_end_of_stream() && back.has_sample());
        let mut warm = d;
        warm.temp_c = 41.5;
        warm.flags |= flags::TEMP_PRESENT;
        assert_eq!(UdpDatagram::try_from(&warm.encode()[..]).unwrap().temp_c, 41.5);
        let eos = UdpDatagram::try_from(&UdpDatagram::end_of_stream(7).encode()[..]).unwrap();
        assert!(eos.is_end_of_stream() && !eos.has_sample());
        assert_eq!(eos.seq, 7);
        assert_eq!(<[u8; LEN]>::from(&d), b);
    }

    #[test]
    fn a_version_1_datagram_reads_without_temperature_and_may_not_flag_it() {
        let mut v1 = sample_datagram().encode()[..LEN_V1].to_vec();
        v1[offset::VERSION..offset::VERSION + 2].copy_from_slice(&1u16.to_le_bytes());
        let d = UdpDatagram::try_from(&v1[..]).unwrap();
        assert_eq!(d.f_load, -1500.0);
        assert!(d.temp_c.is_nan());
        v1[offset::FLAGS..offset::FLAGS + 2].copy_from_slice(&flags::TEMP_PRESENT.to_le_bytes());
        let e = UdpDatagram::try_from(&v1[..]).unwrap_err().to_string();
        assert!(e.contains("bad flags 0x0010"), "{e}");
    }

    #[test]
    fn garbage_is_refused_by_name() {
        let good = sample_datagram().encode();
        let with = |at: usize, bytes: &[u8]| {
            let mut b = good;
            b[at..at + bytes.len()].copy_from_slice(bytes);
            b
        };
        let nan = f64::NAN.to_le_bytes();
        let inf = f64::INFINITY.to_le_bytes();
        let cases: Vec<(Vec<u8>, &str)> = vec![
            (vec![], "wrong length: 0 bytes"),
            (good[..71].to_vec(), "wrong length: 71 bytes"),
            (good[..72].to_vec(), "wrong length: 72 bytes"),
            ([&good[..], &[0]].concat(), "wrong length: 81 bytes"),
            (vec![0xff; 1500], "wrong length: 1500 bytes"),
            (with(0, b"LWUE").to_vec(), "bad magic"),
            (vec![0u8; LEN], "bad magic"),
            (with(4, &3u16.to_le_bytes()).to_vec(), "unsupported version 3"),
            (with(4, &1u16.to_le_bytes()).to_vec(), "wrong length: 80 bytes"),
            (with(4, &0u16.to_le_bytes()).to_vec(), "unsupported version 0"),
            (with(6, &0x0020u16.to_le_bytes()).to_vec(), "bad flags 0x0020"),
            (with(6, &flags::NO_SAMPLE.to_le_bytes()).to_vec(), "bad flags"),
            (with(offset::T, &nan).to_vec(), "field `t` is NaN"),
            (with(offset::U, &inf).to_vec(), "field `u` is inf"),
            (with(offset::X, &nan).to_vec(), "field `x` is NaN"),
            (with(offset::P1, &nan).to_vec(), "field `p1` is NaN"),
            (
                with(offset::P2, &(-f64::INFINITY).to_le_bytes()).to_vec(),
                "field `p2` is -inf",
            ),
            (with(offset::F_LOAD, &nan).to_vec(), "field `f_load` is NaN"),
        ];
        for (bytes, expect) in cases {
            let e = UdpDatagram::try_from(&bytes[..]).unwrap_err().to_string();
            assert!(e.contains(expect), "{expect}: {e}");
        }
        // an absent optional channel may hold anything; a no-sample end of stream too
        assert!(UdpDatagram::try_from(&with(offset::X_SP, &nan)[..]).is_ok());
        let mut eos = UdpDatagram::end_of_stream(3).encode();
        eos[offset::T..offset::T + 8].copy_from_slice(&inf);
        assert!(UdpDatagram::try_from(&eos[..]).is_ok());
    }
}
