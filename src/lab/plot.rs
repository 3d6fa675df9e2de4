//! Pictures of planar environments with plotters (a maze, the rooms: the walls, target and
//! start of an [`crate::env::Scene`]), archive states, trajectories, markers.
//!
//! The renderers draw in the environment's coordinates on any plotters backend, so the same drawing code
//! produces PNG (bitmap backend) and SVG. Text uses the DejaVu Sans font shipped in
//! `figures/fonts/`, registered once, so no system font lookup happens.

use crate::env::Scene;
use crate::error::{Error, Result};
use crate::picture::PictureData;
use plotters::coord::types::RangedCoordf32;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;
use std::sync::Once;

static FONT: &[u8] = include_bytes!("../../figures/fonts/DejaVuSans.ttf");

/// Registers the bundled font as "sans-serif" (idempotent).
pub fn register_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        plotters::style::register_font("sans-serif", FontStyle::Normal, FONT)
            .unwrap_or_else(|_| panic!("bundled font figures/fonts/DejaVuSans.ttf is invalid"));
    });
}

/// What to draw over a planar environment's scene ([`crate::env::Scene`]).
#[derive(Debug, Clone, Default)]
pub struct Picture<'a> {
    /// Title line above the scene.
    pub title: String,
    /// Faint points (archive states, visited states).
    pub points: &'a [(f32, f32)],
    /// Red polylines (phase-1 trajectory).
    pub tau_paths: Vec<&'a [(f32, f32)]>,
    /// Red filled squares of the given side, by lower-left corner (the explored area).
    pub red_area: &'a [(f32, f32)],
    /// Side of the `red_area` squares.
    pub red_area_side: f32,
    /// Green polylines (rollouts of a policy or chain).
    pub rollout_paths: Vec<Vec<(f32, f32)>>,
    /// Purple circles (centre, radius): activation sets.
    pub circles: Vec<((f32, f32), f32)>,
}

/// Height of the legend line under the scene.
const LEGEND_PX: u32 = 18;

/// Most archive points drawn in an SVG picture (the PNG draws them all).
pub const SVG_MAX_POINTS: usize = 20_000;

/// The legend of what `picture` draws (colours named), empty when it draws nothing but the scene.
pub fn legend(picture: &Picture) -> String {
    let mut parts = vec!["blue dot: start", "green disc: target"];
    if !picture.points.is_empty() {
        parts.push("faint blue: visited states");
    }
    if !picture.red_area.is_empty() {
        parts.push("red squares: explored area");
    }
    if !picture.tau_paths.is_empty() {
        parts.push("red: trajectory τ");
    }
    if !picture.rollout_paths.is_empty() {
        parts.push("green: rollouts");
    }
    if !picture.circles.is_empty() {
        parts.push("purple: activation balls");
    }
    parts.join(" · ")
}

type Chart<'b, DB> = ChartContext<'b, DB, Cartesian2d<RangedCoordf32, RangedCoordf32>>;

fn plot_err(path: &Path, e: impl std::fmt::Display) -> Error {
    Error::Plot {
        path: path.to_path_buf(),
        message: e.to_string(),
    }
}

/// Draws `picture` over `scene` (an environment's, [`crate::env::Planar::scene`]) on `area` (any plotters
/// backend; the caller presents it).
pub fn draw_scene<DB: DrawingBackend>(
    area: DrawingArea<DB, Shift>,
    scene: &Scene,
    picture: &Picture,
) -> std::result::Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    area.fill(&WHITE)?;
    let area = with_legend(area, picture)?;
    let (w, h) = (scene.width, scene.height);
    let margin = 0.1;
    let mut builder = ChartBuilder::on(&area);
    builder.margin(10);
    if !picture.title.is_empty() {
        // The whole title fits the width: at most 14 px, smaller for long titles on small
        // mazes (a glyph is about 0.55 of the font size wide).
        let width = area.dim_in_pixel().0 as f64 - 20.0;
        let chars = picture.title.chars().count().max(1) as f64;
        let size = (width / (0.55 * chars)).clamp(8.0, 14.0);
        builder.caption(&picture.title, ("sans-serif", size));
    }
    let mut chart: Chart<DB> =
        builder.build_cartesian_2d(-margin..w + margin, -margin..h + margin)?;
    // Faint archive / visited points.
    let faint = RGBColor(70, 110, 200).mix(0.25);
    chart.draw_series(
        picture
            .points
            .iter()
            .map(|&(x, y)| Pixel::new((x, y), faint)),
    )?;
    // Explored area.
    let side = picture.red_area_side;
    let area_colour = RGBColor(220, 40, 40).mix(0.6);
    chart.draw_series(
        picture
            .red_area
            .iter()
            .map(|&(x, y)| Rectangle::new([(x, y), (x + side, y + side)], area_colour.filled())),
    )?;
    // Walls.
    chart.draw_series(
        (scene.walls.iter()).map(|&corners| Rectangle::new(corners, BLACK.filled())),
    )?;
    // Rollouts, then τ on top of them (it would hide under ten rollouts otherwise). Each
    // segment is its own 2-pixel line: the bitmap backend joins a wide polyline with mitres,
    // and at a near reversal (τ is a random walk) a mitre spikes far out of the maze.
    let segments = |path: &[(f32, f32)], style: ShapeStyle| {
        path.windows(2)
            .map(move |w| PathElement::new(vec![w[0], w[1]], style))
            .collect::<Vec<_>>()
    };
    for path in &picture.rollout_paths {
        chart.draw_series(segments(path, RGBColor(0, 170, 0).stroke_width(2)))?;
    }
    for path in &picture.tau_paths {
        chart.draw_series(segments(path, RED.stroke_width(2)))?;
    }
    let purple = RGBColor(140, 40, 200);
    for &((cx, cy), r) in &picture.circles {
        let ring: Vec<(f32, f32)> = (0..=48)
            .map(|i| {
                let a = i as f32 / 48.0 * std::f32::consts::TAU;
                (cx + r * a.cos(), cy + r * a.sin())
            })
            .collect();
        chart.draw_series(LineSeries::new(ring, purple.stroke_width(2)))?;
    }
    draw_target_and_start(&mut chart, scene)
}

/// A titled (stand-alone) picture gets a legend line at the bottom of `area`, fitted to the
/// width; untitled panels of a grid do not. Returns the area left for the picture.
fn with_legend<DB: DrawingBackend>(
    area: DrawingArea<DB, Shift>,
    picture: &Picture,
) -> std::result::Result<DrawingArea<DB, Shift>, DrawingAreaErrorKind<DB::ErrorType>> {
    if picture.title.is_empty() {
        return Ok(area);
    }
    let (w, h) = area.dim_in_pixel();
    let (area, bottom) = area.split_vertically(h.saturating_sub(LEGEND_PX));
    let text = legend(picture);
    let chars = text.chars().count().max(1) as f64;
    let size = ((w as f64 - 20.0) / (0.55 * chars)).clamp(8.0, 12.0);
    bottom.draw(&Text::new(
        text,
        (10, 2),
        ("sans-serif", size).into_font().color(&BLACK),
    ))?;
    Ok(area)
}

/// The target region (a filled, outlined disc) and the start (a blue dot).
fn draw_target_and_start<DB: DrawingBackend>(
    chart: &mut Chart<DB>,
    scene: &Scene,
) -> std::result::Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let ((tx, ty), r) = scene.target;
    let ring: Vec<(f32, f32)> = (0..=64)
        .map(|i| {
            let a = i as f32 / 64.0 * std::f32::consts::TAU;
            (tx + r * a.cos(), ty + r * a.sin())
        })
        .collect();
    chart.draw_series(std::iter::once(Polygon::new(
        ring.clone(),
        RGBColor(0, 160, 0).mix(0.35).filled(),
    )))?;
    chart.draw_series(LineSeries::new(ring, RGBColor(0, 120, 0).stroke_width(2)))?;
    chart.draw_series(std::iter::once(Circle::new(scene.start, 5, BLUE.filled())))?;
    Ok(())
}

/// A figure that can draw itself on any plotters backend, so that one drawing routine gives
/// both the PNG and the SVG file ([`render_figure`]).
pub trait Figure {
    /// Pixel size (width, height).
    fn size(&self) -> (u32, u32);
    /// Draws the figure on `area` (filled white already).
    fn draw<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
    ) -> std::result::Result<(), DrawingAreaErrorKind<DB::ErrorType>>;
}

/// Renders `figure` to `<stem>.png` and `<stem>.svg` (atomically), returning both paths.
pub fn render_figure<F: Figure>(figure: &F, stem: &Path) -> Result<[std::path::PathBuf; 2]> {
    register_font();
    let png = stem.with_extension("png");
    let svg = stem.with_extension("svg");
    let size = figure.size();
    crate::record::write_atomic_via_path(&png, |tmp| {
        let root = BitMapBackend::new(tmp, size).into_drawing_area();
        root.fill(&WHITE)
            .and_then(|()| figure.draw(&root))
            .and_then(|()| root.present())
            .map_err(|e| plot_err(&png, e))
    })?;
    let mut text = String::new();
    {
        let root = SVGBackend::with_string(&mut text, size).into_drawing_area();
        root.fill(&WHITE)
            .and_then(|()| figure.draw(&root))
            .and_then(|()| root.present())
            .map_err(|e| plot_err(&svg, e))?;
    }
    crate::record::write_atomic(&svg, |out| out.write_all(text.as_bytes()))?;
    Ok([png, svg])
}

/// Pixel size of a scene's picture: 40 px per unit of its longer side, that side between
/// 400 and 1200 px (a maze: 40 px per cell), the shorter side in proportion.
fn scene_px(scene: &Scene) -> (u32, u32) {
    let long = scene.width.max(scene.height);
    let side = ((long * 40.0).round() as u32).clamp(400, 1200);
    let px = |x: f32| (side as f32 * x / long).round() as u32;
    (px(scene.width), px(scene.height))
}

/// Renders `picture` over `scene` to a PNG file and an SVG file (both written atomically).
/// The SVG draws at most `svg_max_points` of the faint points and of the area squares (a
/// deterministic stride), so that it stays small for millions of states; the PNG draws all.
pub fn render_scene(
    scene: &Scene,
    picture: &Picture,
    png: &Path,
    svg: &Path,
    svg_max_points: usize,
) -> Result<()> {
    register_font();
    let (w, h) = scene_px(scene);
    let size = (
        w,
        h + if picture.title.is_empty() {
            0
        } else {
            30 + LEGEND_PX
        },
    );
    crate::record::write_atomic_via_path(png, |tmp| {
        let root = BitMapBackend::new(tmp, size).into_drawing_area();
        draw_scene(root.clone(), scene, picture)
            .and_then(|()| root.present())
            .map_err(|e| plot_err(png, e))
    })?;
    let thin = |v: &[(f32, f32)]| -> Vec<(f32, f32)> {
        let stride = v.len().div_ceil(svg_max_points.max(1)).max(1);
        v.iter().step_by(stride).copied().collect()
    };
    let (points, area) = (thin(picture.points), thin(picture.red_area));
    let svg_picture = Picture {
        points: &points,
        red_area: &area,
        ..picture.clone()
    };
    let mut text = String::new();
    {
        let root = SVGBackend::with_string(&mut text, size).into_drawing_area();
        draw_scene(root.clone(), scene, &svg_picture)
            .and_then(|()| root.present())
            .map_err(|e| plot_err(svg, e))?;
    }
    crate::record::write_atomic(svg, |out| out.write_all(text.as_bytes()))
}

/// Draws `picture` over `scene` into an RGB image of `side × side` pixels (row-major, three
/// bytes a pixel), without title or legend: what the Python environment's `render()` returns.
///
/// ```
/// use pbcs::env::Planar;
/// use pbcs::envs::maze::{Maze, MazeConfig};
/// use pbcs::plot::{render_rgb, Picture};
///
/// let maze = Maze::new(&MazeConfig { size: 2, ..Default::default() }).unwrap();
/// let rgb = render_rgb(&maze.scene(), &Picture::default(), 64).unwrap();
/// assert_eq!(rgb.len(), 64 * 64 * 3);
/// assert_eq!(&rgb[..3], &[255, 255, 255]); // the white margin
/// ```
pub fn render_rgb(scene: &Scene, picture: &Picture, side: u32) -> Result<Vec<u8>> {
    register_font();
    let mut buf = vec![0u8; side as usize * side as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (side, side)).into_drawing_area();
        draw_scene(root.clone(), scene, picture)
            .and_then(|()| root.present())
            .map_err(|e| plot_err(Path::new("<rgb array>"), e))?;
    }
    Ok(buf)
}

impl PictureData {
    /// A picture of this data with `title`.
    pub fn picture(&self, title: String) -> Picture<'_> {
        Picture {
            title,
            points: &self.points,
            tau_paths: self.tau_paths.iter().map(Vec::as_slice).collect(),
            red_area: &self.red_area,
            red_area_side: self.red_area_side,
            rollout_paths: self.rollout_paths.clone(),
            circles: self.circles.clone(),
        }
    }
}

/// Draws a run's picture into `dir` as `<stem>.png` and `<stem>.svg` ([`render_scene`]; the
/// SVG thinned to [`SVG_MAX_POINTS`]): the drawing step ([`crate::picture::Draw`]) the
/// commands hand to a run's `write`.
pub fn draw_run(picture: &crate::picture::RunPicture, dir: &Path) -> Result<()> {
    render_scene(
        &picture.scene,
        &picture.data.picture(picture.title.clone()),
        &dir.join(format!("{}.png", picture.stem)),
        &dir.join(format!("{}.svg", picture.stem)),
        SVG_MAX_POINTS,
    )
}
