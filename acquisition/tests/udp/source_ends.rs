//! The source on its own: the idle timeout, a signal that stops it, its addresses checked.

use std::net::SocketAddr;
use std::sync::atomic::AtomicBool;
use std::time::{Duration, Instant};

use acquisition::{Source, UdpEnd, UdpOptions, UdpSource};

use crate::{datagram, drain, source};

#[test]
fn the_stream_ends_after_the_idle_timeout_but_waits_for_its_first_datagram() {
    let (mut src, tx, to) = source(0.3);
    let sender = std::thread::spawn(move || {
        // nothing for 0.5 s (longer than the idle timeout): the source keeps waiting
        std::thread::sleep(Duration::from_millis(500));
        for seq in 0..5 {
            tx.send_to(&datagram(seq), to).unwrap();
        }
    });
    let t0 = Instant::now();
    let items = drain(&mut src);
    let waited = t0.elapsed();
    sender.join().unwrap();
    assert_eq!(items.len(), 5);
    assert_eq!(src.end(), Some(UdpEnd::IdleTimeout));
    assert!(
        waited >= Duration::from_millis(750) && waited < Duration::from_secs(3),
        "{waited:?}"
    );
    assert!(src.summary().unwrap().contains("idle timeout"));
}

#[test]
fn a_signal_stops_a_waiting_source() {
    static STOP: AtomicBool = AtomicBool::new(false);
    let mut src = UdpSource::bind(
        "127.0.0.1:0".parse().unwrap(),
        UdpOptions {
            stop: Some(&STOP),
            ..UdpOptions::default()
        },
    )
    .unwrap();
    let setter = std::thread::spawn(|| {
        std::thread::sleep(Duration::from_millis(200));
        STOP.store(true, std::sync::atomic::Ordering::SeqCst);
    });
    let t0 = Instant::now();
    assert!(src.next_item().is_none());
    assert!(t0.elapsed() < Duration::from_secs(2));
    assert_eq!(src.end(), Some(UdpEnd::Stopped));
    setter.join().unwrap();
}

#[test]
fn addresses_are_checked() {
    use config::udp::parse_udp_address;
    assert_eq!(
        parse_udp_address("udp://127.0.0.1:5005").unwrap(),
        "127.0.0.1:5005".parse::<SocketAddr>().unwrap()
    );
    assert!(parse_udp_address("0.0.0.0:5005").is_ok());
    assert!(parse_udp_address("[::1]:5005").is_ok());
    for (bad, why) in [
        ("udp://127.0.0.1", "IP:PORT"),
        ("udp://localhost:5005", "host names are not looked up"),
        ("udp://127.0.0.1:70000", "IP:PORT"),
        ("udp://127.0.0.1:0", "port 0"),
        ("udp://300.1.1.1:5005", "IP:PORT"),
    ] {
        let e = parse_udp_address(bad).unwrap_err();
        assert!(e.contains(why) && e.contains(bad), "{bad}: {e}");
    }
}
