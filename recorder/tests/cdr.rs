//! The CDR encoding of the records: its byte layout, its names for codes, its
//! errors, and which estimates the recorder keeps.

use frames::{EstimateFrame, HealthFrame, LeakEventFrame, SensorFrame, StatsFrame, Topic};
use recorder::msg::CDR_LE_HEADER;
use recorder::{GapRecord, Message};

fn bits<T: Copy>(v: &T) -> Vec<u8> {
    // SAFETY: the frames are repr(C) with explicit padding only: every byte is initialised
    unsafe { std::slice::from_raw_parts(v as *const T as *const u8, std::mem::size_of::<T>()).to_vec() }
}

fn sensor() -> SensorFrame {
    SensorFrame {
        seq: 7,
        acq_mono_ns: 123_456_789,
        t_s: 0.007,
        u_v: -1.5,
        x_m: 0.3,
        p1_pa: 6.9e6,
        p2_pa: 4.2e6,
        x_sp_m: f64::NAN,
        f_load_n: f64::INFINITY,
        ref_m: -0.0,
        q_leak_lpm: 5e-324,
        flags: 3,
        _pad: 0,
        temp_c: 41.25,
    }
}

fn estimate() -> EstimateFrame {
    let mut e = EstimateFrame {
        seq: 9,
        acq_mono_ns: 1,
        est_recv_mono_ns: 2,
        est_done_mono_ns: 3,
        t_s: 0.009,
        n_states: 11,
        flags: 17,
        u_v: 0.25,
        nis: 3.0,
        th_flags: 4,
        th_nis: 5.0,
        ..EstimateFrame::default()
    };
    for k in 0..11 {
        e.state[k] = k as f64;
        e.state_sigma[k] = -(k as f64);
    }
    e.th_state = [0.5; 7];
    e.mae_pa = [1.0, 2.0];
    e
}

/// The sensor and estimate frames have natural alignment, so their CDR body is
/// their wire layout (frames/README.md) byte for byte, padding as zeros. A
/// version-1 sensor message (ending after `flags`) reads with `temp_c` absent.
#[test]
fn the_cdr_body_of_the_1_khz_frames_is_their_wire_layout() {
    let mut buf = Vec::new();
    let s = sensor();
    s.to_cdr(&mut buf);
    assert_eq!(buf[..4], CDR_LE_HEADER);
    assert_eq!(buf.len(), 4 + 104);
    assert_eq!(buf[4..], bits(&s)[..]);
    let v1 = SensorFrame::from_cdr(&buf[..4 + 92]).unwrap();
    assert!(v1.temp_c.is_nan());
    assert_eq!(
        bits(&SensorFrame {
            temp_c: s.temp_c,
            ..v1
        }),
        bits(&s)
    );
    let e = estimate();
    e.to_cdr(&mut buf);
    assert_eq!(buf.len(), 4 + 704);
    let mut wire = bits(&e);
    wire[356..360].fill(0); // _pad: CDR alignment padding, zero
    assert_eq!(buf[4..], wire[..]);
    assert_eq!(bits(&EstimateFrame::from_cdr(&buf).unwrap()), wire);
}

#[test]
fn codes_are_names_and_unnamed_codes_their_number() {
    let mut buf = Vec::new();
    let ev = LeakEventFrame {
        kind: frames::event_kind::SENSOR_STUCK,
        phase: frames::event_phase::UPDATED,
        detector: frames::detector_bytes("sensors"),
        channel: frames::text_bytes("p2"),
        detail: frames::text_bytes("stuck at 4.2 MPa for 2.0 s"),
        ..LeakEventFrame::default()
    };
    ev.to_cdr(&mut buf);
    // after seq, acq_mono_ns, cls_done_mono_ns, event_id: "sensor-stuck" with its NUL
    assert_eq!(&buf[36..40], &13u32.to_le_bytes());
    assert_eq!(&buf[40..53], b"sensor-stuck\0");
    assert_eq!(bits(&LeakEventFrame::from_cdr(&buf).unwrap()), bits(&ev));
    for (kind, phase) in [(99, 7), (0, 0), (u32::MAX, u32::MAX)] {
        let x = LeakEventFrame { kind, phase, ..ev };
        x.to_cdr(&mut buf);
        let back = LeakEventFrame::from_cdr(&buf).unwrap();
        assert_eq!((back.kind, back.phase), (kind, phase));
    }
    let h = HealthFrame {
        status: 42,
        ..HealthFrame::default()
    };
    h.to_cdr(&mut buf);
    assert_eq!(HealthFrame::from_cdr(&buf).unwrap().status, 42);
    for stage in [frames::stage::RECORDER, 17] {
        let s = StatsFrame {
            stage,
            ..StatsFrame::default()
        };
        s.to_cdr(&mut buf);
        assert_eq!(bits(&StatsFrame::from_cdr(&buf).unwrap()), bits(&s));
    }
    for topic in Topic::ALL {
        let g = GapRecord {
            topic,
            expected_seq: 1,
            got_seq: 4,
            missing: 3,
            recv_mono_ns: 9,
        };
        g.to_cdr(&mut buf);
        assert_eq!(GapRecord::from_cdr(&buf).unwrap(), g);
    }
}

#[test]
fn a_bad_message_is_an_error_naming_the_type_and_field() {
    let mut buf = Vec::new();
    sensor().to_cdr(&mut buf);
    let e = SensorFrame::from_cdr(&buf[..50]).unwrap_err();
    assert!(
        e.contains("leakwatch_msgs/msg/SensorFrame.p1_pa") && e.contains("ends at byte 50"),
        "{e}"
    );
    let mut be = buf.clone();
    be[1] = 0x00; // big-endian CDR
    let e = SensorFrame::from_cdr(&be).unwrap_err();
    assert!(e.contains("not little-endian plain CDR"), "{e}");
    let e = SensorFrame::from_cdr(&buf[..2]).unwrap_err();
    assert!(e.contains("SensorFrame.seq"), "{e}");
    // a string running past the message
    LeakEventFrame::default().to_cdr(&mut buf);
    buf[36..40].copy_from_slice(&1000u32.to_le_bytes());
    let e = LeakEventFrame::from_cdr(&buf).unwrap_err();
    assert!(e.contains("LeakEventFrame.kind: a string of 1000 bytes"), "{e}");
    // an unknown name
    let mut g = Vec::new();
    GapRecord {
        topic: Topic::Frames,
        expected_seq: 0,
        got_seq: 0,
        missing: 0,
        recv_mono_ns: 0,
    }
    .to_cdr(&mut g);
    g[8..14].copy_from_slice(b"framez");
    let e = GapRecord::from_cdr(&g).unwrap_err();
    assert!(e.contains("unknown topic \"framez\""), "{e}");
    // bytes after the last field (a later version's) are ignored
    sensor().to_cdr(&mut buf);
    buf.extend_from_slice(&[0; 16]);
    assert_eq!(bits(&SensorFrame::from_cdr(&buf).unwrap()), bits(&sensor()));
}

#[test]
fn the_recorder_keeps_every_nth_estimate_and_the_marked_ones() {
    use frames::estimate_flags as fl;
    use recorder::shell::keep_estimate;
    let at = |seq, flags| EstimateFrame {
        seq,
        flags,
        ..EstimateFrame::default()
    };
    let kept: Vec<u64> = (0..1000).filter(|&s| keep_estimate(&at(s, 0), 100)).collect();
    assert_eq!(kept, [0, 100, 200, 300, 400, 500, 600, 700, 800, 900]);
    for flag in [fl::RESET, fl::AFTER_GAP, fl::END_OF_STREAM] {
        assert!(keep_estimate(&at(37, flag | fl::CONVERGING), 100));
    }
    assert!(!keep_estimate(
        &at(37, fl::CONVERGING | fl::SKIPPED | fl::CLAMPED),
        100
    ));
    assert!((0..10).all(|s| keep_estimate(&at(s, 0), 1)));
}

#[test]
fn the_schemas_name_their_types_and_dependencies() {
    assert_eq!(EstimateFrame::MSG_TYPE, "leakwatch_msgs/msg/EstimateFrame");
    let def = EstimateFrame::DEFINITION;
    for dep in ["LeakState", "Measurement", "Pressures", "ThesisState"] {
        assert!(def.contains(&format!("\nMSG: leakwatch_msgs/{dep}\n")), "{dep}");
        assert!(def.contains(&format!("leakwatch_msgs/{dep} ")), "{dep} used");
    }
    assert!(recorder::msg::LEAK_STATE.contains("float64 q_e1_m3_s"));
    assert!(HealthFrame::DEFINITION.contains("MSG: leakwatch_msgs/LeakFlows"));
    for d in [
        SensorFrame::DEFINITION,
        LeakEventFrame::DEFINITION,
        StatsFrame::DEFINITION,
        GapRecord::DEFINITION,
    ] {
        assert!(!d.contains("MSG:"), "no dependencies: {d}");
    }
}

/// A health message of the version before the thresholds (HealthFrame.v1: it
/// ends after `leak_flow_sigma_lpm`) reads with NaN thresholds; a message cut
/// inside the thresholds is an error naming the field.
#[test]
fn a_health_message_without_thresholds_reads_with_nan_ones() {
    let h = HealthFrame {
        seq: 7,
        mono_ns: 9,
        t_s: 1.5,
        status: frames::health_status::LEAK,
        active_events: 1,
        leak_flow_lpm: [0.5, 0.0, 0.01],
        leak_flow_sigma_lpm: [0.01, 0.02, 0.03],
        leak_threshold_lpm: [0.05, 0.06, 0.07],
    };
    let mut buf = Vec::new();
    h.to_cdr(&mut buf);
    assert_eq!(bits(&HealthFrame::from_cdr(&buf).unwrap()), bits(&h));
    let old = &buf[..buf.len() - 24];
    let back = HealthFrame::from_cdr(old).unwrap();
    assert!(back.leak_threshold_lpm.iter().all(|x| x.is_nan()));
    assert_eq!(back.leak_flow_sigma_lpm, h.leak_flow_sigma_lpm);
    assert_eq!((back.seq, back.status, back.active_events), (7, h.status, 1));
    let e = HealthFrame::from_cdr(&buf[..buf.len() - 4]).err().unwrap();
    assert!(e.contains("HealthFrame.leak_threshold_lpm"), "{e}");
}

/// A batch of frames round-trips through its CDR message bit for bit (NaN,
/// infinities, −0, a subnormal, the largest stamps), its shuffled columns laid
/// out byte plane by byte plane; a batch that is cut, empty or whose columns
/// disagree in length is an error naming the field.
#[test]
fn a_frame_batch_round_trips_bit_for_bit_and_a_bad_one_is_named() {
    use recorder::SensorFrameBatch;
    let mut batch = SensorFrameBatch::with_capacity(3);
    let mut frames = Vec::new();
    for k in 0..3u64 {
        let f = SensorFrame {
            seq: u64::MAX - 2 + k,
            acq_mono_ns: u64::MAX - k,
            t_s: [0.1 + 0.2, f64::NAN, -0.0][k as usize],
            u_v: [f64::INFINITY, 5e-324, -1.5][k as usize],
            flags: k as u32,
            ..sensor()
        };
        assert!(batch.push(&f));
        frames.push(f);
    }
    let gap = SensorFrame { seq: 5, ..sensor() };
    assert!(!batch.push(&gap), "a frame that does not follow the last");
    let mut buf = Vec::new();
    batch.to_cdr(&mut buf);
    // first_seq, then the stamps' byte planes: the lowest bytes of the 3 stamps first
    assert_eq!(&buf[4..12], &(u64::MAX - 2).to_le_bytes());
    assert_eq!(&buf[12..16], &24u32.to_le_bytes());
    assert_eq!(&buf[16..19], &[0xFF, 0xFE, 0xFD]);
    let back = SensorFrameBatch::from_cdr(&buf).unwrap();
    let got: Vec<Vec<u8>> = back.frames().map(|f| bits(&f)).collect();
    assert_eq!(got, frames.iter().map(bits).collect::<Vec<_>>());
    let mut out = Vec::new();
    assert_eq!(SensorFrameBatch::append_frames_from_cdr(&buf, &mut out), Ok(3));
    assert_eq!(SensorFrameBatch::last_seq_from_cdr(&buf), Ok(Some(u64::MAX)));
    // cut: the error names a field
    let e = SensorFrameBatch::from_cdr(&buf[..buf.len() - 3]).unwrap_err();
    assert!(e.contains("SensorFrameBatch.temp_c"), "{e}");
    // a t_s column of 2 values in a batch of 3
    let mut bad = buf.clone();
    let at = 40; // after the stamps' 24 bytes (16..40): the length of t_s_shuffled
    assert_eq!(&bad[at..at + 4], &24u32.to_le_bytes());
    bad[at..at + 4].copy_from_slice(&16u32.to_le_bytes());
    let e = SensorFrameBatch::from_cdr(&bad).unwrap_err();
    assert!(
        e.contains("t_s_shuffled: 2 values, the batch has 3 frames"),
        "{e}"
    );
    // an empty batch, and a length the message does not hold
    let mut w = Vec::new();
    SensorFrameBatch::default().to_cdr(&mut w);
    let e = SensorFrameBatch::from_cdr(&w).unwrap_err();
    assert!(e.contains("a batch of no frame"), "{e}");
    let mut huge = buf.clone();
    huge[12..16].copy_from_slice(&u32::MAX.to_le_bytes());
    let e = SensorFrameBatch::from_cdr(&huge).unwrap_err();
    assert!(e.contains("acq_mono_ns_shuffled: an array of"), "{e}");
}
