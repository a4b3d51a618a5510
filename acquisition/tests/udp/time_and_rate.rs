//! Time and rate: a time jump is a gap, a sender at the wrong rate, the rate error clearing.

use std::time::Duration;

use acquisition::{Acquired, Source, UdpCounts, UdpEnd};

use crate::{datagram_at, drain, sample, sample_t, send_from, source};

/// A sender's clock that steps by +1 h and back is reported as a gap each
/// time: forward, of the samples the time stamps imply; backward, of one.
#[test]
fn a_time_jump_is_reported_as_a_gap_and_counted() {
    let (mut src, tx, to) = source(5.0);
    let hour = 3600.0;
    let sends: Vec<[u8; frames::udp::LEN]> = (0..100)
        .map(|seq| {
            let t = sample(seq).t_s + if (50..80).contains(&seq) { hour } else { 0.0 };
            datagram_at(seq, t, seq == 99)
        })
        .collect();
    let sender = send_from(tx, to, sends);
    let items = drain(&mut src);
    sender.join().unwrap();
    assert_eq!(items.len(), 100);
    let gaps: Vec<(usize, u64)> = items
        .iter()
        .enumerate()
        .filter_map(|(i, item)| match item {
            Acquired::AfterGap { missing, .. } => Some((i, *missing)),
            _ => None,
        })
        .collect();
    // 49 ms -> 3600.050 s: 3 600 001 periods, 3 600 000 samples missing by the time stamps
    assert_eq!(gaps, [(50, 3_600_000), (80, 1)]);
    match &items[50] {
        Acquired::AfterGap { sample, .. } => assert_eq!(sample.t_s, sample_t(50) + hour),
        other => panic!("{other:?}"),
    }
    let c = src.counts();
    assert_eq!(
        c,
        UdpCounts {
            datagrams: 100,
            samples: 100,
            time_jumps: 2,
            ..UdpCounts::default()
        }
    );
    assert!(src.summary().unwrap().contains("; 2 time jumps"));
    assert!(src.rate_error().is_none());
}

/// A sender at 2 kHz, at 500 Hz or 6 % slow is a rate error: named, counted,
/// shown by `rate_error`, and its samples after the look are dropped (the
/// gross errors are caught after 20 samples, a small one after a block of
/// 200). A right 1 kHz sender is measured right.
#[test]
fn a_sender_at_the_wrong_rate_is_a_rate_error_and_its_samples_are_not_passed_on() {
    for (period_s, passed, hz) in [
        (0.5e-3, 20, "2000.0 Hz"),
        (2e-3, 20, "500.0 Hz"),
        (1.06e-3, 200, "943.4 Hz"),
    ] {
        let (mut src, tx, to) = source(5.0);
        let sends = (0..300)
            .map(|seq| datagram_at(seq, seq as f64 * period_s, seq == 299))
            .collect();
        let sender = send_from(tx, to, sends);
        let items = drain(&mut src);
        sender.join().unwrap();
        // only the samples before the look, each at its own time, no gap
        assert_eq!(items.len(), passed, "{period_s}");
        for (seq, item) in items.iter().enumerate() {
            match item {
                Acquired::Sample(s) => assert_eq!(s.t_s, seq as f64 * period_s),
                other => panic!("{other:?}"),
            }
        }
        assert_eq!(
            src.end(),
            Some(UdpEnd::EndMark),
            "the flagged last sample was dropped"
        );
        let c = src.counts();
        assert_eq!(
            c,
            UdpCounts {
                datagrams: 300,
                samples: passed as u64,
                wrong_rate: 300 - passed as u64,
                rate_errors: 1,
                ..UdpCounts::default()
            },
            "{period_s}"
        );
        let e = src.rate_error().expect("a rate error").to_string();
        assert!(
            e.contains(hz) && e.contains("1000.0 Hz") && e.contains("blind"),
            "{e}"
        );
        let measured = src.measured_period_s().unwrap();
        assert!((measured / period_s - 1.0).abs() < 1e-9, "{measured}");
        let summary = src.summary().unwrap();
        assert!(
            summary.contains(&format!(
                "{} dropped at a wrong rate; 1 rate errors",
                300 - passed
            )) && summary.contains("RATE ERROR"),
            "{summary}"
        );
    }
    // 1 kHz: two full blocks, no error
    let (mut src, tx, to) = source(5.0);
    let sender = send_from(
        tx,
        to,
        (0..450)
            .map(|seq| datagram_at(seq, sample(seq).t_s, seq == 449))
            .collect(),
    );
    assert_eq!(drain(&mut src).len(), 450);
    sender.join().unwrap();
    assert!(src.rate_error().is_none());
    assert!((src.measured_period_s().unwrap() - 1e-3).abs() < 1e-12);
    assert_eq!(src.counts().rate_errors, 0);
}

/// A rate error lasts until a full block of the stream is at the right rate
/// again (here after a reboot of the sender with the right rate): then the
/// samples flow again, the first after a gap.
#[test]
fn a_rate_error_clears_when_the_sender_keeps_the_rate_again() {
    let (mut src, tx, to) = source(5.0);
    let sender = std::thread::spawn(move || {
        for seq in 0..100 {
            tx.send_to(&datagram_at(seq, seq as f64 * 0.5e-3, false), to)
                .unwrap();
        }
        std::thread::sleep(Duration::from_millis(100));
        for seq in 0..400 {
            tx.send_to(&datagram_at(seq, sample(seq).t_s, seq == 399), to)
                .unwrap();
            if seq % 50 == 49 {
                std::thread::sleep(Duration::from_millis(1));
            }
        }
    });
    let items = drain(&mut src);
    sender.join().unwrap();
    // 20 at 2 kHz; at 1 kHz, from the sample that completed a right block on
    assert_eq!(items.len(), 20 + 200);
    assert!(items[..20].iter().all(|i| matches!(i, Acquired::Sample(_))));
    match &items[20] {
        // 80 dropped at 2 kHz, the gap of the reboot (~100 ms), 200 dropped at 1 kHz
        Acquired::AfterGap { sample, missing } => {
            assert_eq!(sample.t_s, sample_t(200));
            assert!(*missing >= 80 + 50 + 200, "{missing}");
        }
        other => panic!("{other:?}"),
    }
    assert!(src.rate_error().is_none());
    let c = src.counts();
    assert_eq!(
        c,
        UdpCounts {
            datagrams: 500,
            samples: 220,
            wrong_rate: 280,
            reboots: 1,
            rate_errors: 1,
            ..UdpCounts::default()
        }
    );
}
