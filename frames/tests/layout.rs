//! Layout of the wire types: sizes, alignment, field offsets (the README table), type names.

use core::mem::{align_of, offset_of, size_of};
use frames::*;
use iceoryx2::prelude::ZeroCopySend;

#[test]
fn sizes_and_alignment() {
    assert_eq!(size_of::<SensorFrame>(), 96);
    assert_eq!(size_of::<EstimateFrame>(), 488);
    assert_eq!(size_of::<LeakEventFrame>(), 96);
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
    ];
    assert_eq!(l, [0, 8, 16, 24, 32, 36, 40, 48, 56, 64, 72, 80]);
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
        assert_eq!(LeakEventFrame::type_name(), "leakwatch.LeakEventFrame.v1");
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
