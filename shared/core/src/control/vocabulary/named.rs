//! Closed sets of values that files and the command line spell by name.
//!
//! A type lists its values once ([`Named::ALL`]) and names each ([`Named::name`]); finding
//! a value by its name, and reading or writing it through serde as that name, is written
//! here once for all of them.

use serde::{Deserialize, Deserializer, Serializer, de};

/// A closed set of values, each with the name files and the command line use.
///
/// ```
/// use shared::control::vocabulary::{Named, TurnMode};
/// assert_eq!(TurnMode::from_name("parallel"), Some(TurnMode::Parallel));
/// assert_eq!(TurnMode::from_name("Parallel"), None);
/// for mode in <TurnMode as Named>::ALL {
///     assert_eq!(TurnMode::from_name(Named::name(mode)), Some(*mode));
/// }
/// ```
pub trait Named: Copy + 'static {
    /// Every value, each once.
    const ALL: &'static [Self];
    /// What a value is, as an error message says it (`"move status"`).
    const WHAT: &'static str;

    /// The value's name (unique among [`Named::ALL`]).
    fn name(&self) -> &'static str;

    /// The value called `name`, if any (names are case-sensitive).
    fn from_name(name: &str) -> Option<Self> {
        Self::ALL.iter().copied().find(|v| v.name() == name)
    }
}

/// Write a [`Named`] value as its name (for `#[serde(with = "shared::control::vocabulary::named")]`).
pub fn serialize<T: Named, S: Serializer>(value: &T, serializer: S) -> Result<S::Ok, S::Error> {
    serializer.serialize_str(value.name())
}

/// Read a [`Named`] value from its name; any other string is an error that quotes it
/// (`unknown move status `lost``).
pub fn deserialize<'de, T: Named, D: Deserializer<'de>>(deserializer: D) -> Result<T, D::Error> {
    let name = String::deserialize(deserializer)?;
    T::from_name(&name).ok_or_else(|| de::Error::custom(format!("unknown {} `{name}`", T::WHAT)))
}
