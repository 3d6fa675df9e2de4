//! A table line of one item (a site, a learner) or of all of them pooled, as a type: the
//! pooled line is [`Scope::Pooled`], written as its table's word for it ([`Pools::POOLED`]:
//! `all` for sites, `pooled` for learners), never a sentinel string compared against names.

use serde::{Deserialize, Deserializer, Serialize, Serializer};
use std::fmt::{self, Display};
use std::str::FromStr;

/// What a table pools, and the word its pooled line is written as (one no item is named).
pub trait Pools: Display + FromStr {
    /// The pooled line's name in the table's files and `\res` keys.
    const POOLED: &'static str;
}

impl Pools for crate::experiment::Site {
    const POOLED: &'static str = "all";
}

impl Pools for crate::learner::td3::Algo {
    const POOLED: &'static str = "pooled";
}

/// One item's line, or the pooled line of them all.
///
/// ```
/// use pbcs::experiment::Site;
/// use pbcs::tables::scope::Scope;
/// assert_eq!(Scope::One(Site::Maze(5)).to_string(), "5");
/// assert_eq!(Scope::<Site>::Pooled.to_string(), "all");
/// assert_eq!("all".parse::<Scope<Site>>().unwrap(), Scope::Pooled);
/// assert_eq!("rooms".parse::<Scope<Site>>().unwrap().to_string(), "rooms");
/// assert!("pooled".parse::<Scope<Site>>().is_err()); // another table's word
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Scope<T> {
    /// The line of one item.
    One(T),
    /// The line of all of them pooled.
    Pooled,
}

impl<T> Scope<T> {
    /// The item of a line of one, none for the pooled line.
    pub fn one(&self) -> Option<&T> {
        match self {
            Scope::One(t) => Some(t),
            Scope::Pooled => None,
        }
    }
}

impl<T: Pools> Display for Scope<T> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Scope::One(t) => t.fmt(f),
            Scope::Pooled => f.write_str(T::POOLED),
        }
    }
}

impl<T: Pools> FromStr for Scope<T> {
    type Err = String;

    fn from_str(s: &str) -> Result<Scope<T>, String> {
        if s == T::POOLED {
            return Ok(Scope::Pooled);
        }
        s.parse().map(Scope::One).map_err(|_| {
            format!(
                "`{s}` is neither an item of the table nor its pooled line `{}`",
                T::POOLED
            )
        })
    }
}

impl<T: Pools> Serialize for Scope<T> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_str(self)
    }
}

impl<'de, T: Pools> Deserialize<'de> for Scope<T> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Scope<T>, D::Error> {
        let s = String::deserialize(d)?;
        s.parse().map_err(serde::de::Error::custom)
    }
}
