//! Helpers of the tests of the HTML reports: a table row's numbers, the
//! page's self-containment, and a screenshot in headless Chromium.

use std::path::Path;

use super::stderr;

/// The numbers of the report's table row named `name` (the cells after it).
pub fn row(html: &str, name: &str) -> Vec<String> {
    let start = html
        .find(&format!("<tr><td>{name}</td>"))
        .unwrap_or_else(|| panic!("no row {name}"));
    let end = start + html[start..].find("</tr>").unwrap();
    html[start..end]
        .split("<td class=\"n\">")
        .skip(1)
        .map(|c| c.split('<').next().unwrap().to_string())
        .collect()
}

/// True where headless Chromium runs; false (the test skips) only where it is
/// not required (LEAKWATCH_REQUIRE_CHROMIUM unset: CI sets it).
pub fn chromium() -> Option<&'static str> {
    let found = ["chromium", "chromium-browser"].into_iter().find(|c| {
        std::process::Command::new(c)
            .arg("--version")
            .output()
            .is_ok_and(|o| o.status.success())
    });
    if found.is_none() {
        assert!(
            std::env::var("LEAKWATCH_REQUIRE_CHROMIUM").is_err(),
            "chromium is required (.ci/setup installs it)"
        );
        eprintln!("SKIPPED: chromium is not installed");
    }
    found
}

/// Checks that `html` loads nothing from outside and prints on A4.
pub fn self_contained(html: &str) {
    for bad in ["src=", "href=", "@import", "url(", "<link", "<script"] {
        assert!(!html.contains(bad), "the report holds `{bad}`");
    }
    // an address only as an SVG's namespace, which is a name, not fetched
    for (i, _) in html.match_indices("http") {
        assert!(
            html[..i].ends_with("xmlns=\"") || html[..i].ends_with("xmlns:xlink=\""),
            "an address in the report: {}",
            &html[i..(i + 60).min(html.len())]
        );
    }
    assert!(html.contains("@page { size: A4") && html.contains("max-width"));
}

/// Opens `html_path` in headless Chromium, where it runs, and checks the
/// screenshot it takes (into `dir`).
pub fn screenshot(html_path: &Path, dir: &Path) {
    let Some(browser) = chromium() else {
        return;
    };
    let shot = html_path.with_extension("png");
    let o = std::process::Command::new(browser)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--no-first-run",
            "--window-size=794,1123",
            &format!("--user-data-dir={}", dir.join("chromium").display()),
            &format!("--screenshot={}", shot.display()),
            &format!("file://{}", html_path.display()),
        ])
        .output()
        .expect("chromium runs");
    assert!(o.status.success(), "{}", stderr(&o));
    let png = std::fs::read(&shot).expect("the screenshot is written");
    assert!(
        png.len() > 10_000 && png.starts_with(b"\x89PNG"),
        "{} bytes",
        png.len()
    );
}
