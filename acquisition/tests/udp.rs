//! The UDP source over a real loopback socket: lost, duplicated, reordered
//! (late), malformed and out-of-range datagrams are counted exactly and the
//! gaps reported; scaling; the end of stream by flag, end mark and idle timeout;
//! and the acquisition process publishing a UDP stream on arrival.

use std::net::{SocketAddr, UdpSocket};
use std::process::{Child, Command, ExitStatus, Stdio};
use std::sync::atomic::AtomicBool;
use std::time::{Duration, Instant};

use acquisition::{Acquired, ChannelScale, Source, UdpCounts, UdpEnd, UdpOptions, UdpScaling, UdpSource};
use bus::{Bus, BusConfig, WaitMode};
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
        }
    );
    let c = src.counts();
    assert_eq!(
        c.datagrams,
        c.samples + c.duplicated + c.late + c.malformed + c.rejected
    );
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
    d.flags |= flags::END_OF_STREAM;
    tx.send_to(&d.encode(), src.local_addr()).unwrap();
    match src.next_item() {
        Some(Acquired::Sample(s)) => {
            assert_eq!(s.p1_pa, 6.9e6);
            assert_eq!(s.u_v, -2.5);
            assert_eq!(s.p2_pa, 3.4e6, "unscaled channels pass through");
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
    use acquisition::parse_udp_address;
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
