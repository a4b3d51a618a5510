//! The UDP datagram format: decoding never panics on arbitrary bytes, the
//! README table is the code's layout, and the C header in examples/udp encodes
//! the same bytes as the Rust encoder.

use std::path::{Path, PathBuf};
use std::process::Command;

use frames::udp::{self, flags, offset, UdpDatagram};
use proptest::prelude::*;

fn cases(default: u32) -> u32 {
    std::env::var("LEAKWATCH_FUZZ_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: cases(2000), ..ProptestConfig::default() })]

    /// Arbitrary bytes of any length: a datagram or a named error, never a panic.
    #[test]
    fn decoding_arbitrary_bytes_never_panics(bytes in proptest::collection::vec(any::<u8>(), 0..200)) {
        match UdpDatagram::try_from(&bytes[..]) {
            // a version-1 datagram encodes as version 2: magic and flags are kept
            Ok(d) => {
                prop_assert_eq!(&d.encode()[..4], &bytes[..4]);
                prop_assert_eq!(&d.encode()[6..16], &bytes[6..16]);
            }
            Err(e) => prop_assert!(!e.to_string().is_empty()),
        }
    }

    /// A valid header with arbitrary flags and payload: decoded, or refused by name;
    /// every accepted datagram has a finite time and required channels.
    #[test]
    fn arbitrary_payloads_behind_a_valid_header(fl in any::<u16>(), payload in proptest::collection::vec(any::<u8>(), udp::LEN - 8)) {
        let mut b = [0u8; udp::LEN];
        b[..4].copy_from_slice(&udp::MAGIC);
        b[4..6].copy_from_slice(&udp::VERSION.to_le_bytes());
        b[6..8].copy_from_slice(&fl.to_le_bytes());
        b[8..].copy_from_slice(&payload);
        match UdpDatagram::try_from(&b[..]) {
            Ok(d) => {
                prop_assert_eq!(d.flags & !flags::ALL, 0);
                if d.has_sample() {
                    prop_assert!([d.t_s, d.u, d.x, d.p1, d.p2].iter().all(|v| v.is_finite()));
                }
            }
            Err(e) => prop_assert!(!e.to_string().is_empty()),
        }
    }

    /// Any finite sample survives encode -> decode bit for bit.
    #[test]
    fn samples_round_trip(seq in any::<u64>(), v in proptest::array::uniform7(-1e12f64..1e12), x_sp in any::<bool>(), eos in any::<bool>()) {
        let mut s = model::Sample::new(v[0], v[1], v[2], v[3], v[4]);
        if x_sp { s.x_sp_m = v[5]; }
        s.f_load_n = v[6];
        let mut d = UdpDatagram::from_sample(seq, &s);
        if eos { d.flags |= flags::END_OF_STREAM; }
        let back = UdpDatagram::try_from(&d.encode()[..]).unwrap();
        prop_assert_eq!(back.seq, seq);
        prop_assert_eq!(back.flags, d.flags);
        prop_assert_eq!(back.is_end_of_stream(), eos);
        for (a, b) in [(back.t_s, d.t_s), (back.u, d.u), (back.x, d.x), (back.p1, d.p1), (back.p2, d.p2), (back.f_load, d.f_load)] {
            prop_assert_eq!(a.to_bits(), b.to_bits());
        }
        prop_assert_eq!(back.x_sp.is_nan(), !x_sp);
    }
}

fn readme() -> String {
    std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/README.md")).expect("README.md")
}

/// frames/README.md tables the datagram as the code lays it out.
#[test]
fn the_readme_table_is_the_datagram() {
    let text = readme();
    let head = "## UdpDatagram: `LWUD` version 2, 80 bytes";
    let start = text.find(head).expect("README.md has the UdpDatagram section");
    let body = &text[start + head.len()..];
    let body = &body[..body.find("\n## ").unwrap_or(body.len())];
    let rows: Vec<(String, usize)> = body
        .lines()
        .filter_map(|l| {
            let cells: Vec<&str> = l.split('|').map(str::trim).collect();
            let at = cells.get(1)?.parse().ok()?;
            Some((cells.get(2)?.to_string(), at))
        })
        .collect();
    let code = [
        ("magic", offset::MAGIC),
        ("version", offset::VERSION),
        ("flags", offset::FLAGS),
        ("seq", offset::SEQ),
        ("t", offset::T),
        ("u", offset::U),
        ("x", offset::X),
        ("p1", offset::P1),
        ("p2", offset::P2),
        ("x_sp", offset::X_SP),
        ("f_load", offset::F_LOAD),
        ("temp_c", offset::TEMP),
    ]
    .map(|(n, o)| (n.to_string(), o));
    assert_eq!(rows, code);
    assert_eq!(udp::LEN, offset::TEMP + 8);
    assert_eq!(udp::LEN_V1, offset::F_LOAD + 8);
    assert_eq!(udp::VERSION, 2);
    assert_eq!(&udp::MAGIC, b"LWUD");
}

fn header() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/udp/leakwatch_udp.h")
}

/// The C header compiles with warnings as errors (C11, pedantic), its packed
/// struct has the table's offsets, and `lwud_encode` writes the bytes the Rust
/// encoder writes.
#[test]
fn the_c_header_encodes_the_same_bytes() {
    let dir = scratch::ScratchDir::new("udp-c");
    let src = dir.join("encode.c");
    let exe = dir.join("encode");
    std::fs::write(
        &src,
        r#"#include <stddef.h>
#include <stdio.h>
#include "leakwatch_udp.h"
int main(void)
{
    struct lwud_sample s = {
        .flags = LWUD_FLAG_X_SP_PRESENT | LWUD_FLAG_F_LOAD_PRESENT | LWUD_FLAG_END_OF_STREAM
            | LWUD_FLAG_TEMP_PRESENT,
        .seq = 0x0102030405060708ull,
        .t = 12.345, .u = -2.5, .x = 0.125, .p1 = 6.9e6, .p2 = 3.1e6, .x_sp = 1e-5, .f_load = -1500.0,
        .temp_c = 47.25,
    };
    uint8_t b[LWUD_LEN];
    lwud_encode(&s, b);
    for (unsigned i = 0; i < LWUD_LEN; i++) {
        printf("%02x", b[i]);
    }
    printf("\n%zu %zu %zu %zu %zu %zu %zu %zu %zu %zu %zu %zu %zu\n",
           offsetof(struct lwud_datagram, magic), offsetof(struct lwud_datagram, version),
           offsetof(struct lwud_datagram, flags), offsetof(struct lwud_datagram, seq),
           offsetof(struct lwud_datagram, t), offsetof(struct lwud_datagram, u),
           offsetof(struct lwud_datagram, x), offsetof(struct lwud_datagram, p1),
           offsetof(struct lwud_datagram, p2), offsetof(struct lwud_datagram, x_sp),
           offsetof(struct lwud_datagram, f_load), offsetof(struct lwud_datagram, temp_c),
           sizeof(struct lwud_datagram));
    return 0;
}
"#,
    )
    .unwrap();
    let include = header().parent().unwrap().to_path_buf();
    let cc = Command::new("cc")
        .args([
            "-std=c11",
            "-Wall",
            "-Wextra",
            "-Werror",
            "-pedantic",
            "-O1",
            "-I",
        ])
        .arg(&include)
        .arg(&src)
        .arg("-o")
        .arg(&exe)
        .output()
        .expect("a C compiler `cc` is on PATH (gcc or clang)");
    assert!(
        cc.status.success(),
        "cc failed:\n{}",
        String::from_utf8_lossy(&cc.stderr)
    );
    let out = Command::new(&exe).output().unwrap();
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout).unwrap();
    let mut lines = text.lines();
    let c_hex = lines.next().unwrap();
    let d = UdpDatagram {
        flags: flags::X_SP_PRESENT | flags::F_LOAD_PRESENT | flags::END_OF_STREAM | flags::TEMP_PRESENT,
        seq: 0x0102030405060708,
        t_s: 12.345,
        u: -2.5,
        x: 0.125,
        p1: 6.9e6,
        p2: 3.1e6,
        x_sp: 1e-5,
        f_load: -1500.0,
        temp_c: 47.25,
    };
    let rust_hex: String = d.encode().iter().map(|b| format!("{b:02x}")).collect();
    assert_eq!(c_hex, rust_hex);
    let offsets: Vec<usize> = lines
        .next()
        .unwrap()
        .split(' ')
        .map(|v| v.parse().unwrap())
        .collect();
    assert_eq!(
        offsets,
        [
            offset::MAGIC,
            offset::VERSION,
            offset::FLAGS,
            offset::SEQ,
            offset::T,
            offset::U,
            offset::X,
            offset::P1,
            offset::P2,
            offset::X_SP,
            offset::F_LOAD,
            offset::TEMP,
            udp::LEN
        ]
    );
    // and the C bytes decode in Rust
    let bytes: Vec<u8> = (0..udp::LEN)
        .map(|i| u8::from_str_radix(&c_hex[2 * i..2 * i + 2], 16).unwrap())
        .collect();
    assert_eq!(UdpDatagram::try_from(&bytes[..]).unwrap(), d);
}
