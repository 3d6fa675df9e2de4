//! A run's picture as data: what a picture of a planar environment draws (points, τ, rollouts,
//! activation balls), owned and stored as `picture.csv`, so that runs write data and the
//! drawing layer ([`crate::plot`], [`crate::figures`]) draws it, then or later from the file.

use crate::error::{Error, Result};
use std::path::Path;

/// The layers of `picture.csv`, by their names in the file (one table: strum derives both
/// directions; `red` and `green` are the names the committed files use).
#[derive(Debug, Clone, Copy, PartialEq, Eq, strum::IntoStaticStr, strum::EnumString)]
#[strum(serialize_all = "snake_case")]
enum Layer {
    /// Faint points (archive or visited states).
    Point,
    /// A phase-1 trajectory τ.
    #[strum(serialize = "red")]
    Tau,
    /// A square of the explored area.
    Area,
    /// A rollout of a policy or chain.
    #[strum(serialize = "green")]
    Rollout,
    /// An activation ball.
    Circle,
}

/// The owned content of a picture ([`crate::plot::Picture`] borrows it), as stored in a run's `picture.csv`, so that figures
/// can be drawn again from committed results without re-running anything.
///
/// The CSV has one row per point: `layer, index, x, y, r`, where `layer` is `point`, `red`
/// (polyline `index`), `area` (square of side `r` at lower-left corner `(x, y)`), `green`
/// (polyline `index`) or `circle` (centre `(x, y)`, radius `r`).
///
/// ```
/// use pbcs::picture::PictureData;
///
/// let data = PictureData {
///     tau_paths: vec![vec![(0.5, 0.5), (0.6, 0.5)]],
///     circles: vec![((1.0, 1.5), 0.1)],
///     ..PictureData::default()
/// };
/// let dir = tempfile::tempdir().unwrap();
/// let path = dir.path().join("picture.csv");
/// data.write_csv(&path).unwrap();
/// assert_eq!(PictureData::read_csv(&path).unwrap(), data);
/// ```
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PictureData {
    /// Faint points.
    pub points: Vec<(f32, f32)>,
    /// Red polylines.
    pub tau_paths: Vec<Vec<(f32, f32)>>,
    /// Red squares by lower-left corner.
    pub red_area: Vec<(f32, f32)>,
    /// Side of the red squares.
    pub red_area_side: f32,
    /// Green polylines.
    pub rollout_paths: Vec<Vec<(f32, f32)>>,
    /// Purple circles.
    pub circles: Vec<((f32, f32), f32)>,
}

/// The columns of a picture's data file.
const PICTURE_HEADER: [&str; 5] = ["layer", "index", "x", "y", "r"];

impl PictureData {
    /// Writes the data as CSV (atomically): one row per point, `layer, index, x, y, r`.
    pub fn write_csv(&self, path: &Path) -> Result<()> {
        let header: Vec<String> = PICTURE_HEADER.map(String::from).to_vec();
        let mut rows: Vec<[String; 5]> = Vec::new();
        let row = |layer: Layer, i: usize, (x, y): (f32, f32), r: f32| {
            [
                <&str>::from(layer).to_string(),
                i.to_string(),
                x.to_string(),
                y.to_string(),
                r.to_string(),
            ]
        };
        rows.extend(self.points.iter().map(|&p| row(Layer::Point, 0, p, 0.0)));
        for (i, path) in self.tau_paths.iter().enumerate() {
            rows.extend(path.iter().map(|&p| row(Layer::Tau, i, p, 0.0)));
        }
        rows.extend(
            self.red_area
                .iter()
                .map(|&p| row(Layer::Area, 0, p, self.red_area_side)),
        );
        for (i, path) in self.rollout_paths.iter().enumerate() {
            rows.extend(path.iter().map(|&p| row(Layer::Rollout, i, p, 0.0)));
        }
        rows.extend(
            self.circles
                .iter()
                .map(|&(c, r)| row(Layer::Circle, 0, c, r)),
        );
        crate::record::write_csv(path, &header, rows)
    }

    /// Reads data written by [`PictureData::write_csv`]: its header, then rows; another header
    /// (an empty file, another file) is an error naming the file.
    pub fn read_csv(path: &Path) -> Result<PictureData> {
        let mut reader = csv::Reader::from_path(path).map_err(|e| Error::csv(path, e))?;
        let header = reader.headers().map_err(|e| Error::csv(path, e))?;
        if header.iter().ne(PICTURE_HEADER) {
            return Err(Error::parse(
                path,
                format!(
                    "line 1: the header is {:?}, a picture's is {:?} (not a picture's data)",
                    header.iter().collect::<Vec<_>>(),
                    PICTURE_HEADER
                ),
            ));
        }
        let mut data = PictureData::default();
        let bad = |line: u64, what: &str| Error::parse(path, format!("line {line}: {what}"));
        let push = |paths: &mut Vec<Vec<(f32, f32)>>, i: usize, p| {
            if paths.len() <= i {
                paths.resize(i + 1, Vec::new());
            }
            paths[i].push(p);
        };
        for (line, rec) in reader.records().enumerate() {
            let rec = rec.map_err(|e| Error::csv(path, e))?;
            let line = line as u64 + 2;
            let num = |k: usize| -> Result<f32> {
                rec.get(k)
                    .and_then(|v| v.parse().ok())
                    .ok_or_else(|| bad(line, "expected a number"))
            };
            let i: usize = rec
                .get(1)
                .and_then(|v| v.parse().ok())
                .ok_or_else(|| bad(line, "expected an index"))?;
            let (p, r) = ((num(2)?, num(3)?), num(4)?);
            let layer = rec.get(0).and_then(|l| l.parse::<Layer>().ok());
            match layer.ok_or_else(|| bad(line, "unknown layer"))? {
                Layer::Point => data.points.push(p),
                Layer::Tau => push(&mut data.tau_paths, i, p),
                Layer::Area => {
                    data.red_area.push(p);
                    data.red_area_side = r;
                }
                Layer::Rollout => push(&mut data.rollout_paths, i, p),
                Layer::Circle => data.circles.push((p, r)),
            }
        }
        Ok(data)
    }
}

/// A run's picture as its folder gets it: the file stem (`run`, `train`, `explore`,
/// `eval-s<seed>`), the title line, the environment's scene and what to draw over it. Runs
/// make it and write its data; the drawing step their `write` is handed ([`Draw`]) draws it.
#[derive(Debug, Clone)]
pub struct RunPicture<'a> {
    /// The pictures' file stem in the run's folder (`<stem>.png`, `<stem>.svg`).
    pub stem: String,
    /// The title line.
    pub title: String,
    /// The environment's scene the data is drawn over.
    pub scene: crate::env::Scene,
    /// What is drawn over the scene.
    pub data: &'a PictureData,
}

/// The drawing step a run's `write` calls with the run's picture and the folder it is
/// writing (for `explore`, `train` and `run`, inside the run folder's staging, so that the
/// pictures land with the data, all or none; `eval` writes its files beside a chain, one by
/// one): [`crate::plot::draw_run`], what the commands pass, or [`no_pictures`]. Runs compute
/// and write data; this is where drawing comes in, from the layer that draws.
pub type Draw<'f> = &'f dyn Fn(&RunPicture, &Path) -> Result<()>;

/// The drawing step that draws nothing: a run's folder holds its data (and, where the run
/// keeps one, its `picture.csv`) without PNG or SVG.
pub fn no_pictures(_: &RunPicture, _: &Path) -> Result<()> {
    Ok(())
}
