//! Names as values: [`name!`] declares a `Copy` newtype over an interned string ([`ustr`]) that
//! holds only names its rule accepts, and is written and read as its text (`Display`,
//! `FromStr`, serde), so a CSV reads as it did when the column was a `String`. Names order as
//! their text. There are a few dozen names in a process (experiments, their methods,
//! learners), each stored once for its life; a copy is a pointer.
//!
//! The names: [`crate::experiment::ExperimentName`], [`crate::experiment::Method`],
//! [`crate::learner::LearnerName`].

/// The longest name [`name!`] takes: names become folder and file names (a cell's folder is
/// `<method>-<site>`), which file systems cut at 255 bytes.
pub const MAX_NAME: usize = 64;

/// Declares `$name`, a name of letters, digits and `_` (and `-` with `dash`), whose error
/// names `$field` and says `$what`.
#[macro_export]
#[doc(hidden)]
macro_rules! name {
    ($(#[$doc:meta])* $name:ident, field = $field:literal, what = $what:literal, dash = $dash:literal) => {
        $(#[$doc])*
        #[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
        pub struct $name(ustr::Ustr);

        impl $name {
            /// The name `name`, or an error saying which characters a name holds.
            pub fn new(name: &str) -> $crate::error::Result<$name> {
                let ok = |c: char| c.is_ascii_alphanumeric() || c == '_' || ($dash && c == '-');
                if name.len() > $crate::name::MAX_NAME {
                    let start: String = name.chars().take(16).collect();
                    return Err($crate::error::Error::invalid(
                        $field,
                        format!(
                            "`{start}…` ({} characters): {} is at most {} characters (it names \
                             folders and files)",
                            name.chars().count(),
                            $what,
                            $crate::name::MAX_NAME
                        ),
                    ));
                }
                if name.is_empty() || !name.chars().all(ok) {
                    let chars = if $dash { "letters, digits, `_` and `-`" } else { "letters, digits and `_`" };
                    return Err($crate::error::Error::invalid(
                        $field,
                        format!("`{name}`: {} holds {chars} only", $what),
                    ));
                }
                Ok($name(ustr::Ustr::from(name)))
            }

            /// The name's text.
            pub fn as_str(self) -> &'static str {
                self.0.as_str()
            }
        }

        impl std::fmt::Display for $name {
            fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str(self.as_str())
            }
        }

        impl std::fmt::Debug for $name {
            fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                write!(f, "{:?}", self.as_str())
            }
        }

        impl std::str::FromStr for $name {
            type Err = $crate::error::Error;
            fn from_str(s: &str) -> $crate::error::Result<$name> {
                $name::new(s)
            }
        }

        $crate::as_text!($name);
    };
}

/// Serde for a type with `Display` and `FromStr`: written and read as its text.
#[macro_export]
#[doc(hidden)]
macro_rules! as_text {
    ($t:ty) => {
        impl serde::Serialize for $t {
            fn serialize<S: serde::Serializer>(
                &self,
                s: S,
            ) -> std::result::Result<S::Ok, S::Error> {
                s.collect_str(self)
            }
        }

        impl<'de> serde::Deserialize<'de> for $t {
            fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<$t, D::Error> {
                let s = std::borrow::Cow::<str>::deserialize(d)?;
                s.parse().map_err(serde::de::Error::custom)
            }
        }
    };
}
