//! What `leakwatch run` prints at the end: the per-stage table, the leak it
//! detected (or none), the UDP stream's counts, and the files written.

use detect::{LeakEvent, Phase};

use crate::args::{parse_source, RunArgs, RunSource};
use crate::stages::Stage;
use crate::supervisor::RunOutcome;
use pipeline::out::outln;

/// Prints the summary of the run `o` made for `args`.
pub(super) fn print(args: &RunArgs, o: &RunOutcome) -> Result<(), String> {
    outln!("\n| stage | frames in | frames out | missing | latency p50 µs (median 1-s p50) | worst 1-s p99 µs | max µs | proc p50 µs | CPU % | RSS MB |");
    outln!("|---|---|---|---|---|---|---|---|---|---|");
    for (name, f) in &o.latency.stages {
        outln!(
            "| {name} | {} | {} | {} | {:.1} | {:.1} | {:.1} | {:.1} | {:.1} | {:.1} |",
            f.frames_in,
            f.frames_out,
            f.seq_gaps,
            f.latency_p50_us,
            f.latency_worst_1s_p99_us,
            f.latency_max_us,
            f.proc_p50_us,
            f.cpu_fraction * 100.0,
            f.rss_mb
        );
    }
    let faults: Vec<String> = o
        .latency
        .stalls
        .iter()
        .map(|(name, st)| (name, st, o.latency.restarts.get(name).copied().unwrap_or(0)))
        .filter(|(_, st, restarts)| st.count > 0 || *restarts > 0)
        .map(|(name, st, restarts)| {
            format!(
                "{name}: {restarts} restarts, {} stalls (longest {:.1} s, {} killed)",
                st.count, st.longest_s, st.killed
            )
        })
        .collect();
    if !faults.is_empty() {
        outln!("\nsupervision: {}", faults.join("; "));
    }
    let leaks: Vec<&LeakEvent> = o
        .events
        .iter()
        .filter(|e| e.kind.is_leak() && e.phase == Phase::Raised && e.detector == "leak-size")
        .collect();
    match leaks.first() {
        Some(e) => outln!(
            "\ndetected: {} leak at t = {:.2} s (onset {:.2} s), {:.3} L/min at the measured pressures",
            e.kind.name(),
            e.t_detect_s,
            e.t_onset_s,
            o.events
                .iter()
                .rev()
                .find(|x| x.event_id == e.event_id && x.detector == e.detector)
                .map_or(e.size_lpm, |x| x.size_lpm)
        ),
        None => match o
            .events
            .iter()
            .find(|e| e.kind.is_leak_alarm() && e.phase == Phase::Raised && e.detector == "leak-size")
        {
            Some(e) => outln!(
                "\ndetected: a leak at t = {:.2} s (onset {:.2} s), kind not decided yet ({})",
                e.t_detect_s,
                e.t_onset_s,
                e.detail
            ),
            None => match o.events.iter().find(|e| e.kind == detect::EventKind::NotArmed) {
                Some(e) => {
                    outln!(
                        "\nNOT WATCHED: the leak detector never armed in this run ({}): no leak could have been seen",
                        e.detail
                    );
                    pipeline::status::set_not_watched();
                }
                None => outln!("\nno leak detected"),
            },
        },
    }
    // monitoring went on; what did not is said plainly, with exit status 4 (status.rs)
    if let Some(why) = &o.log_failure {
        outln!("LOG FAILED: {why}; monitoring went on to the end without a log (the events above are all of them)");
        pipeline::status::set_output_failed();
    }
    for why in &o.output_failures {
        outln!("OUTPUT FAILED: {why}");
        pipeline::status::set_output_failed();
    }
    if matches!(parse_source(args.source.as_deref()), Ok(RunSource::Udp(_))) {
        // the stream's counts (lost, duplicated, late, malformed), from the acquisition's closing line
        let log = std::fs::read_to_string(o.out_dir.join("acquisition.log")).unwrap_or_default();
        if let Some(line) = log.lines().find_map(|l| l.strip_prefix("acquisition: udp: ")) {
            outln!("UDP stream: {line}");
        }
    }
    // a restarted recorder continues the log in run-1.mcap, run-2.mcap, ...; a
    // recorder continues its file after an hour in run.1.mcap, ...
    let restarted = o
        .latency
        .restarts
        .get(Stage::Recorder.name())
        .copied()
        .unwrap_or(0)
        > 0;
    let log: Vec<String> = pipeline::logs::log_parts(&o.out_dir.join("run.mcap"))
        .iter()
        .filter_map(|p| p.file_name().map(|n| n.to_string_lossy().into_owned()))
        .collect();
    // events.json and latency.json where they are (the temporary directory when the
    // output directory could not take them)
    let mut here = Vec::new();
    let mut elsewhere = Vec::new();
    for (name, at) in [("events.json", &o.events_path), ("latency.json", &o.latency_path)] {
        match at {
            Some(p) if p.parent() == Some(o.out_dir.as_path()) => here.push(name.to_string()),
            Some(p) => elsewhere.push(format!("{name} to {}", p.display())),
            None => elsewhere.push(format!("no {name}")),
        }
    }
    here.extend(log.iter().cloned());
    if !elsewhere.is_empty() {
        outln!("wrote {}", elsewhere.join(", "));
    }
    outln!(
        "wrote {}/{}{}",
        o.out_dir.display(),
        here.join(", "),
        if o.log_failure.is_some() {
            " (incomplete: the recorder could not write it)"
        } else if restarted {
            " (the recorder was restarted: the log continues part after part, the frames in none recorded as a gap)"
        } else if log.len() > 1 {
            " (the log continues part after part, a new one every hour)"
        } else {
            ""
        }
    );
    // the processes' own logs (live view and gateway included, when they ran) and the config
    let mut beside: Vec<String> = std::fs::read_dir(&o.out_dir)
        .map(|dir| {
            dir.filter_map(|e| e.ok())
                .map(|e| e.file_name().to_string_lossy().into_owned())
                .filter(|n| n.ends_with(".log"))
                .collect()
        })
        .unwrap_or_default();
    beside.sort();
    if o.out_dir.join("config.toml").is_file() {
        beside.push("config.toml".into());
    }
    if !beside.is_empty() {
        outln!("beside them: {}", beside.join(", "));
    }
    Ok(())
}
