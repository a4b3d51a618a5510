//! `simulate`: the documented CSV, a drifting transducer, standard output; `plot` of its CSV.

use std::process::Command;

use crate::common::*;

#[test]
fn simulate_writes_the_documented_csv() {
    let d = tmpdir("sim");
    let out = d.join("run.csv");
    let args = [
        "simulate",
        "--scenario",
        "loaded-sine",
        "--seconds",
        "2",
        "--fault",
        "ext1:0.3lpm@1s",
        "--out",
        out.to_str().unwrap(),
    ];
    let o = leakwatch(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = std::fs::read_to_string(&out).unwrap();
    assert_eq!(
        text.lines().next(),
        Some("t,u,x,p1,p2,x_sp,f_load,ref,q_leak,temp_c")
    );
    assert_eq!(text.lines().count(), 2001);
    let ds = dataset::read_csv(&out, dataset::Limits::default()).unwrap();
    assert_eq!(ds.samples.len(), 2000);
    assert!(ds.samples[999].q_leak_lpm == 0.0 && ds.samples[1500].q_leak_lpm > 0.1);
    // same seed, same file
    let again = d.join("again.csv");
    let mut args2 = args;
    args2[8] = again.to_str().unwrap();
    assert!(leakwatch(&args2).status.success());
    assert_eq!(std::fs::read(&out).unwrap(), std::fs::read(&again).unwrap());
}

/// `--sensor-fault` drifts the p1 column by its equation, against the healthy
/// run of the same seed, to one ADC step (5.05 kPa); the other columns and the
/// rows before the onset are the healthy ones.
#[test]
fn simulate_drifts_a_pressure_transducer() {
    let d = tmpdir("sim-sensor-fault");
    let (healthy, faulty) = (d.join("healthy.csv"), d.join("drift.csv"));
    let args = |out: &std::path::Path, fault: &[&str]| {
        let mut a = vec!["simulate", "--scenario", "loaded-sine", "--seconds", "30"];
        a.extend_from_slice(fault);
        a.extend(["--out", out.to_str().unwrap()]);
        a.iter().map(|s| s.to_string()).collect::<Vec<_>>()
    };
    // 600 kPa/min = 10 kPa/s from 10 s, at most 100 kPa (from 20 s)
    let spec = ["--sensor-fault", "p1:drift=600kPa/min,max=100kPa@10s"];
    for (out, fault) in [(&healthy, &[][..]), (&faulty, &spec[..])] {
        let a = args(out, fault);
        let o = leakwatch(&a.iter().map(String::as_str).collect::<Vec<_>>());
        assert!(o.status.success(), "{}", stderr(&o));
    }
    let read = |p: &std::path::Path| dataset::read_csv(p, dataset::Limits::default()).unwrap().samples;
    let (h, f) = (read(&healthy), read(&faulty));
    assert_eq!((h.len(), f.len()), (30_000, 30_000));
    for (t, want_pa) in [(15.0, 50e3), (25.0, 100e3)] {
        let i = (t * 1000.0) as usize;
        assert_eq!(f[i].t_s, t);
        let offset = f[i].p1_pa - h[i].p1_pa;
        assert!(
            (offset - want_pa).abs() <= 5.06e3,
            "t = {t} s: p1 offset {offset} Pa"
        );
    }
    assert!(f[..10_000].iter().zip(&h).all(|(a, b)| a.p1_pa == b.p1_pa));
    assert!(f
        .iter()
        .zip(&h)
        .all(|(a, b)| (a.x_m, a.p2_pa, a.u_v) == (b.x_m, b.p2_pa, b.u_v)));
    // a bad spec names its bad part
    let o = leakwatch(&[
        "simulate",
        "--scenario",
        "loaded-sine",
        "--sensor-fault",
        "p1:drift=1mm/min@1s",
        "--out",
        "-",
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        stderr(&o).contains("p1 reads a pressure, so the unit is one of Pa, kPa, MPa or bar, not `mm`"),
        "{}",
        stderr(&o)
    );
}

/// `--out -` writes the CSV to standard output (the same bytes as the file); a
/// reader that stops early (`| head`) ends it with a named error, not a panic.
#[test]
fn simulate_writes_to_standard_output_and_names_a_closed_pipe() {
    use std::io::Read;
    let d = tmpdir("sim-stdout");
    let file = d.join("run.csv");
    let args = |out: &str| {
        [
            "simulate",
            "--scenario",
            "loaded-sine",
            "--seconds",
            "2",
            "--out",
            out,
        ]
        .map(str::to_string)
        .to_vec()
    };
    let o = Command::new(env!("CARGO_BIN_EXE_leakwatch"))
        .args(args(file.to_str().unwrap()))
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let o = Command::new(env!("CARGO_BIN_EXE_leakwatch"))
        .args(args("-"))
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(o.stdout, std::fs::read(&file).unwrap());
    assert_eq!(stderr(&o).trim(), "wrote 2000 samples to standard output");
    assert!(
        !std::path::Path::new("-").exists(),
        "no file named '-' is written"
    );
    // the reader takes 100 bytes and closes the pipe
    let mut child = Command::new(env!("CARGO_BIN_EXE_leakwatch"))
        .args(args("-"))
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let mut first = [0u8; 100];
    child.stdout.take().unwrap().read_exact(&mut first).unwrap();
    let o = child.wait_with_output().unwrap();
    assert!(first.starts_with(b"t,u,x,p1,p2"));
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert_eq!(
        stderr(&o).trim(),
        "leakwatch: error: cannot write the CSV to standard output: Broken pipe (os error 32)"
    );
}

#[test]
fn plot_draws_a_png() {
    let d = tmpdir("plot");
    let csv = d.join("r.csv");
    let png = d.join("r.png");
    let (csv_s, png_s) = (csv.to_str().unwrap(), png.to_str().unwrap());
    let o = leakwatch(&[
        "simulate",
        "--scenario",
        "open-loop-sine",
        "--seconds",
        "3",
        "--fault",
        "ext2:0.5lpm@1s",
        "--out",
        csv_s,
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = leakwatch(&["plot", csv_s, "--out", png_s]);
    assert!(o.status.success(), "{}", stderr(&o));
    let bytes = std::fs::read(&png).unwrap();
    assert_eq!(&bytes[1..4], b"PNG");
    let missing = d.join("missing.csv");
    let o = leakwatch(&["plot", missing.to_str().unwrap(), "--out", png_s]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("missing.csv"));
}
