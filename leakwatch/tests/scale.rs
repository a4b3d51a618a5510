//! `leakwatch bench scale`: two rigs side by side, each a whole `run` with its
//! own rig id and iceoryx2 prefix; every frame of both is classified and the
//! figures are written to scale.json (the figures themselves are benchmark
//! output, not asserted).

use std::process::Command;

#[test]
fn two_rigs_run_side_by_side_and_lose_no_frame() {
    let scratch = scratch::ScratchDir::new("scale");
    let d = scratch.join("out");
    let o = Command::new(env!("CARGO_BIN_EXE_leakwatch"))
        .args(["bench", "scale", "--rigs", "1,2", "--seconds", "5", "--out"])
        .arg(&d)
        .output()
        .expect("leakwatch runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains("| 2 |"), "{stdout}");
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("scale.json")).unwrap()).unwrap();
    let rows = v["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 2);
    for (r, n) in rows.iter().zip([1u64, 2]) {
        assert_eq!(r["rigs"], n);
        // 5 s at 1 kHz per rig, every frame classified
        assert_eq!(r["frames_sent"], 5000 * n, "{r}");
        assert_eq!(r["frames_lost"], 0, "{r}");
        let cpu = r["tree_cpu_per_rig_pct"].as_f64().unwrap();
        assert!(cpu > 0.0 && cpu < 200.0, "{r}");
    }
    // each rig wrote its own run directory
    assert!(d.join("rigs-2").join("rig1").join("latency.json").exists());
}
