//! The OPC UA output end to end: a real `leakwatch run` with `[opcua]`
//! serves a SCADA client that is not ours (Python's `asyncua`, through
//! examples/opcua/scada_client.py): it browses the rig's object, reads every
//! state variable with its unit, is refused a write, and receives the leak's
//! raise as an OPC UA event with its kind and size, the event of the run's
//! events.json; with a user configured, anonymous sessions and a wrong
//! password are refused.
//!
//! The client needs `asyncua` (.ci/setup installs it); CI sets
//! LEAKWATCH_REQUIRE_PYTHON=1, so it must run there.

use std::net::TcpListener;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::sync::Mutex;

use serde_json::Value;

mod common;
use common::*;

const BIN: &str = env!("CARGO_BIN_EXE_leakwatch");

/// The tests that run a pipeline share two cores: one at a time.
static SERIAL: Mutex<()> = Mutex::new(());

fn client_script() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/opcua/scada_client.py")
}

/// A TCP port free on the loopback interface now.
fn free_port() -> u16 {
    TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port()
}

/// `leakwatch run ARGS` started, and the client `client_args` run against
/// `opc.tcp://127.0.0.1:PORT/` meanwhile; both outputs.
fn run_with_client(run_args: &[&str], port: u16, client_args: &[&str]) -> (Output, Output) {
    let run = Command::new(BIN)
        .arg("run")
        .args(run_args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let client = Command::new("python3")
        .arg(client_script())
        .arg(format!("opc.tcp://127.0.0.1:{port}/"))
        .args(client_args)
        .output()
        .unwrap();
    let run = run.wait_with_output().unwrap();
    (run, client)
}

fn client_json(client: &Output) -> Value {
    assert!(
        client.status.success(),
        "the client failed: {}\n{}",
        String::from_utf8_lossy(&client.stderr),
        String::from_utf8_lossy(&client.stdout)
    );
    serde_json::from_slice(&client.stdout).unwrap_or_else(|e| {
        panic!("{e}: {}", String::from_utf8_lossy(&client.stdout));
    })
}

/// Every state variable the docs name, read with its type and unit.
fn check_variables(vars: &Value) {
    let expect = [
        ("Running", "Boolean", None),
        ("Armed", "Boolean", None),
        ("Watched", "Boolean", None),
        ("BlindSinceS", "Double", Some("s")),
        ("HealthStatus", "String", None),
        ("HealthAgeS", "Double", Some("s")),
        ("ActiveEvents", "UInt32", None),
        ("AlarmKind", "String", None),
        ("AlarmEventId", "UInt64", None),
        ("LeakSizeLpm", "Double", Some("L/min")),
        ("LeakSizeSigmaLpm", "Double", Some("L/min")),
        ("OnsetTimeS", "Double", Some("s")),
        ("DetectTimeS", "Double", Some("s")),
        ("Confidence", "Double", None),
        ("SmallestDetectableExt1Lpm", "Double", Some("L/min")),
        ("SmallestDetectableExt2Lpm", "Double", Some("L/min")),
        ("SmallestDetectableIntLpm", "Double", Some("L/min")),
        ("OilTemperatureC", "Double", Some("°C")),
        ("OilTemperatureSigmaK", "Double", Some("K")),
        ("SensorFaults", "String", None),
        ("SensorFaultCount", "UInt32", None),
        ("SampleTimeS", "Double", Some("s")),
    ];
    assert_eq!(vars.as_object().unwrap().len(), expect.len(), "{vars}");
    for (name, ty, unit) in expect {
        let v = &vars[name];
        assert_eq!(v["type"], ty, "{name}: {v}");
        assert_eq!(v["unit"].as_str(), unit, "{name}: {v}");
        assert!(!v["description"].as_str().unwrap_or("").is_empty(), "{name}: {v}");
    }
}

/// `leakwatch run` with `[opcua] enabled` and a 1 L/min chamber-1 leak at 10 s:
/// the client reads all 22 state variables (a write refused), gets the raise
/// of the ext1 leak of events.json as an OPC UA event (kind, size, detection
/// time, its Time the acquisition time of the sample it was decided on) within
/// 100 ms of that time, and the state updated at 20 Hz.
#[test]
fn a_scada_client_reads_the_state_and_receives_the_leak_alarm() {
    if !python_with("asyncua") {
        return;
    }
    let _serial = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let dir = tmpdir("anon");
    let port = free_port();
    let cfg = short_warmup_config_with(
        &dir,
        &format!("[opcua]\nenabled = true\nport = {port}\nupdate_hz = 20.0\n"),
    );
    let out = dir.join("run");
    let (cfg_s, out_s) = (cfg.display().to_string(), out.display().to_string());
    let (run, client) = run_with_client(
        &[
            "--rig",
            "ua1",
            "--seconds",
            "16",
            "--fault",
            "ext1:1lpm@10s",
            "--config",
            &cfg_s,
            "--out",
            &out_s,
        ],
        port,
        &["--rig", "ua1", "--seconds", "40", "--until-leak"],
    );
    let got = client_json(&client);
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    eprintln!("client: {got}");
    check_variables(&got["variables"]);
    // after the raise: the alarm in the state
    let after = &got["after"];
    check_variables(after);
    assert_eq!(after["Running"]["value"], true, "{after}");
    assert_eq!(after["Armed"]["value"], true, "{after}");
    assert_eq!(after["AlarmKind"]["value"], "ext1", "{after}");
    let size = after["LeakSizeLpm"]["value"].as_f64().unwrap();
    assert!((0.5..1.5).contains(&size), "{after}");
    // the oil's temperature: none measured, and none estimated on this rig (no datasheet oil)
    let oil = &after["OilTemperatureC"]["value"];
    assert!(
        oil.is_null() || oil.as_f64().is_some_and(|t| (0.0..120.0).contains(&t)),
        "{after}"
    );
    // read-only
    let write = got["write"].as_str().unwrap();
    assert!(
        write.starts_with("BadNotWritable") || write.starts_with("BadUserAccessDenied"),
        "{write}"
    );
    // the raise of events.json, as an event
    let events = json(&out.join("events.json"));
    let raised = events
        .as_array()
        .unwrap()
        .iter()
        .find(|e| e["kind"] == "ext1" && e["phase"] == "raised")
        .unwrap_or_else(|| panic!("no ext1 raise in {events}"));
    let ua_events = got["events"].as_array().unwrap();
    let ev = ua_events
        .iter()
        .find(|e| e["kind"] == "ext1" && e["phase"] == "raised")
        .unwrap_or_else(|| panic!("no ext1 raise among the OPC UA events {ua_events:?}"));
    assert_eq!(ev["event_number"], raised["event_id"], "{ev} {raised}");
    assert_eq!(ev["detect_time_s"], raised["t_detect_s"], "{ev} {raised}");
    assert_eq!(ev["size_lpm"], raised["size_lpm"], "{ev} {raised}");
    assert_eq!(ev["severity"], 800, "{ev}");
    assert_eq!(ev["source_name"], "ua1", "{ev}");
    assert!(ev["message"].as_str().unwrap().contains("ext1 raised"), "{ev}");
    let latency_ms = (ev["arrival_ns"].as_i64().unwrap() - ev["time_ns"].as_i64().unwrap()) as f64 * 1e-6;
    eprintln!(
        "the ext1 raise (t = {} s) reached the client {latency_ms:.1} ms after its sample's acquisition; \
         state updates {:.1} Hz",
        raised["t_detect_s"], got["state_update_hz"]
    );
    assert!(
        (0.0..100.0).contains(&latency_ms),
        "latency {latency_ms} ms: {ev}"
    );
    let rate = got["state_update_hz"].as_f64().unwrap();
    assert!(rate >= 10.0, "the state was updated at {rate} Hz");
    // the stage's own account
    let log = std::fs::read_to_string(out.join("opcua.log")).unwrap();
    assert!(log.contains("opcua: stopped by signal"), "{log}");
}

/// A session signed and encrypted with a client certificate the server does not
/// trust is refused; once trusted, both signing policies serve the state.
fn secure_sessions(port: u16, user: &[&str], cert_dir: &Path, pki: &Path) {
    let certs = cert_dir.display().to_string();
    let secure = |policy: &str| {
        python_client(
            port,
            &[
                user,
                &["--seconds", "0.2", "--security", policy, "--cert-dir", &certs],
            ]
            .concat(),
        )
    };
    let untrusted = secure("Basic256Sha256");
    let err = String::from_utf8_lossy(&untrusted.stderr);
    assert!(
        !untrusted.status.success() && err.contains("BadCertificateUntrusted"),
        "{err}"
    );
    for f in std::fs::read_dir(pki.join("rejected")).unwrap().flatten() {
        std::fs::rename(f.path(), pki.join("trusted").join(f.file_name())).unwrap();
    }
    for policy in ["Basic256Sha256", "Aes128Sha256RsaOaep"] {
        let got = client_json(&secure(policy));
        assert_eq!(got["security"], policy, "{got}");
        assert_eq!(got["variables"]["Running"]["value"], true, "{got}");
    }
}

fn python_client(port: u16, args: &[&str]) -> Output {
    Command::new("python3")
        .arg(client_script())
        .arg(format!("opc.tcp://127.0.0.1:{port}/"))
        .args(args)
        .output()
        .unwrap()
}

/// With `[opcua] user` and `password_file` (and `--opcua PORT`), the user reads
/// the state over the None policy (the password encrypted with the server's
/// certificate, made in `pki_dir`); an anonymous session and a wrong password
/// are refused. A signed and encrypted session (Basic256Sha256) with a client
/// certificate the server does not trust is refused; once the certificate is
/// moved from `pki_dir/rejected/` to `trusted/`, Basic256Sha256 and
/// Aes128Sha256RsaOaep sessions read the state. The OPC UA stage, killed, is
/// restarted and serves again.
#[test]
fn with_a_user_anonymous_clients_are_refused_and_a_killed_server_comes_back() {
    if !python_with("asyncua") {
        return;
    }
    use std::os::unix::fs::PermissionsExt;
    let _serial = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let dir = tmpdir("user");
    let pw = dir.join("password");
    std::fs::write(&pw, "correct-horse-battery\n").unwrap();
    std::fs::set_permissions(&pw, std::fs::Permissions::from_mode(0o600)).unwrap();
    let pki = dir.join("pki");
    let cfg = short_warmup_config_with(
        &dir,
        &format!(
            "[opcua]\nuser = \"scada\"\npassword_file = \"{}\"\npki_dir = \"{}\"\n\
             security_policies = [\"None\", \"Basic256Sha256\", \"Aes128Sha256RsaOaep\"]\n",
            pw.display(),
            pki.display()
        ),
    );
    let port = free_port();
    let rig = rig_id("user");
    let run = Command::new(BIN)
        .args([
            "run",
            "--rig",
            &rig,
            "--seconds",
            "40",
            "--fault",
            "none",
            "--opcua",
        ])
        .arg(port.to_string())
        .arg("--config")
        .arg(&cfg)
        .arg("--out")
        .arg(dir.join("run"))
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let pw_s = pw.display().to_string();
    let user = ["--rig", &rig, "--user", "scada", "--password-file", &pw_s];
    let first = python_client(
        port,
        &[&user[..], &["--seconds", "1", "--check-anonymous-refused"]].concat(),
    );
    let got = client_json(&first);
    eprintln!("client: {got}");
    check_variables(&got["variables"]);
    // the client connects as soon as the server is up, which can be before the
    // first estimate: "Running" is asserted on its read a second later
    assert_eq!(got["after"]["Running"]["value"], true, "{got}");
    assert!(
        got["anonymous"].as_str().unwrap().starts_with("BadIdentityToken"),
        "{got}"
    );
    assert!(
        got["wrong_password"]
            .as_str()
            .unwrap()
            .starts_with("BadIdentityToken"),
        "{got}"
    );
    assert!(
        pki.join("own/cert.der").is_file(),
        "no server certificate in {}",
        pki.display()
    );
    secure_sessions(port, &user, &dir.join("client-pki"), &pki);
    // killed, restarted like the live view, and serving again
    let pid = wait_for_stage("opcua", "user");
    signal(pid, libc::SIGKILL);
    wait_until("the OPC UA stage restarted", || {
        stage_pids(Some("opcua"), "user").iter().any(|p| *p != pid)
    });
    let again = client_json(&python_client(port, &[&user[..], &["--seconds", "0.5"]].concat()));
    assert_eq!(again["after"]["Running"]["value"], true, "{again}");
    let run = run.wait_with_output().unwrap();
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    let err = String::from_utf8_lossy(&run.stderr);
    assert!(
        err.contains("stage opcua exited"),
        "the restart is not reported: {err}"
    );
}
