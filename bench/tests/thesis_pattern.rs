//! The thesis' experiment reproduced in simulation (docs/estimator.md): what
//! the residual patterns of the 7-state filter really show, asserted with margins.

use bench::thesis::{run, sensor_tuning_7, Row};
use filter::Tuning;

fn rows(scenario: &str, name: &str, tuning: &Tuning) -> Vec<Row> {
    ["none", "ext1", "ext2", "int"]
        .iter()
        .map(|k| run(scenario, name, tuning, k).unwrap())
        .collect()
}

fn rise(r: &Row, ch: usize) -> f64 {
    r.after.mae_pa[ch] / r.before.mae_pa[ch]
}

/// With the thesis' tuning the a-posteriori residuals are tiny (about 1 kPa,
/// the filter follows the pressures) and a 0.5 L/min leak moves their MAE by
/// less than a factor of 2.5; the pattern of MODEL.md §5 does not hold: under
/// the open-loop sine a chamber-2 leak raises the MAE of p1 more than that of p2.
#[test]
fn thesis_tuning_gives_tiny_residuals_and_no_reliable_pattern() {
    let r = rows("open-loop-sine", "thesis", &Tuning::thesis());
    for row in &r {
        assert!(
            row.before.mae_pa[0] < 3e3 && row.before.mae_pa[1] < 3e3,
            "{row:?}"
        );
        assert!(rise(row, 0) < 2.5 && rise(row, 1) < 2.5, "{row:?}");
    }
    let ext2 = &r[2];
    assert!(
        rise(ext2, 0) > rise(ext2, 1) + 0.3,
        "reversed pattern expected: {ext2:?}"
    );
}

/// With a tuning from the sensors (the model trusted, the measurements
/// weighted by their real noise), an external leak raises both MAEs more than
/// tenfold, so the MAE detects it but does not isolate it; an internal leak
/// barely shows (less than 2x): it looks like a velocity offset.
#[test]
fn sensor_tuning_detects_external_leaks_but_does_not_isolate() {
    for scenario in ["open-loop-sine", "loaded-sine"] {
        let r = rows(scenario, "sensor", &sensor_tuning_7());
        let none = &r[0];
        assert!(rise(none, 0) < 2.0 && rise(none, 1) < 2.0, "{none:?}");
        for ext in &r[1..3] {
            assert!(rise(ext, 0) > 8.0 && rise(ext, 1) > 8.0, "{scenario} {ext:?}");
            // both signed innovations turn negative: the pressures fall below the model
            assert!(
                ext.after.innovation_mean_pa[0] < -2e4 && ext.after.innovation_mean_pa[1] < -2e4,
                "{ext:?}"
            );
        }
        let int = &r[3];
        assert!(rise(int, 0) < 3.0 && rise(int, 1) < 3.0, "{scenario} {int:?}");
    }
}
