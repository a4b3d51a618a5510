use dataset::*;
use std::path::Path;

fn tmp(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("leakwatch-dataset-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

fn read_str(text: &str) -> Result<Dataset, DatasetError> {
    let p = tmp(&format!("t{}.csv", text.len()));
    std::fs::write(&p, text).unwrap();
    read_csv(&p, Limits::default())
}

#[test]
fn round_trip_is_bit_exact() {
    let mut rng = model::rng::Rng::new(9);
    let samples: Vec<Sample> = (0..2000)
        .map(|k| Sample {
            t_s: k as f64 * 1e-3,
            u_v: 3.0 * rng.normal(),
            x_m: 0.3 + 1e-3 * rng.normal(),
            p1_pa: 6.9e6 + 1e5 * rng.normal(),
            p2_pa: 6.9e6 * rng.uniform(),
            x_sp_m: 1e-5 * rng.normal(),
            f_load_n: if k % 3 == 0 { f64::NAN } else { 1e3 * rng.normal() },
            ref_m: 1.0 / 3.0,
            q_leak_lpm: 1e-300 * rng.uniform(),
        })
        .collect();
    let p = tmp("round.csv");
    write_csv(&p, &samples).unwrap();
    let back = read_csv(&p, Limits::default()).unwrap();
    assert!(back.issues.is_empty(), "{:?}", back.issues.first());
    assert_eq!(back.samples.len(), samples.len());
    for (a, b) in samples.iter().zip(&back.samples) {
        for (x, y) in [
            (a.t_s, b.t_s),
            (a.u_v, b.u_v),
            (a.x_m, b.x_m),
            (a.p1_pa, b.p1_pa),
            (a.p2_pa, b.p2_pa),
            (a.x_sp_m, b.x_sp_m),
            (a.f_load_n, b.f_load_n),
            (a.ref_m, b.ref_m),
            (a.q_leak_lpm, b.q_leak_lpm),
        ] {
            assert_eq!(x.to_bits(), y.to_bits());
        }
    }
}

#[test]
fn missing_column_is_fatal_and_named() {
    let e = read_str("t,u,x,p1\n0,0,0,1\n").unwrap_err();
    let m = e.to_string();
    assert!(m.contains("`p2`") && m.contains("line 1"), "{m}");
    let e = read_str("").unwrap_err();
    assert!(e.to_string().contains("`t`"));
    let e = read_str("t,u,x,p1,p2,x\n").unwrap_err();
    assert!(e.to_string().contains("appears twice"));
}

#[test]
fn bad_rows_are_skipped_and_reported_with_line_and_column() {
    let text = "t,u,x,p1,p2\n\
                0.000,0,0.3,6.9e6,6.9e6\n\
                0.001,abc,0.3,6.9e6,6.9e6\n\
                0.002,0,NaN,6.9e6,6.9e6\n\
                0.003,0,0.3,inf,6.9e6\n\
                0.004,0,0.3,6.9e6,3e7\n\
                -0.001,0,0.3,6.9e6,6.9e6\n\
                0.005,0,0.3,6.9e6\n\
                0.009,0,0.3,6.9e6,6.9e6\n\
                0.010,0,0.3,6.9e6,6.9e6\n";
    let ds = read_str(text).unwrap();
    assert_eq!(ds.samples.len(), 3);
    let got: Vec<(u64, Option<&str>, bool)> = ds
        .issues
        .iter()
        .map(|i| (i.line, i.column.as_deref(), i.skipped))
        .collect();
    assert_eq!(
        got,
        vec![
            (3, Some("u"), true),
            (4, Some("x"), true),
            (5, Some("p1"), true),
            (6, Some("p2"), true),
            (7, Some("t"), true),
            (8, None, true),
            (9, Some("t"), false),
        ]
    );
    assert_eq!(ds.issues[6].kind, IssueKind::Gap { missing: 8 });
    assert_eq!(ds.skipped(), 6);
    assert!(ds.issues[0].to_string().contains("`abc` is not a number"));
}

#[test]
fn unwritable_path_names_the_path() {
    let e = write_csv(Path::new("/nonexistent-dir/x.csv"), &[]).unwrap_err();
    assert!(e.to_string().contains("/nonexistent-dir/x.csv"));
}
