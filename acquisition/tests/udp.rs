//! The UDP source over a real loopback socket: lost, duplicated, reordered
//! (late), malformed and out-of-range datagrams are counted exactly and the
//! gaps reported; scaling; the end of stream by flag, end mark and idle timeout;
//! and the acquisition process publishing a UDP stream on arrival.

use std::net::{SocketAddr, UdpSocket};
use std::process::{Child, Command, ExitStatus, Stdio};
use std::sync::atomic::AtomicBool;
use std::time::{Duration, Instant};

use acquisition::{Acquired, Source, UdpCounts, UdpEnd, UdpOptions, UdpSource};
use bus::{Bus, BusConfig, WaitMode};
use config::udp::{ChannelScale, UdpScaling};
use frames::udp::{flags, UdpDatagram};
use frames::{sensor_flags, SensorFrame};
use model::Sample;

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

/// An acquisition process receiving UDP on a free loopback port, isolated by
/// its own iceoryx2 prefix, with a subscriber to its frames and a socket to send from.
struct UdpProcess {
    cfg: BusConfig,
    bus: Bus,
    rx: bus::Subscriber<SensorFrame>,
    addr: String,
    tx: UdpSocket,
    child: Child,
}

impl UdpProcess {
    /// Starts `acquisition --rig RIG --udp 127.0.0.1:PORT ARGS...` with the
    /// iceoryx2 prefix `<tag><pid>`.
    fn start(tag: &str, rig: &str, args: &[&str]) -> UdpProcess {
        let port = {
            // a free port: bound and released (the process binds it again)
            let s = UdpSocket::bind("127.0.0.1:0").unwrap();
            s.local_addr().unwrap().port()
        };
        let prefix = format!("{tag}{}", std::process::id());
        let cfg = BusConfig {
            iox_prefix: Some(prefix.clone()),
            ..BusConfig::default()
        };
        let bus = Bus::open(rig, cfg.clone()).unwrap();
        let rx = bus.subscriber::<SensorFrame>(WaitMode::Event).unwrap();
        let addr = format!("127.0.0.1:{port}");
        let child = Command::new(env!("CARGO_BIN_EXE_acquisition"))
            .args(["--rig", rig, "--udp", &addr])
            .args(args)
            .env("LEAKWATCH_IOX_PREFIX", &prefix)
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let tx = UdpSocket::bind("127.0.0.1:0").unwrap();
        UdpProcess {
            cfg,
            bus,
            rx,
            addr,
            tx,
            child,
        }
    }

    /// The frame of datagram 0, sent again until a frame comes: the socket may
    /// not be bound yet (duplicates are dropped).
    fn first_frame(&mut self, stop: &AtomicBool) -> SensorFrame {
        let t0 = Instant::now();
        loop {
            self.tx.send_to(&datagram(0), &self.addr).unwrap();
            if let Some(r) = self.rx.wait(Duration::from_millis(100), stop).unwrap() {
                return r.frame;
            }
            assert!(
                t0.elapsed() < Duration::from_secs(20),
                "no frame from the acquisition"
            );
        }
    }

    /// Waits for the process to end (its exit status and standard error),
    /// then closes the subscriber and removes the prefix's files.
    fn finish(self) -> (ExitStatus, String) {
        let out = self.child.wait_with_output().unwrap();
        drop((self.rx, self.bus));
        self.cfg.remove_isolated_files().unwrap();
        (out.status, String::from_utf8_lossy(&out.stderr).to_string())
    }
}

/// The acquisition process with --udp publishes each datagram's sample as it
/// arrives, marks the gap, ends with the flagged last sample and prints the counts.
#[test]
fn the_acquisition_process_publishes_a_udp_stream_on_arrival() {
    let mut p = UdpProcess::start("acqudp", "udptest", &["--wait-subscribers", "1"]);
    let stop = AtomicBool::new(false);
    // the socket may not be bound yet: send the first datagram until a frame comes
    let mut got = vec![p.first_frame(&stop)];
    for seq in (1..200).filter(|s| *s != 50) {
        let mut d = UdpDatagram::from_sample(seq, &sample(seq));
        if seq == 199 {
            d.flags |= flags::END_OF_STREAM;
        }
        p.tx.send_to(&d.encode(), &p.addr).unwrap();
        // each sample is published before the next datagram is sent: on arrival
        let r =
            p.rx.wait(Duration::from_secs(5), &stop)
                .unwrap()
                .expect("the frame of the datagram just sent");
        assert_eq!(r.frame.t_s, sample(seq).t_s);
        got.push(r.frame);
    }
    let (status, stderr) = p.finish();
    assert!(status.success(), "{stderr}");
    // datagram 0 may have been sent several times before the socket was bound
    let frames: Vec<&SensorFrame> = got.iter().collect();
    assert_eq!(frames.len(), 199);
    assert!(frames.iter().enumerate().all(|(i, f)| f.seq == i as u64));
    let gap: Vec<u64> = frames
        .iter()
        .filter(|f| f.flags & sensor_flags::AFTER_GAP != 0)
        .map(|f| (f.t_s * 1e3).round() as u64)
        .collect();
    assert_eq!(gap, [51]);
    assert!(frames[198].flags & sensor_flags::END_OF_STREAM != 0);
    assert!(stderr.contains("published as it arrives"), "{stderr}");
    assert!(stderr.contains("1 lost, "), "{stderr}");
    assert!(stderr.contains("1 samples missing"), "{stderr}");
}

#[test]
fn udp_arguments_are_refused_with_the_reason() {
    let run = |args: &[&str]| {
        let out = Command::new(env!("CARGO_BIN_EXE_acquisition"))
            .args(args)
            .output()
            .unwrap();
        assert!(!out.status.success(), "{args:?}");
        String::from_utf8_lossy(&out.stderr).to_string()
    };
    let e = run(&["--rig", "r", "--udp", "127.0.0.1"]);
    assert!(e.contains("not a UDP listening address"), "{e}");
    let e = run(&["--rig", "r", "--udp", "127.0.0.1:5005", "--csv", "x.csv"]);
    assert!(e.contains("cannot be used with"), "{e}");
    let e = run(&["--rig", "r", "--udp", "127.0.0.1:5005", "--seconds", "3"]);
    assert!(e.contains("cannot be used with"), "{e}");
    let e = run(&[
        "--rig",
        "r",
        "--udp",
        "127.0.0.1:5005",
        "--udp-idle-timeout-s",
        "0",
    ]);
    assert!(e.contains("--udp-idle-timeout-s"), "{e}");
    // a bad `[udp] sender` is named
    let dir = scratch::ScratchDir::new("acquisition-udp-sender");
    for (text, why) in [
        ("rig-plc:5005", "host names are not looked up"),
        ("192.168.10.20", "IP:PORT"),
        ("192.168.10.20:0", "port 0"),
        ("0.0.0.0:5005", "no sender's address"),
    ] {
        let cfg = dir.join("rig.toml");
        std::fs::write(&cfg, format!("[udp]\nsender = \"{text}\"\n")).unwrap();
        let e = run(&[
            "--rig",
            "r",
            "--udp",
            "127.0.0.1:5005",
            "--config",
            cfg.to_str().unwrap(),
        ]);
        assert!(
            e.contains("[udp] sender") && e.contains(text) && e.contains(why),
            "{text}: {e}"
        );
    }
}

/// A stream that ends by the idle timeout (no end-of-stream flag) is closed by
/// one more frame: `END_OF_STREAM` at the last sample's time, every channel NaN.
#[test]
fn an_idle_stream_is_closed_by_an_end_frame_at_the_last_sample_time() {
    let mut p = UdpProcess::start("acqidle", "udpidle", &["--udp-idle-timeout-s", "0.3"]);
    let stop = AtomicBool::new(false);
    // until the process listens, the first datagram is sent again (duplicates are dropped)
    let mut got = vec![p.first_frame(&stop)];
    for seq in 1..10 {
        p.tx.send_to(&datagram(seq), &p.addr).unwrap();
    }
    while let Some(r) = p.rx.wait(Duration::from_secs(5), &stop).unwrap() {
        got.push(r.frame);
        if r.flags & sensor_flags::END_OF_STREAM != 0 {
            break;
        }
    }
    let (status, stderr) = p.finish();
    assert!(status.success(), "{stderr}");
    assert_eq!(got.len(), 11, "{stderr}");
    let end = got[10];
    assert!(end.flags & sensor_flags::END_OF_STREAM != 0);
    assert_eq!(end.seq, 10);
    assert_eq!(end.t_s, got[9].t_s);
    assert!([end.u_v, end.x_m, end.p1_pa, end.p2_pa]
        .iter()
        .all(|v| v.is_nan()));
    assert!(got[..10]
        .iter()
        .all(|f| f.flags & sensor_flags::END_OF_STREAM == 0));
    assert!(stderr.contains("ended by the idle timeout"), "{stderr}");
}

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

fn sample_t(seq: u64) -> f64 {
    sample(seq).t_s
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
