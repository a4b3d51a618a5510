//! The benchmark report rendered: the Markdown tables, the JSON, the files written.

use super::{BenchReport, CaseResult};

impl BenchReport {
    /// The suite's table (docs/calibration/README.md#results) as Markdown.
    pub fn markdown(&self) -> String {
        let mut s = self.effect_by_input();
        s.push_str("| case | scenario | hidden | named | right | max param error | gap shrink | time |\n");
        s.push_str("|---|---|---|---|---|---|---|---|\n");
        for r in &self.cases {
            let hidden = if r.hidden.is_empty() {
                "—".to_string()
            } else {
                r.hidden.join(" + ")
            };
            let named = if r.named.is_empty() {
                "nothing".to_string()
            } else {
                r.named.join(", ")
            };
            let right = if r.hidden.is_empty() {
                if r.named.is_empty() {
                    "yes (quiet)"
                } else {
                    "NO (false claim)"
                }
            } else if r.all_found && !r.caveats.is_empty() {
                "yes (form not identifiable)"
            } else if r.all_found {
                "yes"
            } else if r.right_first {
                "first only"
            } else {
                "NO"
            };
            let perr = if r.hidden.is_empty() {
                "—".to_string()
            } else {
                format!("{:.1} %", 100.0 * r.max_parameter_error)
            };
            s.push_str(&format!(
                "| {} | {} | {} | {} | {} | {} | {:.0} % ({:.3} → {:.3}) | {:.2} s (+{:.2} s sim) |\n",
                r.case,
                r.scenario,
                hidden,
                named,
                right,
                perr,
                100.0 * r.gap_shrink,
                r.gap_before,
                r.gap_after,
                r.calibrate_s,
                r.simulate_s
            ));
            if let Some(e) = &r.error {
                s.push_str(&format!("|  | error: {e} |  |  |  |  |  |  |\n"));
            }
        }
        let caveated: Vec<&CaseResult> = self.cases.iter().filter(|r| !r.caveats.is_empty()).collect();
        if !caveated.is_empty() {
            s.push_str("\nWhat the workflow said it could not tell:\n\n");
            for r in caveated {
                let eff = r
                    .effective_bulk_modulus_error
                    .map(|e| {
                        format!(
                            " (effective bulk modulus at the mean chamber pressure: {:.1} % off)",
                            100.0 * e
                        )
                    })
                    .unwrap_or_default();
                s.push_str(&format!("- {}{eff}: {}\n", r.case, r.caveats.join("; ")));
            }
        }
        s.push_str("\nParameters (fitted vs truth, SI) and what was stated not identifiable:\n\n");
        for r in self.cases.iter().filter(|r| !r.hidden.is_empty()) {
            let mut parts: Vec<String> = r
                .parameters
                .iter()
                .map(|p| {
                    format!(
                        "{} {:.4e} vs {:.4e} ({:.1} %)",
                        p.parameter,
                        p.fitted,
                        p.truth,
                        100.0 * p.relative_error
                    )
                })
                .collect();
            parts.extend(r.not_identifiable.iter().cloned());
            s.push_str(&format!("- {}: {}\n", r.case, parts.join("; ")));
        }
        s.push_str(&format!(
            "\nRight effect named first: {} of {}; clean controls quiet: {} of {}; median gap shrink {:.0} %.\n",
            self.right_first[0],
            self.right_first[1],
            self.controls_quiet[0],
            self.controls_quiet[1],
            100.0 * self.median_gap_shrink
        ));
        s.push_str(&format!(
            "Right effect named first: {:.0} % (target ≥ 95 %); parameters within 10 %: {:.0} %; \
             gap shrink ≥ 70 %: {:.0} %; effects claimed on clean data: {} (target 0); total {:.1} s.\n",
            100.0 * self.right_named_rate,
            100.0 * self.params_within_10pct_rate,
            100.0 * self.gap_shrink_70pct_rate,
            self.clean_false_claims,
            self.total_s
        ));
        s
    }

    /// The effect × input grid of the matrix cases (named `EFFECT / SCENARIO`,
    /// see [`matrix_cases`](super::matrix_cases)) as Markdown, one cell per case: `pass` when the
    /// hidden effect was named first and alone, its parameters are within
    /// 10 % and the gap shrank by at least 70 %, with the largest parameter
    /// error and the shrink; empty when there are no such cases.
    pub fn effect_by_input(&self) -> String {
        let cells: Vec<(&str, &str, &CaseResult)> = self
            .cases
            .iter()
            .filter_map(|r| r.case.split_once(" / ").map(|(e, sc)| (e, sc, r)))
            .collect();
        if cells.is_empty() {
            return String::new();
        }
        let mut effects: Vec<&str> = Vec::new();
        let mut scenarios: Vec<&str> = Vec::new();
        for (e, sc, _) in &cells {
            if !effects.contains(e) {
                effects.push(e);
            }
            if !scenarios.contains(sc) {
                scenarios.push(sc);
            }
        }
        let mut s = String::from("| effect | ");
        s.push_str(&scenarios.join(" | "));
        s.push_str(" |\n|---|");
        s.push_str(&"---|".repeat(scenarios.len()));
        s.push('\n');
        let (mut pass, mut total) = (0, 0);
        for e in &effects {
            s.push_str(&format!("| {e} |"));
            for sc in &scenarios {
                let Some((_, _, r)) = cells.iter().find(|(a, b, _)| a == e && b == sc) else {
                    s.push_str(" — |");
                    continue;
                };
                total += 1;
                let ok = r.error.is_none()
                    && r.right_first
                    && r.all_found
                    && r.max_parameter_error <= 0.10
                    && r.gap_shrink >= 0.70;
                let verdict = if ok && r.caveats.is_empty() {
                    pass += 1;
                    "pass".to_string()
                } else if r.right_first && r.all_found && !r.caveats.is_empty() {
                    let eff = r
                        .effective_bulk_modulus_error
                        .map(|x| format!(", effective β {:.1} %", 100.0 * x))
                        .unwrap_or_default();
                    format!("named, form not identifiable{eff}")
                } else {
                    "FAIL".to_string()
                };
                s.push_str(&format!(
                    " {verdict} ({:.1} %, {:.0} %) |",
                    100.0 * r.max_parameter_error,
                    100.0 * r.gap_shrink
                ));
            }
            s.push('\n');
        }
        s.push_str(&format!(
            "\n{pass} of {total} effect × input cases pass (in brackets: largest parameter error, gap shrink).\n\n"
        ));
        s
    }

    /// The report as pretty JSON.
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).unwrap_or_else(|e| format!("{{\"error\": \"{e}\"}}"))
    }

    /// Writes `DIR/calibration_bench.md` and `DIR/calibration_bench.json` and returns their
    /// paths; existing ones are replaced only if `overwrite` (`--force`), symbolic links never.
    pub fn write(
        &self,
        dir: &std::path::Path,
        overwrite: bool,
    ) -> Result<[std::path::PathBuf; 2], crate::CalibrateError> {
        let io = |path: &std::path::Path| {
            let path = path.to_path_buf();
            move |source| crate::CalibrateError::Io { path, source }
        };
        use dataset::output::{check_replaceable, create_dir, write_file};
        create_dir(dir).map_err(io(dir))?;
        let md = dir.join("calibration_bench.md");
        let js = dir.join("calibration_bench.json");
        for p in [&md, &js] {
            check_replaceable(p, overwrite, &[]).map_err(io(p))?;
        }
        write_file(&md, self.markdown().as_bytes(), true, &[]).map_err(io(&md))?;
        write_file(&js, self.to_json().as_bytes(), true, &[]).map_err(io(&js))?;
        Ok([md, js])
    }
}
