//! The suite's figures: the per-cell summary of the runs, the Markdown
//! table and the detection-probability figure.

use super::{Cell, Outcome, RunResult, SuiteResult, DETECTORS, FROM_START, GAPS, MID_RUN, SIZES_LPM};
use crate::stats::quantile;

/// Turns runs into the per-cell figures.
pub fn summarise(runs: Vec<RunResult>, wall_s: f64) -> SuiteResult {
    let mut cells = Vec::new();
    for (di, det) in DETECTORS.iter().enumerate() {
        for kind in ["ext1", "ext2", "int"] {
            for size in SIZES_LPM {
                for variant in [MID_RUN, FROM_START] {
                    let these: Vec<&RunResult> = runs
                        .iter()
                        .filter(|r| {
                            r.case.kind == kind && r.case.size_lpm == size && r.case.variant == variant
                        })
                        .collect();
                    if these.is_empty() {
                        continue;
                    }
                    let n = these.len();
                    let det_runs: Vec<&Outcome> = these.iter().map(|r| &r.outcomes[di]).collect();
                    let mut delays: Vec<f64> = det_runs
                        .iter()
                        .filter(|o| o.detected)
                        .map(|o| o.delay_s)
                        .collect();
                    let mut errs: Vec<f64> = det_runs
                        .iter()
                        .filter(|o| o.isolated && o.size_lpm.is_finite() && o.real_flow_lpm > 0.0)
                        .map(|o| (o.size_lpm - o.real_flow_lpm).abs() / o.real_flow_lpm)
                        .collect();
                    cells.push(Cell {
                        detector: det.to_string(),
                        kind: kind.into(),
                        size_lpm: size,
                        variant: variant.into(),
                        runs: n,
                        p_detect: det_runs.iter().filter(|o| o.detected).count() as f64 / n as f64,
                        p_isolate: det_runs.iter().filter(|o| o.isolated).count() as f64 / n as f64,
                        delay_median_s: quantile(&mut delays, 0.5),
                        delay_p95_s: quantile(&mut delays, 0.95),
                        size_error_median: quantile(&mut errs, 0.5),
                        size_error_p95: quantile(&mut errs, 0.95),
                    });
                }
            }
        }
    }
    let healthy: Vec<&RunResult> = runs.iter().filter(|r| r.case.kind == "none").collect();
    let hours = healthy.iter().map(|r| r.case.seconds).sum::<f64>() / 3600.0;
    let false_alarms_per_hour = DETECTORS
        .iter()
        .enumerate()
        .map(|(di, d)| {
            let n: u32 = healthy.iter().map(|r| r.outcomes[di].false_alarms).sum();
            (
                d.to_string(),
                if hours > 0.0 { n as f64 / hours } else { f64::NAN },
            )
        })
        .collect();
    let counts: Vec<(String, u32)> = DETECTORS
        .iter()
        .enumerate()
        .map(|(di, d)| {
            (
                d.to_string(),
                healthy.iter().map(|r| r.outcomes[di].false_alarms).sum(),
            )
        })
        .collect();
    let upper = counts
        .iter()
        .map(|(d, n)| (d.clone(), poisson_upper95(*n) / hours.max(1e-9)))
        .collect();
    let gap_hours = healthy
        .iter()
        .filter(|r| r.case.variant == GAPS)
        .map(|r| r.case.seconds)
        .sum::<f64>()
        / 3600.0;
    SuiteResult {
        cells,
        healthy_hours: hours,
        false_alarms_per_hour,
        false_alarm_counts: counts,
        false_alarms_per_hour_upper95: upper,
        gap_hours,
        runs,
        wall_s,
    }
}

/// One-sided 95 % upper confidence bound of a Poisson mean after `n` events
/// (exact for n ≤ 5, the Wilson–Hilferty approximation beyond).
pub fn poisson_upper95(n: u32) -> f64 {
    const EXACT: [f64; 6] = [2.996, 4.744, 6.296, 7.754, 9.154, 10.513];
    match EXACT.get(n as usize) {
        Some(v) => *v,
        None => {
            let k = n as f64 + 1.0;
            k * (1.0 - 1.0 / (9.0 * k) + 1.645 / (3.0 * k.sqrt())).powi(3)
        }
    }
}

/// The suite's tables in Markdown: one per leak kind, both detectors side by side.
pub fn markdown(r: &SuiteResult) -> String {
    let mut s = String::new();
    let f = |v: f64, digits: usize| {
        if v.is_finite() {
            format!("{v:.digits$}")
        } else {
            "–".into()
        }
    };
    for kind in ["ext1", "ext2", "int"] {
        s.push_str(&format!("\n### {kind}\n\n"));
        s.push_str(
            "| size L/min | leak | detector | runs | P(detect) | P(right kind at first alarm) | delay median s | delay p95 s | size error median (real flow) | size error p95 |\n",
        );
        s.push_str("|---|---|---|---|---|---|---|---|---|---|\n");
        for size in SIZES_LPM {
            for variant in [MID_RUN, FROM_START] {
                for det in DETECTORS {
                    if let Some(c) = r.cells.iter().find(|c| {
                        c.kind == kind && c.size_lpm == size && c.detector == det && c.variant == variant
                    }) {
                        let when = if variant == FROM_START {
                            "from t = 0, commissioned"
                        } else {
                            "mid-run"
                        };
                        s.push_str(&format!(
                            "| {size} | {when} | {det} | {} | {:.2} | {:.2} | {} | {} | {} | {} |\n",
                            c.runs,
                            c.p_detect,
                            c.p_isolate,
                            f(c.delay_median_s, 2),
                            f(c.delay_p95_s, 2),
                            f(c.size_error_median * 100.0, 0)
                                + if c.size_error_median.is_finite() { " %" } else { "" },
                            f(c.size_error_p95 * 100.0, 0)
                                + if c.size_error_p95.is_finite() { " %" } else { "" },
                        ));
                    }
                }
            }
        }
    }
    s.push_str(&format!(
        "\nHealthy runs: {:.2} simulated hours (all six scenarios; {:.2} h of them losing samples in gaps of 1-2000 \
         samples every 10-30 s).\n\n| detector | false alarms | per hour | 95 % upper bound per hour |\n|---|---|---|---|\n",
        r.healthy_hours, r.gap_hours
    ));
    for (i, (d, fa)) in r.false_alarms_per_hour.iter().enumerate() {
        s.push_str(&format!(
            "| {d} | {} | {} | {} |\n",
            r.false_alarm_counts.get(i).map_or(0, |c| c.1),
            f(*fa, 3),
            f(
                r.false_alarms_per_hour_upper95.get(i).map_or(f64::NAN, |c| c.1),
                3
            )
        ));
    }
    s
}

/// Plots of detection probability against leak size, both detectors, one panel per kind.
pub fn probability_figure(r: &SuiteResult) -> plot::Figure {
    let mut fig = plot::Figure::new(
        "Detection probability against leak size",
        "leak size [L/min at p_s/2]",
    );
    for kind in ["ext1", "ext2", "int"] {
        let mut panel = plot::Panel::new(&format!("{kind}: P(detect) and P(isolate)"), "probability [-]");
        for det in DETECTORS {
            let cells: Vec<&Cell> = r
                .cells
                .iter()
                .filter(|c| c.kind == kind && c.detector == det && c.variant == MID_RUN)
                .collect();
            let x: Vec<f64> = cells.iter().map(|c| c.size_lpm).collect();
            let pd: Vec<f64> = cells.iter().map(|c| c.p_detect).collect();
            let pi: Vec<f64> = cells.iter().map(|c| c.p_isolate).collect();
            panel = panel
                .with_series(plot::Series::line(&format!("{det} detect"), &x, &pd))
                .with_series(
                    plot::Series::line(&format!("{det} isolate"), &x, &pi).styled(plot::Style::Dashed),
                );
        }
        fig.panels.push(panel);
    }
    fig
}
