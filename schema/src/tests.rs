//! The schema's own checks: a declared struct, its table, its ranges.

use crate::{below, config_struct, int, num, FieldType, Kind, Range};

config_struct! {
    /// A friction curve.
    #[derive(Debug, Clone, PartialEq)]
    pub struct Inner {
        /// Slip friction, N.
        pub slip_n: f64 = 1100.0 => ["N", num!("a force", 0, 1e6)],
        /// A fraction.
        pub air: f64 = 0.0 => ["", below!("a fraction", 0, 0.5)],
    }
}

config_struct! {
    /// The outer section.
    /// Its second line.
    #[derive(Debug, Clone, PartialEq)]
    pub struct Outer {
        /// ADC resolution, bits.
        pub adc_bits: u32 = 12 => ["bits", int!(1, 24)],
        /// The states.
        pub states: u32 = 7 => ["", Range::OneOf(&[6, 7, 10, 11, 12])],
        /// An angle, rad.
        pub angle_rad: f64 = 0.0 => ["rad", num!("an angle", -10, 10, "(0: horizontal)")],
        /// The friction.
        pub friction: Inner = Inner::default(),
        /// Optional friction.
        pub retract: Option<Inner> = None,
        /// Listed tables.
        pub leaks: Vec<Inner> = Vec::new(),
        /// Offsets, Pa.
        pub offsets: [f64; 2] = [0.0; 2] => ["Pa", num!("offsets", -1e7, 1e7)],
        /// A rig fact, not a setting.
        #[allow(dead_code)]
        pub hidden: f64 = 1.0,
    }
}

config_struct! {
    /// Required fields: no Default.
    #[derive(Debug)]
    pub struct Required {
        /// Bore, m.
        pub bore_m: f64 => ["m", num!("a bore", 1e-3, 2)],
    }
}

#[test]
fn the_table_holds_each_fact_once() {
    let s = Outer::SCHEMA;
    assert_eq!(s.name, "Outer");
    assert_eq!(s.file, "schema/src/tests.rs");
    assert_eq!(crate::join_doc(s.doc), "The outer section. Its second line.");
    let keys: Vec<&str> = s.settings().map(|f| f.key).collect();
    assert_eq!(keys.len(), 8);
    let f = s.find(&["adc_bits"]).expect("adc_bits");
    assert_eq!((f.unit, f.expected()), ("bits", "1 to 24 bits".to_string()));
    assert_eq!(
        s.find(&["states"]).map(|f| f.expected()),
        Some("6, 7, 10, 11 or 12".into())
    );
    assert_eq!(
        s.find(&["angle_rad"]).map(|f| f.expected()),
        Some("an angle from -10 to 10 rad (0: horizontal)".into())
    );
    assert_eq!(
        s.find(&["friction", "air"]).map(|f| f.expected()),
        Some("a fraction in [0, 0.5)".into())
    );
    assert_eq!(s.find(&["leaks", "slip_n"]).map(|f| f.key), Some("slip_n"));
    assert!(s.find(&["retract"]).is_some_and(|f| f.optional));
    assert!(matches!(
        s.find(&["leaks"]).map(|f| f.kind),
        Some(Kind::Tables(_))
    ));
    assert!(matches!(
        s.find(&["offsets"]).map(|f| f.kind),
        Some(Kind::List(Kind::Number))
    ));
    const { assert!(!<Outer as FieldType>::OPTIONAL) };
    let _ = Required { bore_m: 0.1 };
    assert_eq!(Required::SCHEMA.fields[0].expected(), "a bore from 1e-3 to 2 m");
}

#[test]
fn check_ranges_names_the_dotted_key() {
    Outer::default()
        .check_ranges("")
        .expect("the defaults are in range");
    let o = Outer {
        retract: Some(Inner {
            slip_n: f64::NAN,
            ..Inner::default()
        }),
        ..Outer::default()
    };
    let e = o.check_ranges("").unwrap_err();
    assert_eq!(
        e.to_string(),
        "retract.slip_n = NaN: must be a force from 0 to 1e6 N"
    );
    let o = Outer {
        leaks: vec![
            Inner::default(),
            Inner {
                air: 0.5,
                ..Inner::default()
            },
        ],
        ..Outer::default()
    };
    let e = o.check_ranges("model").unwrap_err();
    assert_eq!(e.key, "model.leaks[1].air");
    let mut o = Outer {
        adc_bits: 64,
        ..Outer::default()
    };
    assert_eq!(
        o.check_ranges("").unwrap_err().to_string(),
        "adc_bits = 64: must be 1 to 24 bits"
    );
    o.adc_bits = 12;
    o.states = 8;
    assert_eq!(o.check_ranges("").unwrap_err().shown, "8");
    o.states = 12;
    o.offsets[1] = 2e7;
    assert_eq!(o.check_ranges("").unwrap_err().key, "offsets");
}
