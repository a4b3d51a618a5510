//! Layout of the wire types: sizes, alignment, field offsets (the README table), type names.

use core::mem::{align_of, offset_of, size_of};
use frames::*;
use iceoryx2::prelude::ZeroCopySend;

#[test]
fn sizes_and_alignment() {
    assert_eq!(size_of::<SensorFrame>(), 96);
    assert_eq!(size_of::<EstimateFrame>(), 488);
    assert_eq!(size_of::<LeakEventFrame>(), 328);
    assert_eq!(size_of::<HealthFrame>(), 80);
    assert_eq!(size_of::<StatsFrame>(), 112);
    assert_eq!(align_of::<SensorFrame>(), 8);
    assert_eq!(align_of::<EstimateFrame>(), 8);
    assert_eq!(align_of::<LeakEventFrame>(), 8);
    assert_eq!(align_of::<HealthFrame>(), 8);
    assert_eq!(align_of::<StatsFrame>(), 8);
}

/// The offsets tabled in README.md (and mirrored by the Python bindings).
#[test]
fn field_offsets_match_the_readme_table() {
    let s = [
        offset_of!(SensorFrame, seq),
        offset_of!(SensorFrame, acq_mono_ns),
        offset_of!(SensorFrame, t_s),
        offset_of!(SensorFrame, u_v),
        offset_of!(SensorFrame, x_m),
        offset_of!(SensorFrame, p1_pa),
        offset_of!(SensorFrame, p2_pa),
        offset_of!(SensorFrame, x_sp_m),
        offset_of!(SensorFrame, f_load_n),
        offset_of!(SensorFrame, ref_m),
        offset_of!(SensorFrame, q_leak_lpm),
        offset_of!(SensorFrame, flags),
        offset_of!(SensorFrame, _pad),
    ];
    assert_eq!(s, [0, 8, 16, 24, 32, 40, 48, 56, 64, 72, 80, 88, 92]);
    let e = [
        offset_of!(EstimateFrame, seq),
        offset_of!(EstimateFrame, acq_mono_ns),
        offset_of!(EstimateFrame, est_recv_mono_ns),
        offset_of!(EstimateFrame, est_done_mono_ns),
        offset_of!(EstimateFrame, t_s),
        offset_of!(EstimateFrame, n_states),
        offset_of!(EstimateFrame, flags),
        offset_of!(EstimateFrame, state),
        offset_of!(EstimateFrame, state_sigma),
        offset_of!(EstimateFrame, residual),
        offset_of!(EstimateFrame, innovation),
        offset_of!(EstimateFrame, innovation_sigma),
        offset_of!(EstimateFrame, measured),
        offset_of!(EstimateFrame, u_v),
        offset_of!(EstimateFrame, nis),
        offset_of!(EstimateFrame, mae_pa),
        offset_of!(EstimateFrame, th_flags),
        offset_of!(EstimateFrame, _pad),
        offset_of!(EstimateFrame, th_state),
        offset_of!(EstimateFrame, th_residual),
        offset_of!(EstimateFrame, th_innovation),
        offset_of!(EstimateFrame, th_mae_pa),
        offset_of!(EstimateFrame, th_nis),
    ];
    assert_eq!(
        e,
        [
            0, 8, 16, 24, 32, 40, 44, 48, 136, 224, 248, 272, 296, 320, 328, 336, 352, 356, 360, 416, 440,
            464, 480
        ]
    );
    let l = [
        offset_of!(LeakEventFrame, seq),
        offset_of!(LeakEventFrame, acq_mono_ns),
        offset_of!(LeakEventFrame, cls_done_mono_ns),
        offset_of!(LeakEventFrame, event_id),
        offset_of!(LeakEventFrame, kind),
        offset_of!(LeakEventFrame, phase),
        offset_of!(LeakEventFrame, t_detect_s),
        offset_of!(LeakEventFrame, t_onset_s),
        offset_of!(LeakEventFrame, size_lpm),
        offset_of!(LeakEventFrame, size_lpm_sigma),
        offset_of!(LeakEventFrame, confidence),
        offset_of!(LeakEventFrame, detector),
        offset_of!(LeakEventFrame, size_nominal_lpm),
        offset_of!(LeakEventFrame, coefficient_m3_s_sqrt_pa),
        offset_of!(LeakEventFrame, statistic),
        offset_of!(LeakEventFrame, threshold),
        offset_of!(LeakEventFrame, channel),
        offset_of!(LeakEventFrame, detail),
    ];
    assert_eq!(
        l,
        [0, 8, 16, 24, 32, 36, 40, 48, 56, 64, 72, 80, 96, 104, 112, 120, 128, 136]
    );
    let h = [
        offset_of!(HealthFrame, seq),
        offset_of!(HealthFrame, mono_ns),
        offset_of!(HealthFrame, t_s),
        offset_of!(HealthFrame, status),
        offset_of!(HealthFrame, active_events),
        offset_of!(HealthFrame, leak_flow_lpm),
        offset_of!(HealthFrame, leak_flow_sigma_lpm),
    ];
    assert_eq!(h, [0, 8, 16, 24, 28, 32, 56]);
    let st = [
        offset_of!(StatsFrame, mono_ns),
        offset_of!(StatsFrame, pid),
        offset_of!(StatsFrame, stage),
        offset_of!(StatsFrame, frames_in),
        offset_of!(StatsFrame, frames_out),
        offset_of!(StatsFrame, seq_gaps),
        offset_of!(StatsFrame, deadline_misses),
        offset_of!(StatsFrame, proc_ns_p50),
        offset_of!(StatsFrame, proc_ns_p99),
        offset_of!(StatsFrame, proc_ns_max),
        offset_of!(StatsFrame, lat_ns_p50),
        offset_of!(StatsFrame, lat_ns_p99),
        offset_of!(StatsFrame, lat_ns_max),
        offset_of!(StatsFrame, cpu_fraction),
        offset_of!(StatsFrame, rss_bytes),
    ];
    assert_eq!(st, [0, 8, 12, 16, 24, 32, 40, 48, 56, 64, 72, 80, 88, 96, 104]);
}

#[test]
fn type_names_are_versioned() {
    unsafe {
        assert_eq!(SensorFrame::type_name(), "leakwatch.SensorFrame.v1");
        assert_eq!(EstimateFrame::type_name(), "leakwatch.EstimateFrame.v2");
        assert_eq!(LeakEventFrame::type_name(), "leakwatch.LeakEventFrame.v2");
        assert_eq!(HealthFrame::type_name(), "leakwatch.HealthFrame.v1");
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
    ($ty:ty, [$($f:ident),* $(,)?]) => {
        vec![$((stringify!($f).to_string(), offset_of!($ty, $f))),*]
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
        (
            "SensorFrame",
            // SAFETY: type_name only returns the type's static name
            unsafe { SensorFrame::type_name() },
            size_of::<SensorFrame>(),
            fields!(
                SensorFrame,
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
                    flags,
                    _pad
                ]
            ),
        ),
        (
            "EstimateFrame",
            // SAFETY: type_name only returns the type's static name
            unsafe { EstimateFrame::type_name() },
            size_of::<EstimateFrame>(),
            fields!(
                EstimateFrame,
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
                    _pad,
                    th_state,
                    th_residual,
                    th_innovation,
                    th_mae_pa,
                    th_nis
                ]
            ),
        ),
        (
            "LeakEventFrame",
            // SAFETY: type_name only returns the type's static name
            unsafe { LeakEventFrame::type_name() },
            size_of::<LeakEventFrame>(),
            fields!(
                LeakEventFrame,
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
                    detector,
                    size_nominal_lpm,
                    coefficient_m3_s_sqrt_pa,
                    statistic,
                    threshold,
                    channel,
                    detail
                ]
            ),
        ),
        (
            "HealthFrame",
            // SAFETY: type_name only returns the type's static name
            unsafe { HealthFrame::type_name() },
            size_of::<HealthFrame>(),
            fields!(
                HealthFrame,
                [
                    seq,
                    mono_ns,
                    t_s,
                    status,
                    active_events,
                    leak_flow_lpm,
                    leak_flow_sigma_lpm
                ]
            ),
        ),
        (
            "StatsFrame",
            // SAFETY: type_name only returns the type's static name
            unsafe { StatsFrame::type_name() },
            size_of::<StatsFrame>(),
            fields!(
                StatsFrame,
                [
                    mono_ns,
                    pid,
                    stage,
                    frames_in,
                    frames_out,
                    seq_gaps,
                    deadline_misses,
                    proc_ns_p50,
                    proc_ns_p99,
                    proc_ns_max,
                    lat_ns_p50,
                    lat_ns_p99,
                    lat_ns_max,
                    cpu_fraction,
                    rss_bytes
                ]
            ),
        ),
    ];
    for (ty, name, size, fields) in types {
        let (doc_name, doc_size, doc_fields) = readme_section(&readme, ty);
        assert_eq!(doc_name, name, "{ty}: type name in README.md");
        assert_eq!(doc_size, size, "{ty}: size in README.md");
        assert_eq!(doc_fields, fields, "{ty}: the README.md table");
    }
}
