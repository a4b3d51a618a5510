//! Lost, duplicated, reordered, malformed and out-of-range datagrams counted exactly; scaling.

use std::net::UdpSocket;

use acquisition::{Acquired, Source, UdpCounts, UdpEnd, UdpOptions, UdpSource};
use config::udp::{ChannelScale, UdpScaling};
use frames::udp::{flags, UdpDatagram};

use crate::{datagram, drain, identity, sample, seqs, source};

#[test]
fn lost_duplicated_reordered_and_malformed_datagrams_are_counted_exactly() {
    let (mut src, tx, to) = source(5.0);
    let mut nan_p1 = UdpDatagram::from_sample(108, &sample(108));
    nan_p1.p1 = f64::NAN;
    let mut bad_magic = datagram(200);
    bad_magic[..4].copy_from_slice(b"XXXX");
    let mut last = UdpDatagram::from_sample(110, &sample(110));
    last.flags |= flags::END_OF_STREAM;
    let sends: Vec<Vec<u8>> = vec![
        datagram(100).to_vec(),
        datagram(101).to_vec(),
        datagram(102).to_vec(),
        // 103 lost
        datagram(104).to_vec(),
        datagram(104).to_vec(), // duplicated
        datagram(106).to_vec(),
        datagram(105).to_vec(), // reordered: late
        b"hello, not a datagram".to_vec(),
        datagram(107).to_vec(),
        bad_magic.to_vec(),
        nan_p1.encode().to_vec(), // 108 malformed (p1 NaN)
        datagram(109).to_vec(),
        last.encode().to_vec(),
    ];
    for d in &sends {
        tx.send_to(d, to).unwrap();
    }
    let items = drain(&mut src);
    assert_eq!(
        seqs(&items),
        [
            (100, 0),
            (101, 0),
            (102, 0),
            (104, 1),
            (106, 1),
            (107, 0),
            (109, 1),
            (110, 0)
        ]
    );
    assert!(src.ended());
    assert_eq!(src.end(), Some(UdpEnd::LastSample));
    assert!(src.next_item().is_none());
    assert_eq!(
        src.counts(),
        UdpCounts {
            datagrams: 13,
            samples: 8,
            lost: 3,
            duplicated: 1,
            late: 1,
            malformed: 3,
            rejected: 0,
            foreign: 0,
            wrong_rate: 0,
            reboots: 0,
            time_jumps: 0,
            rate_errors: 0,
        }
    );
    let c = src.counts();
    assert_eq!(c.datagrams, identity(&c));
    // the samples are passed on bit for bit
    match &items[5] {
        Acquired::Sample(s) => {
            let want = sample(107);
            assert_eq!(s.p1_pa.to_bits(), want.p1_pa.to_bits());
            assert_eq!(s.x_m.to_bits(), want.x_m.to_bits());
            assert_eq!(s.f_load_n, -100.0);
            assert!(s.x_sp_m.is_nan() && s.ref_m.is_nan());
        }
        other => panic!("{other:?}"),
    }
    let summary = src.summary().unwrap();
    assert!(
        summary.contains(
            "13 datagrams: 8 samples, 3 lost, 1 duplicated, 1 late (reordered), 3 malformed, 0 rejected"
        ),
        "{summary}"
    );
    assert!(summary.contains("the sender's last sample"), "{summary}");
}

#[test]
fn out_of_range_samples_and_time_going_back_are_rejected_and_reported_as_gaps() {
    let (mut src, tx, to) = source(5.0);
    let mut high = UdpDatagram::from_sample(2, &sample(2));
    high.p2 = 1e9; // beyond 1.5 p_s
    let mut back_in_time = UdpDatagram::from_sample(3, &sample(3));
    back_in_time.t_s = 0.0005;
    for d in [
        datagram(0),
        datagram(1),
        high.encode(),
        back_in_time.encode(),
        datagram(4),
        UdpDatagram::end_of_stream(5).encode(),
    ] {
        tx.send_to(&d, to).unwrap();
    }
    let items = drain(&mut src);
    assert_eq!(seqs(&items), [(0, 0), (1, 0), (4, 2)]);
    assert!(src.next_item().is_none());
    assert_eq!(src.end(), Some(UdpEnd::EndMark));
    let c = src.counts();
    assert_eq!((c.datagrams, c.samples, c.rejected, c.lost), (6, 3, 2, 0));
}

#[test]
fn raw_counts_are_scaled_to_si() {
    let scaling = UdpScaling {
        p1: ChannelScale {
            gain: 1000.0,
            offset: -1.0e5,
        },
        u: ChannelScale {
            gain: -0.01,
            offset: 0.0,
        },
        temp_c: ChannelScale {
            gain: 0.1,
            offset: -50.0,
        },
        ..UdpScaling::default()
    };
    assert!(scaling.validate().is_ok() && !scaling.is_identity());
    let mut src = UdpSource::bind(
        "127.0.0.1:0".parse().unwrap(),
        UdpOptions {
            scaling,
            ..UdpOptions::default()
        },
    )
    .unwrap();
    let tx = UdpSocket::bind("127.0.0.1:0").unwrap();
    let mut d = UdpDatagram::from_sample(0, &sample(0));
    d.p1 = 7000.0; // counts: 7000 · 1000 Pa − 1e5 Pa = 6.9 MPa
    d.u = 250.0; // counts: −2.5 V
    d.temp_c = 925.0; // counts: 0.1 K · 925 − 50 °C = 42.5 °C
    d.flags |= flags::END_OF_STREAM | flags::TEMP_PRESENT;
    tx.send_to(&d.encode(), src.local_addr()).unwrap();
    match src.next_item() {
        Some(Acquired::Sample(s)) => {
            assert_eq!(s.p1_pa, 6.9e6);
            assert_eq!(s.u_v, -2.5);
            assert_eq!(s.p2_pa, 3.4e6, "unscaled channels pass through");
            assert_eq!(s.temp_c, 42.5, "the oil temperature of a version-2 datagram");
        }
        other => panic!("{other:?}"),
    }
    for (bad, field) in [
        (
            UdpScaling {
                x: ChannelScale {
                    gain: 0.0,
                    offset: 0.0,
                },
                ..UdpScaling::default()
            },
            "x.gain",
        ),
        (
            UdpScaling {
                f_load: ChannelScale {
                    gain: 1.0,
                    offset: f64::NAN,
                },
                ..UdpScaling::default()
            },
            "f_load.offset",
        ),
    ] {
        let e = bad.validate().unwrap_err();
        assert!(e.contains(field), "{e}");
    }
}
