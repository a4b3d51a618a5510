//! Tests of the configuration file: defaults, ranges, messages.

use super::*;

#[test]
fn default_round_trips_and_errors_name_the_problem() {
    let text = Config::default_toml();
    assert_eq!(Config::parse(&text).unwrap(), Config::default());
    let e = Config::parse("[model]\nsupply_pressure_psi = 2000.0\n").unwrap_err();
    assert!(e.contains("supply_pressure_psi"), "{e}");
    let e = Config::parse("[model]\nsupply_pressure_pa = \"13.8 MPa\"\n").unwrap_err();
    assert!(e.contains("supply_pressure_pa"), "{e}");
    let e = Config::parse("[model]\nmass_kg = -3.0\n").unwrap_err();
    assert!(e.contains("mass_kg"), "{e}");
    // Values that would abort, hang or give NaN are refused by name.
    for (text, field) in [
        (
            "[estimator]\nmae_window_samples = 1000000000000\n",
            "mae_window_samples",
        ),
        ("[model]\nsupply_pressure_pa = 1e308\n", "supply_pressure_pa"),
        ("[estimator]\nsample_period_s = 1e-300\n", "sample_period_s"),
        ("[sensors]\nadc_bits = 0\n", "adc_bits"),
        ("[sensors]\nadc_bits = 64\n", "adc_bits"),
        ("[sim]\nsubsteps_per_sample = 4000000000\n", "substeps_per_sample"),
        ("[sim]\nsample_period_s = 1e-300\n", "sample_period_s"),
    ] {
        let e = Config::parse(text).unwrap_err();
        assert!(e.contains(field), "{text}: {e}");
    }
    let e = Config::parse("[modle]\n").unwrap_err();
    assert!(e.contains("modle"), "{e}");
    // A partial [leak_filter] keeps the leak filter's own defaults for the rest.
    let c = Config::parse("[leak_filter]\nsubsteps = 2\n").unwrap();
    assert_eq!(c.leak_filter.states, 12);
    assert_eq!(c.leak_filter.substeps, 2);
    assert_eq!(c.leak_filter.r_p_pa2, Tuning::sensor_derived().r_p_pa2);
    // [udp]: raw counts to SI per channel; an unknown channel or field is named
    let c = Config::parse("[udp.p1]\ngain = 250.0\noffset = -1.0e6\n").unwrap();
    assert_eq!((c.udp.p1.gain, c.udp.p1.offset), (250.0, -1.0e6));
    assert_eq!(c.udp.p2, udp::ChannelScale::default());
    let e = Config::parse("[udp.p3]\ngain = 2.0\n").unwrap_err();
    assert!(e.contains("p3"), "{e}");
    let e = Config::parse("[udp.x]\nscale = 2.0\n").unwrap_err();
    assert!(e.contains("scale"), "{e}");
    // [udp] sender: the one address datagrams are taken from, named when bad
    assert_eq!(Config::default().udp.sender, None);
    let c = Config::parse("[udp]\nsender = \"192.168.10.20:5005\"\n").unwrap();
    assert_eq!(c.udp.sender, Some("192.168.10.20:5005".parse().unwrap()));
    assert_eq!(Config::parse(&toml::to_string(&c).unwrap()).unwrap(), c);
    for (text, why) in [
        ("plc.local:5005", "host names are not looked up"),
        ("192.168.10.20", "IP:PORT"),
        ("192.168.10.20:0", "port 0"),
        ("[::]:5005", "no sender's address"),
    ] {
        let e = Config::parse(&format!("[udp]\nsender = \"{text}\"\n")).unwrap_err();
        assert!(e.contains("[udp] sender") && e.contains(why), "{text}: {e}");
    }
    let c = Config::parse("[rig]\nbulk_modulus_pa = 5e8\n").unwrap();
    assert_eq!(c.rig_params().bulk_modulus_pa, 5e8);
    assert_eq!(c.model.bulk_modulus_pa, 6.89e8);
}

/// Every numeric leaf of `t` with its path (section names, then the key).
fn numeric_leaves(t: &toml::Table, path: &mut Vec<String>, out: &mut Vec<(Vec<String>, toml::Value)>) {
    for (k, v) in t {
        path.push(k.clone());
        match v {
            toml::Value::Table(sub) => numeric_leaves(sub, path, out),
            toml::Value::Integer(_) | toml::Value::Float(_) => out.push((path.clone(), v.clone())),
            _ => {}
        }
        path.pop();
    }
}

fn set(t: &mut toml::Table, path: &[String], v: toml::Value) {
    if path.len() == 1 {
        t.insert(path[0].clone(), v);
    } else if let Some(toml::Value::Table(sub)) = t.get_mut(&path[0]) {
        set(sub, &path[1..], v);
    }
}

/// Runs 0.3 s of the loaded scenario on the configured rig through both filters and
/// the classifier; every measurement and every filter state must stay finite.
fn runs_finite(cfg: &Config, what: &str) -> Result<(), String> {
    let scenario = model::Scenario::by_name("loaded-sine", 1, 0.3).unwrap();
    let mut sim = model::Simulator::new(
        cfg.rig_params(),
        cfg.sensors,
        cfg.sim,
        scenario,
        model::FaultSchedule::default(),
        1,
    )
    .unwrap();
    let samples = sim.run(0.3);
    let mut stage =
        filter::EstimatorStage::new(cfg.model.clone(), cfg.leak_filter.clone(), cfg.estimator.clone())
            .unwrap();
    let mut cls = detect::Classifier::new(cfg.classifier.clone()).unwrap();
    for s in &samples {
        if ![s.t_s, s.u_v, s.x_m, s.p1_pa, s.p2_pa]
            .iter()
            .all(|v| v.is_finite())
        {
            return Err(format!("{what}: sample {s:?}"));
        }
        let e = stage.on_sample(s);
        for f in [&e.leak, &e.thesis] {
            let n = f.n_states as usize;
            if !f.state[..n].iter().all(|v| v.is_finite()) {
                return Err(format!("{what}: t = {} s, state {:?}", f.t_s, &f.state[..n]));
            }
        }
        cls.on_stage(&e, |_| {});
    }
    Ok(())
}

#[test]
fn every_numeric_field_swept_with_absurd_values_is_refused_by_name_or_stays_finite() {
    let base: toml::Table = toml::from_str(&Config::default_toml()).unwrap();
    let mut leaves = Vec::new();
    numeric_leaves(&base, &mut Vec::new(), &mut leaves);
    assert_eq!(leaves.len(), 175, "numeric fields");
    let floats = [0.0, -1.0, 1e308, -1e308, 1e-300, -1e-300, 1e30];
    let ints = [0i64, -1, 4_000_000_000, 1_000_000_000_000, i64::MAX];
    let (mut refused, mut accepted) = (0, 0);
    let mut not_finite = Vec::new();
    for (path, v) in &leaves {
        let values: Vec<toml::Value> = match v {
            toml::Value::Float(_) => floats.iter().map(|f| toml::Value::Float(*f)).collect(),
            _ => ints.iter().map(|i| toml::Value::Integer(*i)).collect(),
        };
        for value in values {
            let mut t = base.clone();
            set(&mut t, path, value.clone());
            let text = toml::to_string(&t).unwrap();
            let what = format!("[{}] = {value}", path.join("."));
            let key = path.last().unwrap();
            let parsed = std::panic::catch_unwind(|| Config::parse(&text));
            match parsed {
                Err(_) => panic!("{what}: Config::parse panicked"),
                Ok(Err(e)) => {
                    refused += 1;
                    assert!(
                        e.contains(key.as_str()),
                        "{what}: the error does not name the field: {e}"
                    );
                }
                Ok(Ok(cfg)) => {
                    accepted += 1;
                    if let Err(e) = runs_finite(&cfg, &what) {
                        not_finite.push(e);
                    }
                }
            }
        }
    }
    assert!(not_finite.is_empty(), "{not_finite:#?}");
    // most absurd values are refused; the rest (zeros of noises, offsets, ...) run finite
    assert!(refused > 3 * accepted, "{refused} refused, {accepted} accepted");
}

#[test]
fn a_value_of_the_wrong_type_is_named_with_the_fields_range_and_unit() {
    for (text, expect) in [
        (
            "[sensors]\nadc_bits = -1\n",
            "line 2, column 12 (`adc_bits = -1`): invalid value: integer `-1`, expected u32 \
             (`sensors.adc_bits` must be an integer: 1 to 24 bits)",
        ),
        (
            "[sensors]\nadc_bits = 12.5\n",
            "line 2, column 12 (`adc_bits = 12.5`): invalid type: floating point `12.5`, expected u32 \
             (`sensors.adc_bits` must be an integer: 1 to 24 bits)",
        ),
        (
            "[sim]\nsubsteps_per_sample = 99999999999\n",
            "line 2, column 23 (`substeps_per_sample = 99999999999`): invalid value: integer \
             `99999999999`, expected u32 (`sim.substeps_per_sample` must be an integer: 1 to 10000 \
             sub-steps per sample)",
        ),
        (
            "[rig]\nmass_kg = true\n",
            "line 2, column 11 (`mass_kg = true`): invalid type: boolean `true`, expected f64 \
             (`rig.mass_kg` must be a number: a mass from 1e-3 to 1e5 kg)",
        ),
        (
            "[leak_filter]\nq_p_pa2 = \"1e6 Pa²\"\n",
            "line 2, column 11 (`q_p_pa2 = \"1e6 Pa²\"`): invalid type: string \"1e6 Pa²\", \
             expected f64 (`leak_filter.q_p_pa2` must be a number from 0.0 to 1e18 Pa²)",
        ),
        (
            "[estimator]\nmax_bridged_gap_samples = -3\n",
            "line 2, column 27 (`max_bridged_gap_samples = -3`): invalid value: integer `-3`, \
             expected u32 (`estimator.max_bridged_gap_samples` must be an integer: 0 to 3600000 \
             samples (an hour at 1 kHz))",
        ),
        (
            "[classifier]\nstuck_samples = 1e3\n",
            "line 2, column 17 (`stuck_samples = 1e3`): invalid type: floating point `1000.0`, \
             expected u32 (`classifier.stuck_samples` must be an integer: 1 to 1000000000 samples)",
        ),
        (
            "[udp.p1]\noffset = \"0\"\n",
            "line 2, column 10 (`offset = \"0\"`): invalid type: string \"0\", expected f64 \
             (`udp.p1.offset` must be a number from -1e9 to 1e9 Pa)",
        ),
        // not a numeric field: no range to give
        (
            "[model]\nfriction = 3\n",
            "line 2, column 12 (`friction = 3`): invalid type: integer `3`, expected struct Friction",
        ),
    ] {
        assert_eq!(Config::parse(text).unwrap_err(), expect, "{text}");
    }
}

#[test]
fn every_numeric_field_of_the_wrong_type_is_named_with_its_range() {
    let base: toml::Table = toml::from_str(&Config::default_toml()).unwrap();
    let mut leaves = Vec::new();
    numeric_leaves(&base, &mut Vec::new(), &mut leaves);
    assert_eq!(leaves.len(), 175, "numeric fields");
    for (path, v) in &leaves {
        let wrong = match v {
            toml::Value::Integer(_) => [toml::Value::Float(0.5), toml::Value::Integer(-1)],
            _ => [toml::Value::String("1 unit".into()), toml::Value::Boolean(true)],
        };
        for value in wrong {
            let mut t = base.clone();
            set(&mut t, path, value.clone());
            let e = Config::parse(&toml::to_string(&t).unwrap()).unwrap_err();
            let kind = if v.is_integer() {
                "an integer: "
            } else {
                "a number"
            };
            let hint = format!("(`{}` must be {kind}", path.join("."));
            assert!(e.contains(&hint), "{} = {value}: {e}", path.join("."));
        }
    }
}

#[test]
fn control_characters_from_the_file_are_escaped_in_messages() {
    for (text, expect) in [
        // an unknown key with ESC (written as a TOML escape)
        (
            "[model]\n\"\\u001b[31mx\" = 1\n",
            "line 2, column 1 (`\"\\u001b[31mx\" = 1`): unknown field `\\u{1b}[31mx`, expected one of",
        ),
        // raw ESC and NUL in the file
        (
            "[model]\nmass_kg = \"\u{1b}[31m\0\"\n",
            "line 2, column 12 (`mass_kg = \"\\u{1b}[31m\\0\"`): invalid basic string",
        ),
        (
            "[model]\nmass_kg = 1\0\u{1b}[2J\n",
            "line 2, column 14 (`mass_kg = 1\\0\\u{1b}[2J`): unexpected key or value",
        ),
    ] {
        let e = Config::parse(text).unwrap_err();
        assert!(e.starts_with(expect), "{text:?}: {e}");
        assert!(!e.chars().any(|c| c.is_control()), "{e:?}");
    }
}

#[test]
fn ranges_name_the_unit() {
    for (text, expect) in [
        (
            "[model]\nmass_kg = 1e308\n",
            "[model] parameter `mass_kg` = 1e308 is invalid: expected a mass from 1e-3 to 1e5 kg",
        ),
        (
            "[sensors]\nadc_bits = 64\n",
            "parameter `sensors.adc_bits` = 64 is invalid: expected 1 to 24 bits",
        ),
        (
            "[sensors]\npressure_noise_pa = 1e308\n",
            "a noise from 0 to 1e8 Pa",
        ),
        (
            "[estimator]\nq_p_pa2 = 1e308\n",
            "q_p_pa2 = 1e308: must be a number from 0.0 to 1e18 Pa²",
        ),
        (
            "[leak_filter]\nr_x_m2 = 1e-300\n",
            "[leak_filter] r_x_m2 = 1e-300: must be a number from 1e-30 to 100.0 m²",
        ),
        (
            "[classifier]\nwarmup_s = 1e308\n",
            "[classifier] warmup_s = 1e308: must be a number from 0.0 to 1000000.0 s",
        ),
        (
            "[estimator]\nmax_bridged_gap_samples = 4000000000\n",
            "must be 0 to 3600000 samples",
        ),
        (
            "[udp.p1]\ngain = 0.0\n",
            "[udp] p1.gain = 0.0: must be a number of magnitude from 1e-12 to 1e12 Pa per raw unit",
        ),
        (
            "[udp.f_load]\noffset = 1e30\n",
            "[udp] f_load.offset = 1e30: must be a number from -1e9 to 1e9 N",
        ),
    ] {
        let e = Config::parse(text).unwrap_err();
        assert!(e.contains(expect), "{text}: {e}");
    }
}

#[test]
fn run_cpus_name_known_stages_and_existing_cpus() {
    let ok = Config::parse("[run]\ncpus = { acquisition = 0, \"estimator+classifier\" = 0 }\n").unwrap();
    assert_eq!(ok.run.cpu_of("acquisition"), Some(0));
    assert_eq!(ok.run.cpu_of("recorder"), None);
    assert_eq!(ok.run.low_latency_spin_us, 60);
    let err = Config::parse("[run]\ncpus = { estimatr = 0 }\n").unwrap_err();
    assert!(
        err.contains("[run] cpus") && err.contains("\"estimatr\""),
        "{err}"
    );
    let err = Config::parse("[run]\ncpus = { estimator = 4096 }\n").unwrap_err();
    assert!(
        err.contains("cpus.estimator = 4096") && err.contains("CPUs 0 to"),
        "{err}"
    );
    let err = Config::parse("[run]\nlow_latency_spin_us = 1000\n").unwrap_err();
    assert!(err.contains("low_latency_spin_us = 1000"), "{err}");
}

/// The detector's rig facts are written once: the supply pressure in `[model]`,
/// the transducers' full scale in `[sensors]`. A 21 MPa rig written that way
/// gives its detector 21 MPa (the old `[classifier]` copy, left at 13.8 MPa,
/// called every pressure above 13.1 MPa an excursion to supply). An older
/// file's copy loads when it agrees and is refused by name when it does not.
#[test]
fn the_detectors_rig_facts_come_from_model_and_sensors() {
    let c = Config::parse(
        "[model]\nsupply_pressure_pa = 21e6\n[sensors]\npressure_full_scale_pa = 25e6\n\
         encoder_resolution_m = 2e-6\nposition_noise_m = 3e-6\n",
    )
    .unwrap();
    assert_eq!(c.classifier.supply_pressure_pa, 21e6);
    assert_eq!(c.classifier.pressure_full_scale_pa, 25e6);
    assert!((c.classifier.position_noise_counts - 1.5).abs() < 1e-12);
    let d = Config::default();
    assert_eq!(d.classifier.supply_pressure_pa, d.model.supply_pressure_pa);
    assert_eq!(
        d.classifier.pressure_full_scale_pa,
        d.sensors.pressure_full_scale_pa
    );
    // not written by --print-default (nor by `commission`, which writes the same way)
    let text = Config::default_toml();
    let t: toml::Table = toml::from_str(&text).unwrap();
    assert!(!t["classifier"]
        .as_table()
        .unwrap()
        .contains_key("supply_pressure_pa"));
    assert!(!t["classifier"]
        .as_table()
        .unwrap()
        .contains_key("pressure_full_scale_pa"));
    // an older file's agreeing copy
    let c = Config::parse("[model]\nsupply_pressure_pa = 21e6\n[classifier]\nsupply_pressure_pa = 21e6\n")
        .unwrap();
    assert_eq!(c.classifier.supply_pressure_pa, 21e6);
    // a disagreeing one
    let e = Config::parse("[model]\nsupply_pressure_pa = 21e6\n[classifier]\nsupply_pressure_pa = 13.8e6\n")
        .unwrap_err();
    assert!(
        e.contains("[classifier] supply_pressure_pa") && e.contains("[model] supply_pressure_pa"),
        "{e}"
    );
    let e = Config::parse("[classifier]\npressure_full_scale_pa = \"25 MPa\"\n").unwrap_err();
    assert!(e.contains("[sensors] pressure_full_scale_pa"), "{e}");
}

/// Every name a choice field declares parses, and the parser's own list of
/// names (in its error for an unknown one) is the declared list.
fn choices_are_the_parsers<T: serde::de::DeserializeOwned + schema::FieldType>() {
    #[derive(Deserialize)]
    struct One<T> {
        #[allow(dead_code)]
        v: T,
    }
    let schema::Kind::Choice(names) = T::KIND else {
        panic!("not a choice: {:?}", T::KIND);
    };
    for name in names {
        toml::from_str::<One<T>>(&format!("v = {name:?}")).unwrap_or_else(|e| panic!("{name}: {e}"));
    }
    let Err(e) = toml::from_str::<One<T>>("v = \"?\"") else {
        panic!("`?` was taken");
    };
    let listed = e
        .message()
        .split_once("expected ")
        .map(|(_, l)| l.to_string())
        .unwrap_or_default();
    assert_eq!(listed.matches('`').count(), 2 * names.len(), "{listed}");
    for name in names {
        assert!(listed.contains(&format!("`{name}`")), "{name} not in {listed}");
    }
}

#[test]
fn the_declared_choices_are_the_names_the_parser_takes() {
    choices_are_the_parsers::<filter::tuning::Init>();
    choices_are_the_parsers::<model::datasheet::CylinderKind>();
    choices_are_the_parsers::<model::datasheet::TransducerLocation>();
    choices_are_the_parsers::<model::leakage::LeakPath>();
    choices_are_the_parsers::<model::leakage::LeakLaw>();
}

#[test]
fn the_schema_declares_every_setting_of_the_default_config_and_nothing_else() {
    let defaults = toml::Table::try_from(Config::default()).expect("the defaults");
    fn walk(t: &toml::Table, section: &'static schema::Section, at: &str) {
        for (k, v) in t {
            let field = section
                .settings()
                .find(|f| f.key == k)
                .unwrap_or_else(|| panic!("{at}.{k} is not declared in {}", section.name));
            if let (toml::Value::Table(sub), schema::Kind::Table(s)) = (v, field.kind) {
                walk(sub, s, &format!("{at}.{k}"));
            }
        }
        for f in section
            .settings()
            .filter(|f| !f.optional && !matches!(f.kind, schema::Kind::Tables(_)))
        {
            assert!(
                t.contains_key(f.key),
                "{at}.{} is declared but not in the default config",
                f.key
            );
        }
    }
    walk(&defaults, &Config::SCHEMA, "");
    // the rig facts of [classifier] are declared (and checked) but are no settings
    let skipped: Vec<&str> = ClassifierConfig::SCHEMA
        .fields
        .iter()
        .filter(|f| f.skipped)
        .map(|f| f.key)
        .collect();
    assert_eq!(
        skipped,
        [
            "supply_pressure_pa",
            "pressure_full_scale_pa",
            "pressure_zero_offset_max_pa",
            "pressure_span_error_max",
            "position_noise_counts"
        ]
    );
}

#[test]
fn the_default_config_needs_no_derived_rig_facts() {
    let mut derived = Config::default();
    derived.derive_rig_facts();
    assert_eq!(derived, Config::default());
    Config::default().validate().expect("the defaults are valid");
}

#[test]
fn a_range_hint_comes_from_the_schema_for_every_section() {
    for (text, hint) in [
        (
            "[datasheet.cylinder]\nbore_m = \"50 mm\"\n",
            "(`datasheet.cylinder.bore_m` must be a number: a bore from 1e-3 to 2 m)",
        ),
        (
            "[[model.leaks]]\npath = \"ext1\"\nlaw = \"sqrt\"\ncoefficient = \"x\"\n",
            "(`model.leaks.coefficient` must be a number: a coefficient from 0 to 1e-4 \
             (m³/s per √Pa, or per Pa for the linear law))",
        ),
        (
            "[live_view]\nport = 70000\n",
            "(`live_view.port` must be an integer: 1 to 65535 (a TCP port))",
        ),
    ] {
        let e = Config::parse(text).unwrap_err();
        assert!(e.ends_with(hint), "{text}: {e}");
    }
}

/// The plant_dev rigs' configs in `examples/plant_dev/` (their datasheet.json
/// entered into `leakwatch init`'s template) load, and give the rig facts that
/// datasheet.json's own `derived_for_leakwatch` block states: areas, hose
/// volumes, the valve's area gradients, the spool's frequency and the
/// measurement noise.
#[test]
fn the_plant_dev_examples_give_the_rig_facts_their_datasheets_state() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/plant_dev");
    let close = |what: &str, got: f64, want: f64| {
        assert!(
            ((got - want) / want).abs() < 1e-9,
            "{what}: {got:e} against {want:e}"
        );
    };
    let (annulus, gradient, gradient_b) = (1.198_713_946_89e-3, 3.303_214_902_03e-2, 1.981_928_941_22e-2);
    for (file, areas, hose_volume, gradients, mass) in [
        (
            "double.toml",
            (annulus, annulus),
            6.967_227_837_59e-5,
            (gradient, gradient),
            27.5,
        ),
        (
            "differential.toml",
            (2.002_961_666_2e-3, annulus),
            1.140_091_827_97e-4,
            (gradient, gradient_b),
            185.0,
        ),
    ] {
        let c = Config::load(&dir.join(file)).unwrap_or_else(|e| panic!("{e}"));
        let m = &c.model;
        let (a1, a2) = m.areas_m2();
        close(&format!("{file}: cap-side area"), a1, areas.0);
        close(&format!("{file}: rod-side area"), a2, areas.1);
        close(&format!("{file}: dead volume A"), m.dead_volume_1_m3, hose_volume);
        close(&format!("{file}: dead volume B"), m.dead_volume_2_m3, hose_volume);
        let (g1, g2) = m.area_gradients_m2_per_m();
        close(&format!("{file}: area gradient A"), g1, gradients.0);
        close(&format!("{file}: area gradient B"), g2, gradients.1);
        close(
            &format!("{file}: spool ω_n"),
            m.spool_natural_freq_rad_s,
            816.814_089_933,
        );
        close(&format!("{file}: spool gain"), m.spool_gain_m_per_v, 3e-5);
        close(&format!("{file}: mass"), m.mass_kg, mass);
        close(
            &format!("{file}: R of p"),
            c.leak_filter.r_p_pa2,
            64_012_126.966_1,
        );
        close(
            &format!("{file}: R of x"),
            c.leak_filter.r_x_m2,
            9.333_333_333_33e-12,
        );
    }
}
