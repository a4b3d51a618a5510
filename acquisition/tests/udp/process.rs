//! The acquisition process: a UDP stream published on arrival, bad arguments, an idle stream's end.

use std::net::UdpSocket;
use std::process::{Child, Command, ExitStatus, Stdio};
use std::sync::atomic::AtomicBool;
use std::time::{Duration, Instant};

use bus::{Bus, BusConfig, WaitMode};
use frames::udp::{flags, UdpDatagram};
use frames::{sensor_flags, SensorFrame};

use crate::{datagram, sample};

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
