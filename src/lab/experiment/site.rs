//! Where a cell runs: the paper's maze of one size, or another environment of the registry by
//! name ([`crate::envs::EnvName`]). A grid's columns are methods and its rows are sites.
//!
//! A site is written in three ways, each in one place here: as a cell id's suffix
//! ([`Site::id`]: `maze5`, `rooms`), as a table's value and a TOML key ([`std::fmt::Display`],
//! [`std::str::FromStr`]: `5`, `rooms`), and as a figure's label ([`Site::title`]: `maze 5×5`,
//! `rooms`). In a CSV it is the `maze` column, a size or a name, so every row and table
//! written before other environments existed reads as it did.
//!
//! ```
//! use pbcs::envs::EnvName;
//! use pbcs::experiment::Site;
//!
//! let rooms: Site = "rooms".parse().unwrap();
//! assert_eq!(rooms, Site::Env(EnvName::Rooms));
//! assert_eq!(("5".parse::<Site>().unwrap().id(), rooms.id()), ("maze5".into(), "rooms".into()));
//! assert_eq!(Site::Maze(5).title(), "maze 5×5");
//! assert!("maze".parse::<Site>().is_err()); // the maze is written by its size
//! ```

use crate::config::Located;
use crate::envs::pointmaze::PointMazeConfig;
use crate::envs::EnvName;
use crate::error::{Error, Result};
use crate::phase2::Variant;
use serde::de::{self, Visitor};
use serde::{Deserialize, Deserializer, Serialize, Serializer};

/// The environment of a cell.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Site {
    /// The paper's maze of size N (its layout is the job's `maze.seed`).
    Maze(usize),
    /// Another environment of the registry, which has no size (never [`EnvName::Maze`]).
    Env(EnvName),
}

impl Site {
    /// Where a job runs: its environment, and the maze's size when that is the maze.
    pub fn of(env: &crate::envs::EnvSpec) -> Site {
        match env.name {
            EnvName::Maze => Site::Maze(env.maze.size),
            other => Site::Env(other),
        }
    }

    /// The cell id's suffix: `maze<N>` or the environment's name.
    pub fn id(self) -> String {
        match self {
            Site::Maze(n) => format!("maze{n}"),
            Site::Env(e) => e.name().to_string(),
        }
    }

    /// How figures name it: `maze N×N` or the environment's name.
    pub fn title(self) -> String {
        match self {
            Site::Maze(n) => format!("maze {n}×{n}"),
            Site::Env(e) => e.name().to_string(),
        }
    }

    /// A grid row's or an axis' label: `N×N`, a PointMaze's map (`Medium`) or the
    /// environment's name.
    pub fn axis(self) -> String {
        match self {
            Site::Maze(n) => format!("{n}×{n}"),
            Site::Env(e) => e
                .point_map()
                .map_or_else(|| e.name().to_string(), |m| <&str>::from(m).to_string()),
        }
    }

    /// How sentences name it: `maze N` or the environment's name.
    pub fn named(self) -> String {
        match self {
            Site::Maze(n) => format!("maze {n}"),
            Site::Env(e) => e.name().to_string(),
        }
    }

    /// The maze size, for a maze.
    pub fn size(self) -> Option<usize> {
        match self {
            Site::Maze(n) => Some(n),
            Site::Env(_) => None,
        }
    }

    /// The environment's name.
    pub fn env(self) -> EnvName {
        match self {
            Site::Maze(_) => EnvName::Maze,
            Site::Env(e) => e,
        }
    }
}

impl std::fmt::Display for Site {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Site::Maze(n) => write!(f, "{n}"),
            Site::Env(e) => f.write_str(e.name()),
        }
    }
}

impl std::str::FromStr for Site {
    type Err = Error;

    /// A maze size (`15`) or an environment's name other than the maze (`rooms`).
    fn from_str(s: &str) -> Result<Site> {
        if let Ok(n) = s.parse::<usize>() {
            return Ok(Site::Maze(n));
        }
        match s.parse::<EnvName>() {
            Ok(EnvName::Maze) | Err(_) => Err(Error::invalid(
                "maze",
                format!(
                    "`{s}` is neither a maze size nor an environment ({})",
                    EnvName::others()
                ),
            )),
            Ok(e) => Ok(Site::Env(e)),
        }
    }
}

impl Serialize for Site {
    fn serialize<S: Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        match self {
            Site::Maze(n) => s.serialize_u64(*n as u64),
            Site::Env(e) => s.serialize_str(e.name()),
        }
    }
}

impl<'de> Deserialize<'de> for Site {
    fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<Site, D::Error> {
        struct SiteVisitor;
        impl Visitor<'_> for SiteVisitor {
            type Value = Site;
            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str("a maze size or an environment's name")
            }
            fn visit_u64<E: de::Error>(self, n: u64) -> std::result::Result<Site, E> {
                usize::try_from(n).map(Site::Maze).map_err(E::custom)
            }
            fn visit_i64<E: de::Error>(self, n: i64) -> std::result::Result<Site, E> {
                usize::try_from(n).map(Site::Maze).map_err(E::custom)
            }
            fn visit_str<E: de::Error>(self, s: &str) -> std::result::Result<Site, E> {
                s.parse().map_err(E::custom)
            }
        }
        d.deserialize_any(SiteVisitor)
    }
}

/// A job of a grid runs where its site says: the site sets `env` (and the maze's size), so a
/// job that names an environment itself is refused, naming `env` and `what` (the method).
pub(crate) fn place(
    job: &mut impl Located,
    site: Site,
    what: &str,
    own_map: Option<&PointMazeConfig>,
) -> Result<()> {
    let mut spec = job.env_spec();
    if !spec.name.is_maze() {
        return Err(Error::invalid(
            "env",
            format!(
                "{what}: \"{}\" — a grid's rows say where its methods run: list the \
                 environment in the experiment's `envs` instead",
                spec.name.name()
            ),
        ));
    }
    if !spec.pointmaze.is_default() {
        return Err(Error::invalid(
            "pointmaze",
            format!(
                "{what}: sets [pointmaze] — a grid's map of one's own (its rows and time limit) \
                 is the experiment file's own [pointmaze], for its sites `pointmaze` and \
                 `antmaze`"
            ),
        ));
    }
    match site {
        Site::Maze(n) => spec.maze.size = n,
        Site::Env(e) => spec.name = e,
    }
    if matches!(site, Site::Env(e) if e.takes_map()) {
        spec.pointmaze = own_map.cloned().unwrap_or_default();
    }
    job.set_env_spec(spec);
    *job.seed_mut() = 0;
    Ok(())
}

/// The paper's single run of `variant` on a site (results table, one seed each): its
/// environment steps and whether it solved the maze, from the method of that name (`pbcs`,
/// `pbcs_no_chaining`) in `experiments/table.toml`, the one place they are written (read at
/// compile time, so the binary needs no experiments folder). `(None, None)` for a size the
/// paper did not run (and any environment but its maze).
///
/// ```
/// use pbcs::experiment::{paper_run, Site};
/// use pbcs::phase2::Variant;
/// assert_eq!(paper_run(Variant::Pbcs, Site::Maze(2)), (Some(321_000), Some(true)));
/// assert_eq!(paper_run(Variant::PbcsNoChaining, Site::Maze(2)), (Some(146_000), Some(false)));
/// assert_eq!(paper_run(Variant::Pbcs, Site::Maze(3)), (None, None));
/// assert_eq!(paper_run(Variant::Pbcs, "rooms".parse().unwrap()), (None, None));
/// ```
pub fn paper_run(variant: Variant, site: Site) -> (Option<u64>, Option<bool>) {
    // The paper's figures of each method, as the results table's file states them (its other
    // fields, which the experiment's own reading checks, are not read here).
    #[derive(Deserialize)]
    struct PaperRuns {
        method: Vec<PaperMethod>,
    }
    #[derive(Deserialize)]
    struct PaperMethod {
        name: String,
        #[serde(default)]
        paper_steps: std::collections::BTreeMap<String, u64>,
        #[serde(default)]
        paper_solved: std::collections::BTreeMap<String, bool>,
    }
    let path = std::path::Path::new("experiments/table.toml");
    let spec: Option<PaperRuns> =
        crate::validate::parse_toml(include_str!("../../../experiments/table.toml"), path).ok();
    let method = spec
        .as_ref()
        .and_then(|s| s.method.iter().find(|m| m.name == variant.name()));
    let key = site.to_string();
    (
        method.and_then(|m| m.paper_steps.get(&key).copied()),
        method.and_then(|m| m.paper_solved.get(&key).copied()),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Debug, PartialEq, Serialize, Deserialize)]
    struct Row {
        #[serde(rename = "cell")]
        label: String,
        maze: Site,
    }

    #[test]
    fn a_site_is_the_maze_column_a_size_or_a_name() {
        for (site, csv) in [
            (Site::Maze(15), "cell,maze\nc,15\n"),
            (Site::Env(EnvName::Rooms), "cell,maze\nc,rooms\n"),
        ] {
            let row = Row {
                label: "c".into(),
                maze: site,
            };
            let mut w = csv::Writer::from_writer(Vec::new());
            w.serialize(&row).unwrap();
            assert_eq!(String::from_utf8(w.into_inner().unwrap()).unwrap(), csv);
            let back: Row = csv::Reader::from_reader(csv.as_bytes())
                .deserialize()
                .next()
                .unwrap()
                .unwrap();
            assert_eq!(back, row);
        }
        for bad in [
            "cell,maze\nc,maze\n",
            "cell,maze\nc,-3\n",
            "cell,maze\nc,hall\n",
        ] {
            let got: std::result::Result<Row, _> = csv::Reader::from_reader(bad.as_bytes())
                .deserialize()
                .next()
                .unwrap();
            assert!(got.is_err(), "{bad:?} read as {got:?}");
        }
    }
}
