//! The thesis' experiment in simulation (docs/model.md#the-thesis-pattern): leaks of
//! 0.5 L/min of each kind under the open-loop sine and the loaded closed-loop
//! scenario, with the thesis' tuning and with a tuning derived from the
//! sensors; the MAE of the a-posteriori pressure residuals before and after the
//! onset, and the signed and normalised means of the innovations.

use filter::{Estimator, Tuning};
use model::{ActuatorParams, Fault, FaultSchedule, Scenario, Simulator};
use serde::Serialize;

/// Figures of one channel pair over one window.
#[derive(Debug, Clone, Copy, Default, Serialize)]
pub struct Window {
    /// MAE of the a-posteriori residual of p1 and p2 (the thesis' figure), Pa.
    pub mae_pa: [f64; 2],
    /// Mean of the p1 and p2 innovations (signed), Pa.
    pub innovation_mean_pa: [f64; 2],
    /// Mean of the normalised p1 and p2 innovations ν/σ (signed).
    pub innovation_mean_norm: [f64; 2],
}

/// One row of the table.
#[derive(Debug, Clone, Serialize)]
pub struct Row {
    /// Scenario.
    pub scenario: String,
    /// Tuning name.
    pub tuning: String,
    /// Leak kind or `none`.
    pub kind: String,
    /// The 4 s before the onset.
    pub before: Window,
    /// The last 4 s of the run.
    pub after: Window,
}

/// The 7-state tuning from the sensors: the thesis filter's layout with the
/// leak filter's noise model.
pub fn sensor_tuning_7() -> Tuning {
    Tuning {
        states: 7,
        init: filter::Init::Thesis,
        p0_x_m2: 1.0,
        ..Tuning::sensor_derived()
    }
}

/// Runs one case of the experiment.
pub fn run(scenario: &str, tuning_name: &str, tuning: &Tuning, kind: &str) -> Result<Row, String> {
    let sc = Scenario::by_name(scenario, 1, 120.0).map_err(|e| e.to_string())?;
    let onset = sc.default_onset_s;
    let seconds = onset + 12.0;
    let rig = ActuatorParams::default();
    let mut faults = FaultSchedule::default();
    if kind != "none" {
        faults
            .faults
            .push(Fault::parse(&format!("{kind}:0.5lpm@{onset}s"), &rig).map_err(|e| e.to_string())?);
    }
    let mut sim = Simulator::with_default_sensors(rig, sc, faults, 1).map_err(|e| e.to_string())?;
    let mut est = Estimator::new(ActuatorParams::default(), tuning.clone())?;
    let mut acc = [[0.0f64; 5]; 2];
    let mut mae = [[0.0f64; 2]; 2];
    for _ in 0..(seconds * 1000.0).round() as usize {
        let s = sim.step();
        let e = est.on_sample(&s);
        let w = if s.t_s >= onset - 4.0 && s.t_s < onset {
            0
        } else if s.t_s >= seconds - 4.0 {
            1
        } else {
            continue;
        };
        if !(e.innovation[1].is_finite() && e.innovation[2].is_finite()) {
            continue;
        }
        let a = &mut acc[w];
        a[0] += e.innovation[1];
        a[1] += e.innovation[2];
        a[2] += e.innovation[1] / e.innovation_sigma[1];
        a[3] += e.innovation[2] / e.innovation_sigma[2];
        a[4] += 1.0;
        mae[w] = e.mae_pa;
    }
    let win = |k: usize| {
        let n = acc[k][4].max(1.0);
        Window {
            mae_pa: mae[k],
            innovation_mean_pa: [acc[k][0] / n, acc[k][1] / n],
            innovation_mean_norm: [acc[k][2] / n, acc[k][3] / n],
        }
    };
    Ok(Row {
        scenario: scenario.into(),
        tuning: tuning_name.into(),
        kind: kind.into(),
        before: win(0),
        after: win(1),
    })
}

/// The whole table.
pub fn table() -> Result<Vec<Row>, String> {
    let mut rows = Vec::new();
    for scenario in ["open-loop-sine", "loaded-sine"] {
        for (name, tuning) in [("thesis", Tuning::thesis()), ("sensor", sensor_tuning_7())] {
            for kind in ["none", "ext1", "ext2", "int"] {
                rows.push(run(scenario, name, &tuning, kind)?);
            }
        }
    }
    Ok(rows)
}

/// The table in Markdown.
pub fn markdown(rows: &[Row]) -> String {
    let mut s = String::from(
        "| scenario | tuning | leak | MAE p1 before → after (kPa) | MAE p2 before → after (kPa) | mean ν p1 before → after (kPa) | mean ν p2 before → after (kPa) | mean ν/σ p1 after | mean ν/σ p2 after |\n|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        s.push_str(&format!(
            "| {} | {} | {} | {:.2} → {:.2} | {:.2} → {:.2} | {:+.2} → {:+.2} | {:+.2} → {:+.2} | {:+.3} | {:+.3} |\n",
            r.scenario,
            r.tuning,
            r.kind,
            r.before.mae_pa[0] / 1e3,
            r.after.mae_pa[0] / 1e3,
            r.before.mae_pa[1] / 1e3,
            r.after.mae_pa[1] / 1e3,
            r.before.innovation_mean_pa[0] / 1e3,
            r.after.innovation_mean_pa[0] / 1e3,
            r.before.innovation_mean_pa[1] / 1e3,
            r.after.innovation_mean_pa[1] / 1e3,
            r.after.innovation_mean_norm[0],
            r.after.innovation_mean_norm[1],
        ));
    }
    s
}
