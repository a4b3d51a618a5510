//! The UDP source over a real loopback socket: lost, duplicated, reordered
//! (late), malformed and out-of-range datagrams are counted exactly and the
//! gaps reported; scaling; the end of stream by flag, end mark and idle timeout;
//! and the acquisition process publishing a UDP stream on arrival.

use std::net::{SocketAddr, UdpSocket};
use std::time::Duration;

use acquisition::{Acquired, Source, UdpCounts, UdpOptions, UdpSource};
use frames::udp::{flags, UdpDatagram};
use model::Sample;

#[path = "udp/counting.rs"]
mod counting;
#[path = "udp/process.rs"]
mod process;
#[path = "udp/source_ends.rs"]
mod source_ends;
#[path = "udp/streams.rs"]
mod streams;
#[path = "udp/time_and_rate.rs"]
mod time_and_rate;

fn sample(seq: u64) -> Sample {
    let t = seq as f64 * 1e-3;
    let mut s = Sample::new(t, 0.5, 0.2 + 1e-5 * seq as f64, 6.9e6, 3.4e6);
    s.f_load_n = -100.0;
    s
}

fn datagram(seq: u64) -> [u8; frames::udp::LEN] {
    UdpDatagram::from_sample(seq, &sample(seq)).encode()
}

fn source(idle_s: f64) -> (UdpSource, UdpSocket, SocketAddr) {
    let src = UdpSource::bind(
        "127.0.0.1:0".parse().unwrap(),
        UdpOptions {
            idle_timeout: Duration::from_secs_f64(idle_s),
            ..UdpOptions::default()
        },
    )
    .unwrap();
    let to = src.local_addr();
    let tx = UdpSocket::bind("127.0.0.1:0").unwrap();
    (src, tx, to)
}

/// Items until the source ends (bounded).
fn drain(src: &mut UdpSource) -> Vec<Acquired> {
    let mut out = Vec::new();
    while let Some(item) = src.next_item() {
        out.push(item);
        if src.ended() || out.len() > 10_000 {
            break;
        }
    }
    out
}

/// The datagrams counted by outcome (without end marks): equals `datagrams`
/// when no end mark came.
fn identity(c: &UdpCounts) -> u64 {
    c.samples + c.duplicated + c.late + c.malformed + c.rejected + c.foreign + c.wrong_rate
}

/// The datagram of `seq` at time `t_s`, s (flagged end of stream if `last`).
fn datagram_at(seq: u64, t_s: f64, last: bool) -> [u8; frames::udp::LEN] {
    let mut d = UdpDatagram::from_sample(seq, &sample(seq));
    d.t_s = t_s;
    if last {
        d.flags |= flags::END_OF_STREAM;
    }
    d.encode()
}

/// Sends `datagrams` from `tx` to `to` on a thread (a pause of 1 ms every 50,
/// so that a small receive buffer does not overflow while the test drains).
fn send_from(
    tx: UdpSocket,
    to: SocketAddr,
    datagrams: Vec<[u8; frames::udp::LEN]>,
) -> std::thread::JoinHandle<()> {
    std::thread::spawn(move || {
        for (i, d) in datagrams.iter().enumerate() {
            tx.send_to(d, to).unwrap();
            if i % 50 == 49 {
                std::thread::sleep(Duration::from_millis(1));
            }
        }
    })
}

/// (seq of the sample as the test encodes it, missing before it)
fn seqs(items: &[Acquired]) -> Vec<(u64, u64)> {
    items
        .iter()
        .map(|i| match i {
            Acquired::Sample(s) => ((s.t_s * 1e3).round() as u64, 0),
            Acquired::AfterGap { sample, missing } => ((sample.t_s * 1e3).round() as u64, *missing),
            Acquired::Unusable(why) => panic!("unexpected unusable item: {why}"),
        })
        .collect()
}

fn sample_t(seq: u64) -> f64 {
    sample(seq).t_s
}
