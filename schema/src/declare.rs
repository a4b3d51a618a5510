//! The declaring macros: [`config_struct!`](crate::config_struct) and the
//! ranges' shorthands ([`num!`](crate::num), [`below!`](crate::below),
//! [`int!`](crate::int)).

/// Declares a config struct and its schema together, each field once:
///
/// ```
/// schema::config_struct! {
///     /// A spring in front of the rod.
///     #[derive(Debug, Clone, PartialEq)]
///     pub struct Spring {
///         /// Spring stiffness, N/m.
///         pub stiffness_n_per_m: f64 = 2e4 => ["N/m", schema::num!("a stiffness", 0, 1e10)],
///         /// Whether it is there.
///         pub present: bool = true,
///     }
/// }
/// assert_eq!(Spring::default().stiffness_n_per_m, 2e4);
/// let f = &Spring::SCHEMA.fields[0];
/// assert_eq!((f.key, f.unit), ("stiffness_n_per_m", "N/m"));
/// assert_eq!(f.expected(), "a stiffness from 0 to 1e10 N/m");
/// assert_eq!(f.doc_text(), "Spring stiffness, N/m.");
/// let bad = Spring { stiffness_n_per_m: -1.0, present: true };
/// assert_eq!(bad.check_ranges("load").unwrap_err().to_string(),
///            "load.stiffness_n_per_m = -1.0: must be a stiffness from 0 to 1e10 N/m");
/// ```
///
/// A field is `doc comment, attributes, name: Type [= default] [=> [unit, range]]`
/// (or `=> [unit]`: a unit, no range):
/// the struct gets every attribute and doc comment as written; `Default` is
/// implemented from the defaults when every field has one (a section with
/// required fields has none); `SCHEMA` holds the table and `check_ranges`
/// checks each field against its range (sub-sections and lists of tables too).
#[macro_export]
macro_rules! config_struct {
    (
        $(#[$($sattr:tt)*])*
        $svis:vis struct $name:ident {
            $(
                $(#[$($fattr:tt)*])*
                $fvis:vis $field:ident : $ty:ty $(= $default:expr)? $(=> [$unit:literal $(, $range:expr)?])?
            ),* $(,)?
        }
    ) => {
        $(#[$($sattr)*])*
        $svis struct $name {
            $(
                $(#[$($fattr)*])*
                $fvis $field: $ty,
            )*
        }

        $crate::__impl_default! { $name; $($field $(= $default)?),* }

        impl $name {
            /// This section's declared fields: key, unit, range, kind and doc of each, in order.
            pub const SCHEMA: $crate::Section = $crate::Section {
                name: stringify!($name),
                file: file!(),
                doc: &[$($crate::__doc!($($sattr)*)),*],
                fields: &[$(
                    $crate::Field {
                        key: stringify!($field),
                        doc: &[$($crate::__doc!($($fattr)*)),*],
                        unit: $crate::__unit!($($unit)?),
                        range: $crate::__range!($($($range)?)?),
                        kind: <$ty as $crate::FieldType>::KIND,
                        optional: <$ty as $crate::FieldType>::OPTIONAL,
                        skipped: false $(|| $crate::__skips!($($fattr)*))*,
                    }
                ),*],
            };

            /// Checks every field against its declared range (sub-sections
            /// too); the error names the first field out of range by its
            /// dotted key under `prefix`, with the range and unit.
            pub fn check_ranges(&self, prefix: &str) -> Result<(), $crate::OutOfRange> {
                let mut fields = Self::SCHEMA.fields.iter();
                $(
                    if let Some(f) = fields.next() {
                        $crate::FieldType::check(&self.$field, &$crate::join(prefix, f.key), f)?;
                    }
                )*
                Ok(())
            }
        }

        impl $crate::FieldType for $name {
            const KIND: $crate::Kind = $crate::Kind::Table(&<$name>::SCHEMA);
            fn check(&self, key: &str, _field: &'static $crate::Field) -> Result<(), $crate::OutOfRange> {
                self.check_ranges(key)
            }
        }
    };
}

/// `Default` from the declared defaults, when every field has one.
#[doc(hidden)]
#[macro_export]
macro_rules! __impl_default {
    ($name:ident; $($field:ident = $default:expr),*) => {
        impl Default for $name {
            fn default() -> Self {
                $name { $($field: $default),* }
            }
        }
    };
    ($($other:tt)*) => {};
}

/// A doc attribute's text; `""` for any other attribute.
#[doc(hidden)]
#[macro_export]
macro_rules! __doc {
    (doc = $doc:literal) => {
        $doc
    };
    ($($other:tt)*) => {
        ""
    };
}

/// Whether an attribute keeps its field out of the file (`serde(skip)`).
#[doc(hidden)]
#[macro_export]
macro_rules! __skips {
    (serde(skip)) => {
        true
    };
    ($($other:tt)*) => {
        false
    };
}

/// The declared unit, or none.
#[doc(hidden)]
#[macro_export]
macro_rules! __unit {
    () => {
        ""
    };
    ($unit:literal) => {
        $unit
    };
}

/// The declared range, or [`Range::Any`](crate::Range::Any).
#[doc(hidden)]
#[macro_export]
macro_rules! __range {
    () => {
        $crate::Range::Any
    };
    ($range:expr) => {
        $range
    };
}

/// [`Range::Number`](crate::Range::Number): `num!("a mass", 1e-3, 1e5)`, or
/// with a remark after the unit, `num!("a position", -10, 10, "(0: the middle)")`.
/// The bounds are shown as written.
#[macro_export]
macro_rules! num {
    ($what:literal, $lo:literal, $hi:literal $(, $note:literal)?) => {
        $crate::Range::Number {
            what: $what,
            lo: $lo as f64,
            hi: $hi as f64,
            lo_text: stringify!($lo),
            hi_text: stringify!($hi),
            note: $crate::__unit!($($note)?),
        }
    };
}

/// [`Range::Below`](crate::Range::Below): `below!("a fraction", 0, 0.5)`, from 0 up to 0.5 excluded.
#[macro_export]
macro_rules! below {
    ($what:literal, $lo:literal, $hi:literal) => {
        $crate::Range::Below {
            what: $what,
            lo: $lo as f64,
            hi: $hi as f64,
            lo_text: stringify!($lo),
            hi_text: stringify!($hi),
        }
    };
}

/// [`Range::Integer`](crate::Range::Integer): `int!(1, 24)`, or with a
/// remark after the unit, `int!(0, 900, "(less than the 1 ms period)")`.
#[macro_export]
macro_rules! int {
    ($lo:literal, $hi:literal $(, $note:literal)?) => {
        $crate::Range::Integer {
            lo: $lo,
            hi: $hi,
            note: $crate::__unit!($($note)?),
        }
    };
}
