use super::*;
use detect::{EventKind, Phase};

fn raised(kind: EventKind, id: u64, t_s: f64, size_lpm: f64) -> LeakEvent {
    LeakEvent {
        kind,
        phase: Phase::Raised,
        detector: "leak-size".into(),
        event_id: id,
        t_detect_s: t_s,
        t_onset_s: 20.0,
        size_lpm,
        size_lpm_sigma: 0.01,
        size_nominal_lpm: size_lpm,
        coefficient_m3_s_sqrt_pa: 1e-9,
        statistic: 6.0,
        threshold: 5.0,
        confidence: 0.99,
        channel: String::new(),
        detail: String::new(),
    }
}

fn truth(kind: &str) -> Truth {
    Truth {
        run: "run_x".into(),
        scenario: "cl_sine".into(),
        kind: kind.into(),
        size_nominal_lpm: 0.25,
        t_on_s: 20.0,
        ramp_s: 4.0,
        observed_flow_lpm: 0.25,
    }
}

/// A 60 s run at 1 kHz with the events `events`, no sensor event, thresholds
/// of 0.04 L/min, the flow past both floors at the onset (20 s).
fn file_run(events: Vec<LeakEvent>) -> FileRun {
    FileRun {
        events,
        sensor_raised_s: vec![],
        samples: 60_000,
        t_end_s: 60.0,
        thresholds_lpm: [0.04; 3],
        thresholds_sigma: [5.0; 3],
        blind_s: 0.0,
        blind_by_cause: detect::BlindSeconds::default(),
        t_detectable_s: [20.0, 20.0],
        floors_lpm: [0.04, 0.06],
        size_window_s: 2.0,
        true_flows: None,
    }
}

#[test]
fn a_run_is_scored_at_its_first_alarm_and_its_first_named_kind() {
    // A false alarm at 10 s; the leak raised with its kind pending at 21.0 s,
    // named ext1 at 22.5 s; the real flow reached 0.04 L/min at 20.64 s and
    // 0.06 L/min at 20.96 s.
    let run = FileRun {
        // one sensor event before the onset, one after
        sensor_raised_s: vec![5.0, 30.0],
        t_detectable_s: [20.64, 20.96],
        ..file_run(vec![
            raised(EventKind::Ext2, 1, 10.0, 0.1),
            raised(EventKind::Leak, 2, 21.0, 0.12),
            raised(EventKind::Ext1, 2, 22.5, 0.2),
        ])
    };
    let o = score_run(truth("ext1"), &run);
    assert!(o.detected);
    assert_eq!((o.kind_first.as_str(), o.false_alarms), ("ext1", 1));
    assert_eq!(o.sensor_events, 1);
    assert!((o.delay_s - 1.0).abs() < 1e-9, "{}", o.delay_s);
    assert!((o.delay_named_s - 2.5).abs() < 1e-9, "{}", o.delay_named_s);
    // from the external floor for an external leak, the internal one for an internal leak
    assert!(
        (o.delay_after_detectable_s - 0.36).abs() < 1e-9,
        "{}",
        o.delay_after_detectable_s
    );
    let o = score_run(truth("int"), &run);
    assert!(
        (o.delay_after_detectable_s - 0.04).abs() < 1e-9,
        "{}",
        o.delay_after_detectable_s
    );
    assert_eq!(o.kind_first, "ext1", "named wrong");
    // without a logged flow, from the truth's ramp: 0.25 L/min over 4 s
    // reaches 0.04 L/min 0.64 s after the onset
    let unlogged = FileRun {
        t_detectable_s: [f64::NAN; 2],
        ..run.clone()
    };
    let o = score_run(truth("ext1"), &unlogged);
    assert!(
        (o.delay_after_detectable_s - 0.36).abs() < 1e-9,
        "{}",
        o.delay_after_detectable_s
    );
    let s = summarise_data(
        vec![score_run(truth("ext1"), &run), score_run(truth("int"), &run)],
        0.0,
    );
    let row = &s.by_size[0];
    assert_eq!((row.runs, row.p_detect, row.p_kind_first), (2, 1.0, 0.5));
    assert!((row.delay_named_median_s - 2.5).abs() < 1e-9);
    assert!(data_markdown(&s).contains("| 0.25 | 2 | 100 % | 50 % | 1.00 | 1.00 | 0.20 | 2.50 |"));
    // the named size 0.2 L/min: 20 % under the run's mean flow (0.25), right
    // against a true flow of 0.2 L/min over the detector's window
    assert!(
        (row.size_error_median - 0.2).abs() < 1e-9,
        "{}",
        row.size_error_median
    );
    let t_s: Vec<f64> = (0..60_000).map(|i| f64::from(i) * 1e-3).collect();
    // the truth's ramp: 0.2 L/min fully open, from 20 s over 4 s
    let flow_lpm = t_s
        .iter()
        .map(|&t| 0.2 * ((t - 20.0) / 4.0).clamp(0.0, 1.0))
        .collect();
    let with_flows = FileRun {
        true_flows: Some(TrueFlows { t_s, flow_lpm }),
        ..run.clone()
    };
    let o = score_run(truth("ext1"), &with_flows);
    // named at 22.5 s, 5/8 open: it passed 0.125 L/min, and the 0.2 named is 60 % over
    assert!((o.true_flow_lpm[1] - 0.125).abs() < 1e-6, "{:?}", o.true_flow_lpm);
    let s = summarise_data(vec![o], 0.0);
    let e = s.by_size[0].size_error_median;
    assert!((e - 0.6).abs() < 1e-5, "{e}");
    assert!(
        s.from_quarter_lpm.is_none(),
        "one size: no row over the larger ones"
    );
}

#[test]
fn leaks_of_a_quarter_litre_and_more_are_summed_in_one_row() {
    // 0.1 L/min found at 3 s; 0.25 at 1 s; 0.5 at 0.2 s and 0.4 s; one 0.5
    // run never found: the row over 0.25 L/min and more holds the last four
    let run = |size: f64, alarm_s: Option<f64>| {
        let events = alarm_s
            .map(|t| raised(EventKind::Ext1, 1, 20.0 + t, size))
            .into_iter()
            .collect();
        let truth = Truth {
            size_nominal_lpm: size,
            observed_flow_lpm: size,
            ramp_s: 0.0,
            ..truth("ext1")
        };
        score_run(truth, &file_run(events))
    };
    let s = summarise_data(
        vec![
            run(0.1, Some(3.0)),
            run(0.25, Some(1.0)),
            run(0.5, Some(0.2)),
            run(0.5, Some(0.4)),
            run(0.5, None),
        ],
        0.0,
    );
    let row = s
        .from_quarter_lpm
        .as_ref()
        .expect("two sizes of 0.25 L/min and more");
    assert_eq!((row.size_nominal_lpm, row.runs), (0.25, 4));
    assert!((row.p_detect - 0.75).abs() < 1e-12, "{}", row.p_detect);
    // the median of 0.2, 0.4 and 1.0 s
    assert!((row.delay_median_s - 0.4).abs() < 1e-9, "{}", row.delay_median_s);
    assert!(data_markdown(&s).contains("| ≥ 0.25 | 4 | 75 % | 75 % | 0.40 |"));
}
