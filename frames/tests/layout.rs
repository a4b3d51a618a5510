//! Layout of the wire types: sizes, alignment, field offsets (the README table), type names.

use core::mem::{align_of, offset_of, size_of};
use frames::*;
use iceoryx2::prelude::ZeroCopySend;

#[test]
fn sizes_and_alignment() {
    assert_eq!(size_of::<SensorFrame>(), 104);
    assert_eq!(size_of::<EstimateFrame>(), 704);
    assert_eq!(size_of::<LeakEventFrame>(), 520);
    assert_eq!(size_of::<HealthFrame>(), 104);
    assert_eq!(size_of::<StatsFrame>(), 112);
    assert_eq!(align_of::<SensorFrame>(), 8);
    assert_eq!(align_of::<EstimateFrame>(), 8);
    assert_eq!(align_of::<LeakEventFrame>(), 8);
    assert_eq!(align_of::<HealthFrame>(), 8);
    assert_eq!(align_of::<StatsFrame>(), 8);
}

/// The offset of every field of a type, in the order of [`frame_fields!`].
macro_rules! offsets {
    ($ty:ident [$($f:ident),* $(,)?]) => {
        [$(offset_of!($ty, $f)),*]
    };
}

/// The offsets tabled in README.md (and mirrored by the Python bindings).
#[test]
fn field_offsets_match_the_readme_table() {
    let s = frame_fields!(SensorFrame, offsets!(SensorFrame));
    assert_eq!(s, [0, 8, 16, 24, 32, 40, 48, 56, 64, 72, 80, 88, 92, 96]);
    let e = frame_fields!(EstimateFrame, offsets!(EstimateFrame));
    assert_eq!(
        e,
        [
            0, 8, 16, 24, 32, 40, 44, 48, 136, 224, 248, 272, 296, 320, 328, 336, 352, 356, 360, 416, 440,
            464, 480, 488, 496, 504, 512, 520, 528, 536, 560, 584, 608, 632, 656, 680
        ]
    );
    let l = frame_fields!(LeakEventFrame, offsets!(LeakEventFrame));
    assert_eq!(
        l,
        [0, 8, 16, 24, 32, 36, 40, 48, 56, 64, 72, 80, 96, 104, 112, 120, 128, 136]
    );
    let h = frame_fields!(HealthFrame, offsets!(HealthFrame));
    assert_eq!(h, [0, 8, 16, 24, 28, 32, 56, 80]);
    let st = frame_fields!(StatsFrame, offsets!(StatsFrame));
    assert_eq!(st, [0, 8, 12, 16, 24, 32, 40, 48, 56, 64, 72, 80, 88, 96, 104]);
}

#[test]
fn type_names_are_versioned() {
    unsafe {
        assert_eq!(SensorFrame::type_name(), "leakwatch.SensorFrame.v2");
        assert_eq!(EstimateFrame::type_name(), "leakwatch.EstimateFrame.v6");
        assert_eq!(LeakEventFrame::type_name(), "leakwatch.LeakEventFrame.v3");
        assert_eq!(HealthFrame::type_name(), "leakwatch.HealthFrame.v2");
        assert_eq!(StatsFrame::type_name(), "leakwatch.StatsFrame.v1");
    }
}

#[test]
fn rig_ids_and_service_names() {
    let rig = RigId::new("rig-7_a").unwrap();
    assert_eq!(service_name(&rig, Topic::Frames), "leakwatch/rig-7_a/frames");
    assert_eq!(
        wake_service_name(&rig, Topic::Stats),
        "leakwatch/rig-7_a/stats/wake"
    );
    for bad in ["", "a/b", "rig 1", "ü", &"x".repeat(33)] {
        let e = RigId::new(bad).unwrap_err().to_string();
        assert!(e.contains("invalid rig id"), "{e}");
    }
    assert!(RigId::new(&"x".repeat(32)).is_ok());
}

#[test]
fn detector_names_round_trip() {
    let b = detector_bytes("cusum");
    assert_eq!(&b[..6], b"cusum\0");
    assert_eq!(detector_name(&b), "cusum");
    assert_eq!(
        detector_name(&detector_bytes("a-very-long-detector-name")),
        "a-very-long-dete"
    );
}

#[test]
fn texts_are_cut_at_a_character_boundary() {
    // "√" is 3 bytes in UTF-8: 2 + 3 fits 5 bytes, a second one does not
    let b: [u8; 6] = text_bytes("ab√√");
    assert_eq!(text(&b), "ab√");
    assert_eq!(&b[5..], &[0]);
    let b: [u8; 4] = text_bytes("p1");
    assert_eq!(text(&b), "p1");
    let b: [u8; 3] = text_bytes("a\0b");
    assert_eq!(text(&b), "ab");
}

#[test]
fn samples_round_trip_through_sensor_frames() {
    let mut s = model::Sample::new(1.25, -3.5, 0.2, 7.0e6, 6.5e6);
    s.x_sp_m = 1e-5;
    s.q_leak_lpm = 0.25;
    let f = SensorFrame::from(&s);
    assert_eq!((f.seq, f.acq_mono_ns, f.flags), (0, 0, 0));
    let back = model::Sample::from(&f);
    assert_eq!(back.t_s, 1.25);
    assert_eq!(back.p2_pa, 6.5e6);
    assert_eq!(back.q_leak_lpm, 0.25);
    assert!(back.f_load_n.is_nan() && back.ref_m.is_nan());
}

/// (field, offset) of every field of a type, in declaration order.
macro_rules! fields {
    ($ty:ident [$($f:ident),* $(,)?]) => {
        vec![$((stringify!($f).to_string(), offset_of!($ty, $f))),*]
    };
}

/// A type's name, iceoryx2 type name, size and (field, offset) rows.
macro_rules! layout {
    ($ty:ident) => {
        (
            stringify!($ty),
            // SAFETY: type_name only returns the type's static name
            unsafe { $ty::type_name() },
            size_of::<$ty>(),
            frame_fields!($ty, fields!($ty)),
        )
    };
}

/// The README's section of a type: its type name, its size and its table's (field, offset) rows.
fn readme_section(readme: &str, ty: &str) -> (String, usize, Vec<(String, usize)>) {
    let head = format!("## {ty}: `");
    let start = readme
        .find(&head)
        .unwrap_or_else(|| panic!("README.md has no section for {ty}"));
    let body = &readme[start + head.len()..];
    let end = body.find("\n## ").unwrap_or(body.len());
    let body = &body[..end];
    let name = body.split('`').next().unwrap_or_default().to_string();
    let size: usize = body
        .split("`, ")
        .nth(1)
        .and_then(|r| r.split(' ').next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("{ty}: no size in the README heading"));
    let rows = body
        .lines()
        .filter_map(|l| {
            let cells: Vec<&str> = l.split('|').map(str::trim).collect();
            let offset = cells.get(1)?.parse().ok()?;
            Some((cells.get(2)?.to_string(), offset))
        })
        .collect();
    (name, size, rows)
}

/// frames/README.md is checked against the types: every section's type name,
/// size and table of offsets are the code's.
#[test]
fn the_readme_tables_are_the_types() {
    let readme =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/README.md")).expect("README.md");
    let types = [
        layout!(SensorFrame),
        layout!(EstimateFrame),
        layout!(LeakEventFrame),
        layout!(HealthFrame),
        layout!(StatsFrame),
    ];
    for (ty, name, size, fields) in types {
        let (doc_name, doc_size, doc_fields) = readme_section(&readme, ty);
        assert_eq!(doc_name, name, "{ty}: type name in README.md");
        assert_eq!(doc_size, size, "{ty}: size in README.md");
        assert_eq!(doc_fields, fields, "{ty}: the README.md table");
    }
}
