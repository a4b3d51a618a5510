use super::*;
use detect::{EventKind, LeakEvent, Phase};
use model::sample::Sample;

/// An event of `kind` raised at `t_s` (s) on `channel`.
fn raised(kind: EventKind, t_s: f64, channel: &str) -> LeakEvent {
    let detector = if channel.is_empty() {
        "leak-size"
    } else {
        "sensors"
    };
    let mut e = LeakEvent::plain(kind, Phase::Raised, detector, 1, t_s, f64::NAN);
    e.channel = channel.into();
    e
}

#[test]
fn a_sensor_event_on_the_faulty_channel_after_the_onset_is_named_right() {
    let mut events = [
        raised(EventKind::SensorOffset, 10.0, "p2"),
        raised(EventKind::SensorOffset, 31.5, "p2"),
        raised(EventKind::SensorOffset, 33.0, "p1"),
    ];
    // p1's event says it has read off since 28.5 s
    events[2].t_onset_s = 28.5;
    let o = score(
        0,
        RunKind::PressureDrift,
        String::new(),
        "p1".into(),
        30.0,
        "lift",
        &events,
    );
    assert!(o.named_right);
    assert_eq!(o.delay_s, 3.0);
    assert_eq!(o.sensor_events_before_onset, 1);
    assert_eq!(o.leak_events, 0);
    assert_eq!(o.first_sensor, Some(("sensor-offset".into(), "p2".into(), 31.5)));
    assert_eq!(o.stated_onset_error_s, -1.5);
    // on the wrong channel only: not named right
    let o = score(
        0,
        RunKind::PressureDrift,
        String::new(),
        "p1".into(),
        30.0,
        "lift",
        &events[..2],
    );
    assert!(!o.named_right && o.delay_s.is_nan() && o.stated_onset_error_s.is_nan());
}

#[test]
fn a_pending_leak_counts_as_a_leak_event_in_a_sensor_fault_run() {
    let events = [
        raised(EventKind::Leak, 50.0, ""),
        raised(EventKind::SensorStuck, 32.0, "x"),
    ];
    // a stuck x from 30 s on the lift's cycle
    let stuck_x =
        |events: &[LeakEvent]| score(0, RunKind::Stuck, String::new(), "x".into(), 30.0, "lift", events);
    let o = stuck_x(&events);
    assert_eq!(o.leak_events, 1);
    assert!(o.leak_alarm_at_end);
    assert!(o.named_right);
    assert_eq!(o.delay_s, 2.0);
    // cleared (withdrawn when the transducer was named): raised, but not standing at the end
    let mut cleared = raised(EventKind::Leak, 52.0, "");
    cleared.phase = Phase::Cleared;
    let events = [events[0].clone(), events[1].clone(), cleared];
    let o = stuck_x(&events);
    assert_eq!(o.leak_events, 1);
    assert!(!o.leak_alarm_at_end);
}

#[test]
fn the_leak_run_is_named_right_only_by_its_own_kind_before_any_sensor_event() {
    let right = [
        raised(EventKind::Leak, 31.0, ""),
        raised(EventKind::Int, 32.0, ""),
    ];
    let o = score(
        0,
        RunKind::Leak,
        String::new(),
        "int".into(),
        30.0,
        "press",
        &right,
    );
    assert!(o.named_right);
    assert_eq!((o.delay_s, o.leak_events), (2.0, 0));
    let wrong_kind = [raised(EventKind::Ext1, 32.0, "")];
    let o = score(
        0,
        RunKind::Leak,
        String::new(),
        "int".into(),
        30.0,
        "press",
        &wrong_kind,
    );
    assert!(!o.named_right);
    let sensor_first = [
        raised(EventKind::SensorOffset, 31.0, "p1"),
        raised(EventKind::Int, 32.0, ""),
    ];
    let o = score(
        0,
        RunKind::Leak,
        String::new(),
        "int".into(),
        30.0,
        "press",
        &sensor_first,
    );
    assert!(!o.named_right);
    // an alarm before the leak opened is a false one
    let early = [
        raised(EventKind::Leak, 12.0, ""),
        raised(EventKind::Int, 32.0, ""),
    ];
    let o = score(
        0,
        RunKind::Leak,
        String::new(),
        "int".into(),
        30.0,
        "press",
        &early,
    );
    assert_eq!(o.leak_events, 1);
}

/// A run of readings from 0 to `end_s` (s) at 1 kHz, p1 at `p1_pa` and p2 at twice it (Pa).
fn readings(end_s: f64, p1_pa: f64) -> Vec<Sample> {
    (0..=(end_s * 1e3) as usize)
        .map(|i| Sample::new(i as f64 * 1e-3, 0.0, 0.1, p1_pa, 2.0 * p1_pa))
        .collect()
}

#[test]
fn a_faults_misreading_is_its_offset_at_the_end_or_its_span_at_the_mean_reading() {
    let fault = |channel, kind| SensorFault {
        channel,
        kind,
        onset_s: 20.0,
    };
    let run = readings(100.0, 5e6);
    // a drift of 3 kPa/s from 20 s, capped at 500 kPa: 240 kPa by 100 s; a drift is named from 1 % of 25 MPa, 250 kPa
    let drift = |max_abs_si| SensorFaultKind::Drift {
        rate_si_per_s: -3e3,
        max_abs_si,
    };
    let m = Misreading::of(&fault(Channel::P2, drift(5e5)), &run, 25e6, [0.0; 2]);
    assert!((m.size - 240.0).abs() < 1e-6 && m.least_named == 250.0, "{m:?}");
    assert!(!m.past_least_named());
    let m = Misreading::of(&fault(Channel::P2, drift(2e5)), &run, 25e6, [0.0; 2]);
    assert!((m.size - 200.0).abs() < 1e-6, "{m:?}");
    // a span error of +2 % grown over 30 s: p1 reads 5 MPa, so 2/102 of it;
    // named from 0.5 % of the range (75 kPa of 15 MPa)
    let span = SensorFaultKind::Span {
        gain_error: 0.02,
        ramp_s: 30.0,
    };
    let m = Misreading::of(&fault(Channel::P1, span), &run, 25e6, [0.0; 2]);
    assert!((m.size - 5e3 * 0.02 / 1.02).abs() < 1e-9, "{m:?}");
    let m = Misreading::of(&fault(Channel::P2, span), &run, 15e6, [0.0; 2]);
    assert!(
        (m.size - 1e4 * 0.02 / 1.02).abs() < 1e-9 && (m.least_named - 75.0).abs() < 1e-9,
        "{m:?}"
    );
    assert!(m.past_least_named());
    // with a datasheet's 50 kPa and 0.5 %: p2 reads 10 MPa, 9.8 MPa with the
    // span error taken off, where a sound transducer reads up to 99 kPa off:
    // under 0.5 % of 25 MPa (125 kPa), over 0.5 % of 15 MPa
    let sound = [50e3, 0.005];
    let m = Misreading::of(&fault(Channel::P2, span), &run, 25e6, sound);
    assert!(
        (m.least_named - (50.0 + 0.005 * 1e4 / 1.02)).abs() < 1e-6,
        "{m:?}"
    );
    let m = Misreading::of(&fault(Channel::P2, span), &run, 15e6, sound);
    assert!((m.least_named - 75.0).abs() < 1e-9, "{m:?}");
    // x drifting at 1.5 mm/min for 80 s: 2 mm, past the least named 1 mm
    let x = SensorFaultKind::Drift {
        rate_si_per_s: 1.5e-3 / 60.0,
        max_abs_si: f64::INFINITY,
    };
    let m = Misreading::of(&fault(Channel::X, x), &run, 25e6, [0.0; 2]);
    assert!((m.size - 2.0).abs() < 1e-9 && m.least_named == 1.0, "{m:?}");
    // against what commissioning stated: on a plant rig whose x moves the
    // leak sizes by 0.0004 L/min per mm, x is not watched (past 22.5 mm);
    // the pressures from the 0.5 % floor (a drift from 1 %); on a rig whose x moves them by 0.01,
    // from 1 mm
    let plant = pipeline::commission::SensorReach::new([0.5, 0.05, 0.0004], [0.05, 0.03, 0.04], 25e6);
    let stated = m.stated_by(Channel::X, &plant);
    assert!(stated.said_not_watched() && !stated.past_stated(), "{stated:?}");
    assert!(Misreading::NONE.stated.is_nan() && !Misreading::NONE.said_not_watched());
    let thesis = pipeline::commission::SensorReach::new([0.5, 0.05, 0.01], [0.05, 0.03, 0.04], 25e6);
    let stated = m.stated_by(Channel::X, &thesis);
    assert!(stated.stated == 1.0 && stated.past_stated() && !stated.said_not_watched());
    let drift =
        Misreading::of(&fault(Channel::P2, drift(5e5)), &run, 25e6, [0.0; 2]).stated_by(Channel::P2, &plant);
    assert!(drift.stated == 250.0 && !drift.past_stated(), "{drift:?}");
    // a stuck transducer has no size to compare
    let m = Misreading::of(&fault(Channel::P1, SensorFaultKind::Stuck), &run, 25e6, [0.0; 2]);
    assert!(m.size.is_nan() && !m.past_least_named());
}

#[test]
fn the_drawn_faults_are_in_the_stated_ranges_and_their_specs_parse_back() {
    let mut rng = Rng::new(7);
    for _ in 0..200 {
        let (f, _) = draw_fault(RunKind::PressureDrift, 25.0, &mut rng);
        let f = f.expect("a drift");
        assert!(f.channel.is_pressure());
        let SensorFaultKind::Drift {
            rate_si_per_s,
            max_abs_si,
        } = f.kind
        else {
            panic!("{f:?}")
        };
        let kpa_per_min = rate_si_per_s.abs() * 60.0 / 1e3;
        assert!((DRIFT_RATE_KPA_PER_MIN.0..=DRIFT_RATE_KPA_PER_MIN.1).contains(&kpa_per_min));
        assert_eq!(max_abs_si, DRIFT_MAX_KPA * 1e3);
        assert_eq!(SensorFault::parse(&f.to_string()).expect("parses"), f);

        let (f, _) = draw_fault(RunKind::Span, 25.0, &mut rng);
        let f = f.expect("a span error");
        let SensorFaultKind::Span { gain_error, ramp_s } = f.kind else {
            panic!("{f:?}")
        };
        assert!((SPAN_PERCENT.0..=SPAN_PERCENT.1).contains(&(gain_error.abs() * 100.0)));
        assert!((SPAN_RAMP_S.0..=SPAN_RAMP_S.1).contains(&ramp_s));
        assert!(f.channel.is_pressure());

        let (f, _) = draw_fault(RunKind::PositionDrift, 25.0, &mut rng);
        let f = f.expect("a position drift");
        assert_eq!(f.channel, Channel::X);
        let SensorFaultKind::Drift { rate_si_per_s, .. } = f.kind else {
            panic!("{f:?}")
        };
        let mm_per_min = rate_si_per_s.abs() * 60.0 * 1e3;
        assert!(
            (POSITION_DRIFT_MM_PER_MIN.0 - 1e-9..=POSITION_DRIFT_MM_PER_MIN.1 + 1e-9).contains(&mm_per_min)
        );

        let (f, leak) = draw_fault(RunKind::Leak, 25.0, &mut rng);
        assert!(f.is_none() && ["ext1", "ext2", "int"].contains(&leak.expect("a kind")));
        assert_eq!(draw_fault(RunKind::Healthy, 25.0, &mut rng), (None, None));
    }
}

/// One instance of the built-in rig, seed 1, runs of 360 s on one thread,
/// into `out`: nothing kept, no thermometer.
fn one_thesis_instance(out: std::path::PathBuf) -> SensorFaultsArgs {
    SensorFaultsArgs {
        rig: Some("thesis".into()),
        data: None,
        config: None,
        instances: 1,
        seed: 1,
        seconds: 360.0,
        out,
        threads: Some(1),
        keep: false,
        temp_c: false,
    }
}

/// The whole command on one instance of the built-in rig with short runs: the
/// report is written, every run kind is there, a stuck transducer is named on
/// its channel, the leak is named as itself and the healthy twin stays quiet.
#[test]
fn one_thesis_instance_is_commissioned_watched_and_scored() {
    let dir = scratch::ScratchDir::new("sensor-faults");
    let args = SensorFaultsArgs {
        seed: 3,
        seconds: 75.0,
        threads: Some(2),
        keep: true,
        ..one_thesis_instance(dir.to_path_buf())
    };
    command(&args, false).expect("the bench runs");
    // --keep: the commissioned config parses and holds the learned state; every run's recording is there
    let rig = std::fs::read_to_string(dir.join("inst_000/rig.toml")).expect("rig.toml");
    let rig = Config::parse(&rig).expect("the kept config parses");
    assert!(rig.classifier.commissioning.is_some());
    for kind in RUN_KINDS {
        let path = kept_recording(&args, 0, kind);
        let rows = std::fs::read_to_string(&path).expect("a kept recording");
        assert!(rows.lines().count() > 70_000, "{}", path.display());
    }
    let text = std::fs::read_to_string(dir.join("sensor_faults.json")).expect("the report");
    let json: serde_json::Value = serde_json::from_str(&text).expect("JSON");
    let runs = json["runs"].as_array().expect("runs");
    assert_eq!(runs.len(), RUN_KINDS.len());
    let run = |kind: &str| runs.iter().find(|r| r["kind"] == kind).expect(kind);
    assert_eq!(run("healthy")["leak_events"], 0, "{text}");
    assert_eq!(run("healthy")["sensor_events_before_onset"], 0, "{text}");
    assert_eq!(run("stuck")["named_right"], true, "{text}");
    assert_eq!(run("leak")["named_right"], true, "{text}");
    // the drifts and the span error carry their misreading (kPa or mm), the others none
    for kind in ["pressure-drift", "span", "position-drift"] {
        let size = run(kind)["misreading"]["size"].as_f64().expect("a size");
        assert!(size > 0.0, "{kind}: {text}");
    }
    assert!(run("stuck")["misreading"]["size"].is_null(), "{text}");
    assert!(std::fs::read_to_string(dir.join("sensor_faults.md"))
        .expect("md")
        .contains("| stuck | 1 |"));
    // the second run refuses to overwrite without --force
    assert!(command(&args, false).is_err());
}

/// Writes `seconds` of the built-in rig on `scenario` (seed `seed`) to `path`.
fn write_recording(path: &std::path::Path, scenario: &str, seconds: f64, seed: u64) {
    let req = SimulateRequest {
        scenario: scenario.into(),
        seconds: Some(seconds),
        seed,
        faults: vec![],
        rig_variant: None,
    };
    let (mut sim, seconds) = simulate::build(&Config::default(), &req).expect("a simulator");
    let mut w = std::io::BufWriter::new(std::fs::File::create(path).expect("a file"));
    simulate::write_csv(&mut w, &sim.run(seconds)).expect("written");
}

/// `--data` on a plant-style folder of the built-in rig (a commissioning
/// recording, one healthy run and one leak run): the chain is commissioned on
/// the recording, the faults are laid onto the healthy run only, every sensor
/// kind is watched once per instance and the healthy run once, no leak run.
#[test]
fn a_folders_healthy_recordings_carry_the_drawn_faults() {
    let data = scratch::ScratchDir::new("sensor-faults-data");
    write_recording(&data.join("commission_cold.csv"), "loaded-random", 60.0, 5);
    for (run, fault) in [
        ("run_000", "null"),
        ("run_001", r#"{"kind": "ext1", "size_lpm": 0.5, "t_on_s": 5.0}"#),
    ] {
        let dir = data.join(run);
        std::fs::create_dir(&dir).expect("a run folder");
        write_recording(&dir.join("measured.csv"), "loaded-random", 75.0, 6);
        let truth = format!(r#"{{"fault": {fault}, "scenario": {{"name": "loaded-random"}}}}"#);
        std::fs::write(dir.join("truth.json"), truth).expect("truth");
    }
    let out = scratch::ScratchDir::new("sensor-faults-data-out");
    let args = SensorFaultsArgs {
        rig: None,
        data: Some(data.to_path_buf()),
        config: None,
        instances: 2,
        seed: 3,
        seconds: 360.0,
        out: out.to_path_buf(),
        threads: Some(2),
        keep: true,
        temp_c: false,
    };
    command(&args, false).expect("the bench runs");
    let text = std::fs::read_to_string(out.join("sensor_faults.json")).expect("the report");
    let json: serde_json::Value = serde_json::from_str(&text).expect("JSON");
    assert_eq!(
        json["recordings"],
        serde_json::json!(["run_000 loaded-random"]),
        "{text}"
    );
    let runs = json["runs"].as_array().expect("runs");
    // the healthy run once, five sensor faults per instance
    assert_eq!(runs.len(), 1 + 2 * 5, "{text}");
    let of = |kind: &str| runs.iter().filter(|r| r["kind"] == kind).collect::<Vec<_>>();
    assert!(of("leak").is_empty());
    assert_eq!(of("healthy")[0]["leak_events"], 0, "{text}");
    assert_eq!(of("healthy")[0]["sensor_events_before_onset"], 0, "{text}");
    for stuck in of("stuck") {
        assert_eq!(stuck["named_right"], true, "{text}");
    }
    // each instance draws its own faults
    assert_ne!(of("pressure-drift")[0]["spec"], of("pressure-drift")[1]["spec"]);
    // --keep: the one commissioned config, and each run's recording with its fault laid on
    let rig = std::fs::read_to_string(out.join("rig.toml")).expect("rig.toml");
    assert!(Config::parse(&rig)
        .expect("the kept config parses")
        .classifier
        .commissioning
        .is_some());
    let stuck = of("stuck")[1];
    let column = match stuck["channel"].as_str() {
        Some("x") => 2,
        Some("p1") => 3,
        _ => 4,
    };
    let kept = std::fs::read_to_string(kept_recording(&args, 1, RunKind::Stuck)).expect("a kept recording");
    let rows: Vec<Vec<&str>> = kept.lines().skip(1).map(|r| r.split(',').collect()).collect();
    assert!(rows.len() >= 74_000, "{}", rows.len());
    // frozen over the last 30 s (the onset is drawn up to 40 s), the other channels not
    let last = &rows[rows.len() - 1];
    assert!(
        rows[45_000..].iter().all(|r| r[column] == last[column]),
        "{stuck}"
    );
    let other = if column == 3 { 4 } else { 3 };
    assert!(rows[45_000..].iter().any(|r| r[other] != last[other]));
    let md = std::fs::read_to_string(out.join("sensor_faults.md")).expect("md");
    assert!(
        md.starts_with("# Sensor faults on the healthy recordings of "),
        "{md}"
    );
    assert!(
        md.contains("| stuck | 2 |") && !md.contains("| leak 0.25 L/min |"),
        "{md}"
    );
}

/// The thesis rig's runs have no oil course: `--temp-c` is refused there,
/// before anything is written.
#[test]
fn a_thermometer_is_refused_on_the_thesis_rig() {
    let dir = scratch::ScratchDir::new("sensor-faults-temp");
    let out = dir.join("out");
    let args = SensorFaultsArgs {
        temp_c: true,
        ..one_thesis_instance(out.clone())
    };
    let err = command(&args, false).expect_err("refused");
    assert!(err.contains("--temp-c") && err.contains("thesis"), "{err}");
    assert!(!out.exists(), "nothing written");
}
