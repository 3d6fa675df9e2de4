//! The names results are joined by, as values: an [`ExperimentName`] (an experiment file's
//! stem), a [`Method`] (a name an experiment declares) and a [`CellKey`] (a method at a
//! [`Site`]). All are `Copy` and compare as values, so a table joins rows on keys, never on
//! strings. The names are declared in [`crate::name`]; a cell key is written and read here,
//! one way only (`pbcs-maze05` is refused: it is written `pbcs-maze5`).
//!
//! A cell key is written `<method>-<site id>` (`pbcs-maze5`, `td3_her-pointmaze_umaze_goals`):
//! a cell's folder name, its name on the command line and its `cell` column. A method name
//! holds letters, digits and `_` only, so the first `-` ends it.
//!
//! Names are interned ([`crate::name`]). They order as their text does,
//! and a cell key orders as its written form, so sorting by key sorts as the tables always
//! have.
//!
//! ```
//! use pbcs::envs::EnvName;
//! use pbcs::experiment::{CellKey, Method, Site};
//!
//! let key: CellKey = "pbcs_pm-pointmaze_medium".parse().unwrap();
//! assert_eq!(key.method, Method::new("pbcs_pm").unwrap());
//! assert_eq!(key.site, Site::Env(EnvName::PointmazeMedium));
//! assert_eq!(CellKey::new(Method::new("td3").unwrap(), Site::Maze(5)).to_string(), "td3-maze5");
//! assert!("pbcs-maze".parse::<CellKey>().is_err()); // a maze is written with its size
//! assert!("pbcs maze5".parse::<CellKey>().is_err()); // no method-site separator
//! assert!(Method::new("pbcs-pm").is_err()); // `-` separates a method from its site
//! assert!("pbcs-maze05".parse::<CellKey>().is_err()); // one way to write a key
//! ```

use super::Site;
use crate::envs::EnvName;
use crate::error::{Error, Result};
use std::cmp::Ordering;
use std::fmt;
use std::str::FromStr;

crate::name!(
    /// A method's name as its experiment declares it (`pbcs`, `td3_her`, `pbcs_pm_velocity`):
    /// letters, digits and `_` (a method name is a folder name and the first part of a cell
    /// key).
    Method,
    field = "method.name",
    what = "a method's name",
    dash = false
);

crate::name!(
    /// An experiment's name: its file's stem (`table`, `pointmaze_her`), the folder of its raw
    /// rows and the first part of its tables' names and LaTeX keys; letters, digits, `_` and
    /// `-`.
    ExperimentName,
    field = "experiment",
    what = "an experiment's name (its file's stem)",
    dash = true
);

/// Its folder under `raw/`.
impl AsRef<std::path::Path> for ExperimentName {
    fn as_ref(&self) -> &std::path::Path {
        std::path::Path::new(self.as_str())
    }
}

/// A cell of an experiment's grid: a method at a site. Two cells of one experiment never
/// share a key ([`super::Experiment`] checks it).
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
pub struct CellKey {
    /// The method.
    pub method: Method,
    /// Where it runs.
    pub site: Site,
}

impl CellKey {
    /// `method` at `site`.
    pub fn new(method: Method, site: Site) -> CellKey {
        CellKey { method, site }
    }
}

impl fmt::Display for CellKey {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}-{}", self.method, self.site.id())
    }
}

impl fmt::Debug for CellKey {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{:?}", self.to_string())
    }
}

/// As the written key (`pbcs-maze10` before `pbcs-maze5`), the order every table was sorted
/// in when keys were strings: by method, then by site id (the same order, since `-` sorts
/// below every character of a method name).
impl Ord for CellKey {
    fn cmp(&self, other: &CellKey) -> Ordering {
        (self.method.cmp(&other.method)).then_with(|| self.site.id().cmp(&other.site.id()))
    }
}

impl PartialOrd for CellKey {
    fn partial_cmp(&self, other: &CellKey) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl FromStr for CellKey {
    type Err = Error;

    /// `<method>-maze<N>` or `<method>-<environment>`.
    fn from_str(s: &str) -> Result<CellKey> {
        let bad = |why: String| Error::invalid("cell", format!("`{s}` is not a cell key: {why}"));
        let (method, site) = s
            .split_once('-')
            .ok_or_else(|| bad("it has no `-` between its method and its site".into()))?;
        let method = Method::new(method).map_err(|e| bad(e.to_string()))?;
        let site = match site.strip_prefix("maze").map(str::parse::<usize>) {
            Some(Ok(n)) => Site::Maze(n),
            _ => match site.parse::<EnvName>() {
                Ok(EnvName::Maze) | Err(_) => {
                    return Err(bad(format!(
                        "its site `{site}` is neither `maze<N>` nor an environment ({})",
                        EnvName::others()
                    )))
                }
                Ok(e) => Site::Env(e),
            },
        };
        let key = CellKey { method, site };
        // One way to write a key: `maze05` or `maze+5` would read as `maze5`.
        if key.to_string() != s {
            return Err(bad(format!("it is written `{key}`")));
        }
        Ok(CellKey { method, site })
    }
}

crate::as_text!(CellKey);

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn site() -> impl Strategy<Value = Site> {
        prop_oneof![
            (1usize..200).prop_map(Site::Maze),
            proptest::sample::select(
                EnvName::all()
                    .iter()
                    .copied()
                    .filter(|e| *e != EnvName::Maze)
                    .collect::<Vec<_>>()
            )
            .prop_map(Site::Env),
        ]
    }

    proptest! {
        /// A key written and read back is the same key, for any method name and site.
        #[test]
        fn a_key_reads_back_as_written(m in "[a-z0-9_]{1,12}", s in site()) {
            let key = CellKey::new(Method::new(&m).unwrap(), s);
            prop_assert_eq!(key.to_string().parse::<CellKey>().unwrap(), key);
        }

        /// Keys order as their written form.
        #[test]
        fn keys_order_as_text(a in "[a-z_]{1,6}", b in "[a-z_]{1,6}", s in site(), t in site()) {
            let (x, y) = (CellKey::new(Method::new(&a).unwrap(), s), CellKey::new(Method::new(&b).unwrap(), t));
            prop_assert_eq!(x.cmp(&y), x.to_string().cmp(&y.to_string()));
        }
    }
}
