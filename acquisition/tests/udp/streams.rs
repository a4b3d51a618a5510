//! Streams and senders: a rebooted sender, a sequence starting again, second and foreign senders.

use std::net::UdpSocket;
use std::time::{Duration, Instant};

use acquisition::{Acquired, Source, UdpCounts, UdpEnd, UdpOptions, UdpSource};
use frames::udp::UdpDatagram;

use crate::{datagram, datagram_at, drain, identity, sample, sample_t, send_from, seqs, source};

/// A sender that reboots (sequence number and time back to 0 after a silence)
/// is recognised on the first datagram of its new stream, within 100 ms: the
/// new stream's samples are all passed on, the first after a gap as long as
/// the silence. A reordered datagram, and an old one that arrives while the
/// stream flows, stay late.
#[test]
fn a_rebooted_sender_is_recognised_on_its_first_datagram_and_its_new_stream_taken() {
    let (mut src, tx, to) = source(5.0);
    let (sent_tx, sent_rx) = std::sync::mpsc::channel();
    let sender = std::thread::spawn(move || {
        // the first stream: 0..=99, 51 before 50 (reordered), then seq 5 again (far behind, no silence)
        let mut first: Vec<u64> = (0..100).collect();
        first.swap(50, 51);
        first.push(5);
        for seq in first {
            tx.send_to(&datagram(seq), to).unwrap();
        }
        // the reboot: 300 ms of silence, then sequence and time from 0 again
        std::thread::sleep(Duration::from_millis(300));
        tx.send_to(&datagram(0), to).unwrap();
        sent_tx.send(Instant::now()).unwrap();
        // the rest well after the recognition is due
        std::thread::sleep(Duration::from_millis(200));
        for seq in 1..100 {
            tx.send_to(&datagram_at(seq, sample(seq).t_s, seq == 99), to)
                .unwrap();
        }
    });
    let mut items = Vec::new();
    let mut arrived = Vec::new();
    while let Some(item) = src.next_item() {
        items.push(item);
        arrived.push(Instant::now());
        if src.ended() || items.len() > 1000 {
            break;
        }
    }
    sender.join().unwrap();
    let sent = sent_rx.recv().unwrap();
    let got = seqs(&items);
    // the first stream: 50 came late (after 51, reported missing then)
    let mut want: Vec<(u64, u64)> = (0..50).map(|s| (s, 0)).collect();
    want.push((51, 1));
    want.extend((52..100).map(|s| (s, 0)));
    assert_eq!(got[..99], want[..]);
    // the new stream, all of it; its first sample after the gap of the silence
    assert_eq!(got.len(), 199);
    assert_eq!(got[99].0, 0);
    assert!(
        (250..=2000).contains(&got[99].1),
        "300 ms of silence at 1 kHz: {:?}",
        got[99]
    );
    assert_eq!(got[100..], (1..100).map(|s| (s, 0)).collect::<Vec<_>>()[..]);
    // recognised on its first datagram, well within 100 ms
    let took = arrived[99].saturating_duration_since(sent);
    assert!(took < Duration::from_millis(100), "{took:?}");
    assert_eq!(src.end(), Some(UdpEnd::LastSample));
    let c = src.counts();
    assert_eq!(
        c,
        UdpCounts {
            datagrams: 201,
            samples: 199,
            lost: 1,
            late: 2,
            reboots: 1,
            ..UdpCounts::default()
        }
    );
    assert_eq!(c.datagrams, identity(&c));
    let summary = src.summary().unwrap();
    assert!(summary.contains("; 1 sender restarts (reboots)"), "{summary}");
    assert!(src.rate_error().is_none());
}

/// A sender whose sequence starts again while its clock goes on (no old
/// datagram can be newer than the newest) starts a new stream at once.
#[test]
fn a_sequence_that_starts_again_with_the_time_going_on_is_a_new_stream() {
    let (mut src, tx, to) = source(5.0);
    let mut sends: Vec<[u8; frames::udp::LEN]> = (0..100).map(datagram).collect();
    sends.extend((0..10).map(|seq| datagram_at(seq, 0.1 + seq as f64 * 1e-3, seq == 9)));
    let sender = send_from(tx, to, sends);
    let items = drain(&mut src);
    sender.join().unwrap();
    assert_eq!(items.len(), 110);
    assert!(matches!(items[100], Acquired::AfterGap { missing, .. } if missing >= 1));
    let c = src.counts();
    assert_eq!((c.datagrams, c.samples, c.late, c.reboots), (110, 110, 0, 1));
}

/// With `[udp] sender` configured, a second device sending higher sequence
/// numbers cannot take the stream over: its datagrams are counted foreign,
/// every one of the real stream's samples arrives.
#[test]
fn a_configured_sender_keeps_its_stream_against_a_second_device() {
    let real = UdpSocket::bind("127.0.0.1:0").unwrap();
    let intruder = UdpSocket::bind("127.0.0.1:0").unwrap();
    let mut src = UdpSource::bind(
        "127.0.0.1:0".parse().unwrap(),
        UdpOptions {
            sender: Some(real.local_addr().unwrap()),
            ..UdpOptions::default()
        },
    )
    .unwrap();
    let to = src.local_addr();
    // the intruder first, and in between, with sequence numbers far ahead
    for seq in 1_000_000..1_000_005 {
        intruder.send_to(&datagram(seq), to).unwrap();
    }
    let mut sends = Vec::new();
    for seq in 0..100 {
        sends.push((seq % 10 == 5, datagram_at(seq, sample_t(seq), seq == 99)));
    }
    let t = std::thread::spawn(move || {
        for (also_intruder, d) in sends {
            if also_intruder {
                intruder.send_to(&datagram(2_000_000), to).unwrap();
            }
            real.send_to(&d, to).unwrap();
        }
    });
    let items = drain(&mut src);
    t.join().unwrap();
    assert_eq!(seqs(&items), (0..100).map(|s| (s, 0)).collect::<Vec<_>>());
    let c = src.counts();
    assert_eq!(
        c,
        UdpCounts {
            datagrams: 115,
            samples: 100,
            foreign: 15,
            ..UdpCounts::default()
        }
    );
    assert_eq!(c.datagrams, identity(&c));
    assert!(src.summary().unwrap().contains(", 15 foreign (another sender)"));
}

/// Without `[udp] sender` the first sender of a valid datagram locks the
/// stream; a second one is counted foreign and does not disturb it.
#[test]
fn without_a_configured_sender_a_second_sender_is_foreign_and_does_not_disturb_the_stream() {
    let (mut src, tx, to) = source(5.0);
    let other = UdpSocket::bind("127.0.0.1:0").unwrap();
    // garbage from the other one first: it does not lock the stream
    other.send_to(b"not a datagram", to).unwrap();
    let mut sends = Vec::new();
    for seq in 0..100 {
        sends.push((seq % 20 == 10, datagram_at(seq, sample_t(seq), seq == 99)));
    }
    let t = std::thread::spawn(move || {
        for (also_other, d) in sends {
            tx.send_to(&d, to).unwrap();
            if also_other {
                // higher sequence numbers and a valid end mark: both ignored
                other.send_to(&datagram(500), to).unwrap();
                other
                    .send_to(&UdpDatagram::end_of_stream(501).encode(), to)
                    .unwrap();
            }
        }
    });
    let items = drain(&mut src);
    t.join().unwrap();
    assert_eq!(seqs(&items), (0..100).map(|s| (s, 0)).collect::<Vec<_>>());
    assert_eq!(src.end(), Some(UdpEnd::LastSample));
    let c = src.counts();
    assert_eq!(
        c,
        UdpCounts {
            datagrams: 111,
            samples: 100,
            malformed: 1,
            foreign: 10,
            ..UdpCounts::default()
        }
    );
    assert_eq!(c.datagrams, identity(&c));
}
