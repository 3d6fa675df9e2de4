//! A PointMaze map of one's own (`env = "pointmaze"`): the job's `[pointmaze]`, its rows
//! read inline or from a file, and checked into a [`PointMap`].

use super::model::PointMap;
use crate::error::{Error, Result};

/// Steps per episode of a map of one's own when its job does not say (`[pointmaze]
/// time_limit`): Large's, the longest gymnasium-robotics registers.
pub const OWN_TIME_LIMIT: usize = 800;

/// The most rows or columns a map of one's own may have: the task is a breadth-first search
/// from every free cell ([`PointMap::farthest_cells`], cells² steps) and MuJoCo's model one box
/// per wall cell; 64 × 64 cells is 64 m across, 1 280 steps at top speed.
pub const MAX_MAP_SIDE: usize = 64;

/// A PointMaze map of one's own, as a job holds it (`env = "pointmaze"`, `[pointmaze]`): its
/// rows, and the time limit gymnasium-robotics' judge gives its episodes. A job writes the
/// rows themselves, so a run folder's `run.toml` says which map it ran; a config may instead
/// name a file of rows (`map_file`, read when the config is, relative to the working
/// folder: one row per line, `0` free and `1` wall, spaces between cells allowed, `#` starts a
/// comment).
///
/// ```
/// use pbcs::envs::pointmaze::{PointMazeConfig, PointMap};
/// let c: PointMazeConfig = toml::from_str(r#"map = ["11111", "10001", "11111"]"#).unwrap();
/// let map = PointMap::from_config(&c).unwrap();
/// assert_eq!((map.rows(), map.cols(), map.farthest_cells()), (3, 5, ((1, 1), (1, 3))));
/// assert_eq!(c.time_limit, 800);
/// let both = r#"map = ["111"]
/// map_file = "m.txt""#;
/// assert!(toml::from_str::<PointMazeConfig>(both).unwrap_err().to_string().contains("not both"));
/// ```
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(try_from = "PointMazeSpec")]
pub struct PointMazeConfig {
    /// The rows, top first, each a string of `0` (free) and `1` (wall) cells: gymnasium-robotics'
    /// `maze_map` (empty: no map, the default of every job but a `pointmaze` one).
    pub map: Vec<String>,
    /// Steps per episode of the judge (`gym.make(..., max_episode_steps=)`), default
    /// [`OWN_TIME_LIMIT`].
    pub time_limit: usize,
}

impl Default for PointMazeConfig {
    fn default() -> Self {
        PointMazeConfig {
            map: Vec::new(),
            time_limit: OWN_TIME_LIMIT,
        }
    }
}

impl PointMazeConfig {
    /// Whether this is the default (no map): left out of written jobs.
    pub fn is_default(&self) -> bool {
        *self == PointMazeConfig::default()
    }

    /// The map read from a file of rows (see [`PointMazeConfig`]), the time limit the
    /// default.
    pub fn from_file(path: &std::path::Path) -> Result<PointMazeConfig> {
        let text = std::fs::read_to_string(path).map_err(|e| {
            Error::invalid("pointmaze.map_file", format!("{}: {e}", path.display()))
        })?;
        let map = rows_of_text(&text).map_err(|e| {
            Error::invalid("pointmaze.map_file", format!("{}: {e}", path.display()))
        })?;
        Ok(PointMazeConfig {
            map,
            ..PointMazeConfig::default()
        })
    }

    /// Checks the map ([`PointMap::from_config`]: rows of 0/1, walled border, at most
    /// [`MAX_MAP_SIDE`] cells a side, two connected free cells for a task) and the time limit.
    pub fn check(&self) -> Result<()> {
        let map = PointMap::from_config(self)?;
        let (start, goal) = map.farthest_cells();
        if start == goal {
            return Err(Error::invalid(
                "pointmaze.map",
                "has no two connected free cells (one free cell, or free cells walled off \
                 from each other): the task goes from one free cell to another",
            ));
        }
        if self.time_limit == 0 {
            return Err(Error::invalid(
                "pointmaze.time_limit",
                "must be at least 1 step (the judge's episodes end there)",
            ));
        }
        Ok(())
    }
}

/// A file's rows: one per line of `0` and `1` (spaces between cells ignored), blank lines
/// and `#` comments skipped; a bad character is refused naming its line.
fn rows_of_text(text: &str) -> std::result::Result<Vec<String>, String> {
    let mut rows = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let line = line.split('#').next().unwrap_or("");
        let row: String = line.chars().filter(|c| !c.is_whitespace()).collect();
        if row.is_empty() {
            continue;
        }
        if let Some(c) = row.chars().find(|c| !matches!(c, '0' | '1')) {
            return Err(format!(
                "line {}: {c:?} is not a cell (0 free, 1 wall)",
                n + 1
            ));
        }
        rows.push(row);
    }
    if rows.is_empty() {
        return Err("has no rows".to_string());
    }
    Ok(rows)
}

/// How a config writes [`PointMazeConfig`]: the rows or a file of them, not both.
#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct PointMazeSpec {
    map: Option<Vec<String>>,
    map_file: Option<std::path::PathBuf>,
    time_limit: Option<usize>,
}

impl TryFrom<PointMazeSpec> for PointMazeConfig {
    type Error = String;
    fn try_from(s: PointMazeSpec) -> std::result::Result<PointMazeConfig, String> {
        let map = match (s.map, s.map_file) {
            (Some(_), Some(_)) => {
                return Err(
                    "give the map's rows (`map`) or a file of them (`map_file`), not both".into(),
                )
            }
            (Some(map), None) => map,
            (None, Some(file)) => {
                PointMazeConfig::from_file(&file)
                    .map_err(|e| e.to_string())?
                    .map
            }
            (None, None) => Vec::new(),
        };
        Ok(PointMazeConfig {
            map,
            time_limit: s.time_limit.unwrap_or(OWN_TIME_LIMIT),
        })
    }
}

impl PointMap {
    /// The map a job's `[pointmaze]` gives, its rows of `0` and `1` checked as
    /// [`PointMap::from_rows`] does, at most [`MAX_MAP_SIDE`] cells a side.
    pub fn from_config(c: &PointMazeConfig) -> Result<PointMap> {
        let field = "pointmaze.map";
        if c.map.is_empty() {
            return Err(Error::invalid(
                field,
                "env = \"pointmaze\" (and \"antmaze\") runs a map of one's own: give its rows \
                 (`[pointmaze] map = [\"111\", \"101\", ...]`, --map FILE, Python's map=)",
            ));
        }
        let mut rows = Vec::with_capacity(c.map.len());
        for (i, row) in c.map.iter().enumerate() {
            let cells: Option<Vec<u8>> = row
                .chars()
                .map(|ch| ch.to_digit(2).map(|d| d as u8))
                .collect();
            rows.push(cells.ok_or_else(|| {
                Error::invalid(
                    field,
                    format!("row {i} ({row:?}): cells are 0 (free) or 1 (wall)"),
                )
            })?);
        }
        let (h, w) = (rows.len(), rows[0].len());
        if h > MAX_MAP_SIDE || w > MAX_MAP_SIDE {
            return Err(Error::invalid(
                field,
                format!(
                    "{h} × {w} cells: at most {MAX_MAP_SIDE} a side (the task searches from \
                     every free cell, and MuJoCo adds a box per wall)"
                ),
            ));
        }
        PointMap::from_rows(&rows)
    }
}
