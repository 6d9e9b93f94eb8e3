//! The plotting kit every figure shares: the typed error, the one writer of PNG and SVG files
//! ([`Canvas`], [`write`]), the font, the scenario runs a figure overlays, the page, axes and
//! legends, the colour maps, contours and map cells.

use crate::run::{run, RunOptions};
use crate::scenario::{self, ScenarioError};
use crate::study::sweep::SweepError;
use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::element::ComposedElement;
use plotters::prelude::*;
use std::collections::{HashMap, VecDeque};
use std::path::{Path, PathBuf};

/// Why a figure could not be drawn.
#[derive(Debug, thiserror::Error)]
pub enum FigureError {
    /// No figure has this name; `known` lists the names.
    #[error("unknown figure '{name}' (expected one of: {known})")]
    Unknown { name: String, known: String },
    #[error("the bundled font is invalid")]
    Font,
    /// The output directory cannot be created.
    #[error("cannot create {}: {source}", .dir.display())]
    CreateDir { dir: PathBuf, source: std::io::Error },
    /// A scenario file a figure edits before running it cannot be read.
    #[error("{}: {source}", .path.display())]
    Read { path: PathBuf, source: std::io::Error },
    /// An output cannot be written or replaced (`crate::output`).
    #[error(transparent)]
    Output(#[from] crate::output::OutputError),
    #[error(transparent)]
    Scenario(#[from] ScenarioError),
    #[error(transparent)]
    Sweep(#[from] SweepError),
    /// A scenario run stopped early (divergence, bad model).
    #[error("{path}: {error}")]
    Run { path: String, error: crate::report::ReportedError },
    /// A scenario run did not meet its declared verdict.
    #[error("{path} did not meet its declared verdict (failures: {failures})")]
    Verdict { path: String, failures: String },
    /// The data of a figure is not what it draws (a scenario that settled nothing, a file
    /// without the line a figure edits).
    #[error("{0}")]
    Data(String),
    /// `tensegrity sweep --x`: not an axis of the sweep.
    #[error("--x {x}: not an axis of this sweep (its inputs and swept parameters: {axes})")]
    NotAnAxis { x: String, axes: String },
    /// `tensegrity sweep --figure`: neither .png nor .svg.
    #[error("--figure {}: give a .png or .svg file", .0.display())]
    Extension(PathBuf),
    /// A backend failed (the plotters error, as debug text).
    #[error("drawing failed: {0}")]
    Drawing(String),
}

impl<E: std::error::Error + Send + Sync> From<DrawingAreaErrorKind<E>> for FigureError {
    fn from(e: DrawingAreaErrorKind<E>) -> Self {
        FigureError::Drawing(format!("{e:?}"))
    }
}

// ---------------------------------------------------------------------------
// The one writer of figure files.
// ---------------------------------------------------------------------------

/// A figure's file format.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    Png,
    Svg,
}

impl Format {
    /// The format a file's extension names (`.png`, `.svg`).
    pub fn of(path: &Path) -> Option<Format> {
        match path.extension().and_then(|e| e.to_str()) {
            Some("png") => Some(Format::Png),
            Some("svg") => Some(Format::Svg),
            _ => None,
        }
    }

    /// The extension of a file of this format.
    pub fn extension(self) -> &'static str {
        match self {
            Format::Png => "png",
            Format::Svg => "svg",
        }
    }
}

/// What a figure draws from its data, the same on every backend.
pub trait Plot {
    /// Draws the figure on `root`, a blank page of the figure's size (the caller presents it).
    fn plot<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), FigureError>;
}

/// The files a figure is being drawn into (temporary ones, renamed by [`write`] when every one
/// is complete), with its size in pixels.
pub struct Canvas {
    size: (u32, u32),
    files: Vec<(PathBuf, Format)>,
}

impl Canvas {
    /// Draws `figure` into every file of the canvas (PNG through plotters' bitmap backend, SVG
    /// through its SVG backend), each written when its page is complete.
    pub fn draw(&self, figure: &impl Plot) -> Result<(), FigureError> {
        for (path, format) in &self.files {
            match format {
                Format::Png => present(BitMapBackend::new(path, self.size).into_drawing_area(), figure)?,
                Format::Svg => present(SVGBackend::new(path, self.size).into_drawing_area(), figure)?,
            }
        }
        Ok(())
    }
}

fn present<DB: DrawingBackend>(root: DrawingArea<DB, Shift>, figure: &impl Plot) -> Result<(), FigureError> {
    figure.plot(&root)?;
    root.present()?;
    Ok(())
}

/// Draws a figure of `size` into `outputs` (paths with their formats) through the project's
/// atomic writer (`crate::output`): `draw` draws into temporary files, which are renamed over
/// the outputs when it succeeds and removed when it fails (the old outputs stay).
pub(crate) fn write(
    outputs: &[(PathBuf, Format)],
    size: (u32, u32),
    draw: impl FnOnce(&Canvas) -> Result<(), FigureError>,
) -> Result<(), FigureError> {
    register_font()?;
    for (path, _) in outputs {
        crate::output::check_replaceable(path).map_err(FigureError::Output)?;
    }
    let canvas =
        Canvas { size, files: outputs.iter().map(|(path, f)| (crate::output::partial_path(path), *f)).collect() };
    let mut done = draw(&canvas);
    for ((partial, _), (path, _)) in canvas.files.iter().zip(outputs) {
        match done {
            Ok(()) => done = crate::output::commit(partial, path).map_err(FigureError::Output),
            Err(_) => crate::output::discard(partial),
        }
    }
    done
}

static FONT: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");

fn register_font() -> Result<(), FigureError> {
    plotters::style::register_font("sans-serif", FontStyle::Normal, FONT).map_err(|_| FigureError::Font)
}

// ---------------------------------------------------------------------------
// The dynamics a figure overlays.
// ---------------------------------------------------------------------------

/// Loads and runs a scenario whose results a figure draws (findings left out); a run that
/// stopped early (divergence, bad model) is an error naming the file.
pub(crate) fn run_scenario(path: &str) -> Result<(scenario::Scenario, crate::report::ScenarioReport), FigureError> {
    let sc = scenario::load(Path::new(path))?;
    let report = run(&sc, &RunOptions { skip_findings: true, ..Default::default() });
    match &report.error {
        Some(e) => Err(FigureError::Run { path: path.to_string(), error: e.clone() }),
        None => Ok((sc, report)),
    }
}

/// The text of scenario file `path` (to edit before parsing it).
pub(crate) fn read_scenario(path: &Path) -> Result<String, FigureError> {
    std::fs::read_to_string(path).map_err(|source| FigureError::Read { path: path.to_path_buf(), source })
}

// ---------------------------------------------------------------------------
// Pages, axes and legends.
// ---------------------------------------------------------------------------

/// The range of the values `v`, padded by 5 % of its width on each side.
pub(crate) fn range(v: &[f64]) -> std::ops::Range<f64> {
    let (lo, hi) = v.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| (a.min(*x), b.max(*x)));
    let pad = 0.05 * (hi - lo).max(1e-12);
    (lo - pad)..(hi + pad)
}

/// A chart with both axes in f64.
pub(crate) type Chart<'a, DB> = ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// A legend entry for a filled region of colour `colour` (the region itself is drawn cell by
/// cell, without a label).
pub(crate) fn swatch<'a, DB: DrawingBackend + 'a>(
    chart: &mut Chart<'a, DB>,
    label: &str,
    colour: RGBColor,
) -> Result<(), FigureError> {
    chart
        .draw_series(std::iter::empty::<Rectangle<(f64, f64)>>())?
        .label(label)
        .legend(move |(x, y)| Rectangle::new([(x, y - 5), (x + 15, y + 5)], colour.filled()));
    Ok(())
}

/// A figure's page: white, with its title on top in a font of `font_px`; the area below it.
pub(crate) fn titled_page<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
    font_px: u32,
) -> Result<DrawingArea<DB, Shift>, FigureError> {
    root.fill(&WHITE)?;
    Ok(root.titled(title, ("sans-serif", font_px))?)
}

/// The chart of a workspace map on `area`: `caption` above, axes over the ranges [rad or m]
/// labelled (x, y), no grid lines (the map's cells cover it).
pub(crate) fn map_chart<'a, DB: DrawingBackend>(
    area: &'a DrawingArea<DB, Shift>,
    caption: &str,
    x: std::ops::Range<f64>,
    y: std::ops::Range<f64>,
    (x_desc, y_desc): (&str, &str),
) -> Result<Chart<'a, DB>, FigureError> {
    let mut chart = ChartBuilder::on(area)
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(60)
        .caption(caption, ("sans-serif", 16))
        .build_cartesian_2d(x, y)?;
    chart.configure_mesh().disable_mesh().x_desc(x_desc).y_desc(y_desc).axis_desc_style(("sans-serif", 16)).draw()?;
    Ok(chart)
}

/// The legend box of every figure: framed, on a translucent white background.
pub(crate) fn legend_box<'a, DB: DrawingBackend + 'a>(
    chart: &mut Chart<'a, DB>,
    position: SeriesLabelPosition,
    font_px: u32,
) -> Result<(), FigureError> {
    chart
        .configure_series_labels()
        .position(position)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", font_px))
        .draw()?;
    Ok(())
}

/// A dot marker: a filled circle and its rim, placed at a point of the chart.
pub(crate) type Dot<DB> = ComposedElement<(f64, f64), DB, Circle<(i32, i32), i32>, Circle<(i32, i32), i32>>;

/// A dot marker at `at`: a circle of `radius` [px] filled with `fill`, with a black rim `rim_px`
/// wide.
pub(crate) fn rimmed_dot<DB: DrawingBackend>(at: (f64, f64), radius: i32, fill: RGBColor, rim_px: u32) -> Dot<DB> {
    EmptyElement::at(at)
        + Circle::new((0, 0), radius, fill.filled())
        + Circle::new((0, 0), radius, BLACK.stroke_width(rim_px))
}

// ---------------------------------------------------------------------------
// Helpers of the workspace maps (colour maps, colour bars, contours, legend panels).
// ---------------------------------------------------------------------------

/// Anchors of a sequential colour map from `t = 0` to `t = 1` (equally spaced).
pub(crate) type ColourAnchors = [(u8, u8, u8)];

/// Viridis, sampled at 9 equally spaced points (perceptually uniform, readable in grey).
pub(crate) const VIRIDIS: &ColourAnchors = &[
    (68, 1, 84),
    (71, 44, 122),
    (59, 81, 139),
    (44, 113, 142),
    (33, 144, 141),
    (39, 173, 129),
    (92, 200, 99),
    (170, 220, 50),
    (253, 231, 37),
];

/// A light white-to-blue map: dark markers and coloured curves stay readable on it.
pub(crate) const LIGHT_BLUES: &ColourAnchors = &[(250, 252, 255), (198, 219, 239), (140, 190, 226), (80, 150, 205)];

/// The colour at `t` in [0, 1] (clamped) of a map given by its anchors, linearly interpolated.
pub(crate) fn colour_at(anchors: &ColourAnchors, t: f64) -> RGBColor {
    let t = if t.is_finite() { t.clamp(0.0, 1.0) } else { 0.0 };
    let s = t * (anchors.len() - 1) as f64;
    let i = (s.floor() as usize).min(anchors.len() - 2);
    let f = s - i as f64;
    let (a, b) = (anchors[i], anchors[i + 1]);
    let mix = |p: u8, q: u8| (p as f64 + (q as f64 - p as f64) * f).round() as u8;
    RGBColor(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}

/// Steps of a colour bar.
const COLOUR_BAR_STEPS: usize = 200;
/// A colour bar spanning at least this much is labelled in whole units.
const COLOUR_BAR_INTEGER_SPAN: f64 = 10.0;

/// A vertical colour bar for values `lo..hi` of the map `anchors`, with its axis label.
pub(crate) fn colour_bar<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    anchors: &ColourAnchors,
    lo: f64,
    hi: f64,
    label: &str,
) -> Result<(), FigureError> {
    let mut chart = ChartBuilder::on(area)
        .margin_top(60)
        .margin_bottom(60)
        .margin_right(10)
        .y_label_area_size(70)
        .build_cartesian_2d(0.0..1.0, lo..hi)?;
    chart
        .configure_mesh()
        .disable_x_axis()
        .disable_x_mesh()
        .disable_y_mesh()
        .y_desc(label)
        .axis_desc_style(("sans-serif", 15))
        .label_style(("sans-serif", 13))
        .y_label_formatter(&|v| if hi - lo >= COLOUR_BAR_INTEGER_SPAN { format!("{v:.0}") } else { format!("{v:.2}") })
        .draw()?;
    let step = (hi - lo) / COLOUR_BAR_STEPS as f64;
    chart.draw_series((0..COLOUR_BAR_STEPS).map(|k| {
        let y = lo + step * k as f64;
        let c = colour_at(anchors, (k as f64 + 0.5) / COLOUR_BAR_STEPS as f64);
        Rectangle::new([(0.0, y), (1.0, y + step)], c.filled())
    }))?;
    Ok(())
}

/// The zero set of `f` on a `cells x cells` grid over `xs x ys`, by marching squares, as
/// polylines (segments chained through the grid edges they cross). NaN values cut a curve.
pub(crate) fn zero_contour(
    f: &dyn Fn(f64, f64) -> f64,
    xs: std::ops::Range<f64>,
    ys: std::ops::Range<f64>,
    cells: usize,
) -> Vec<Vec<(f64, f64)>> {
    let (crossing, segments) = contour_segments(f, xs, ys, cells);
    chain_segments(&segments).into_iter().map(|chain| chain.iter().map(|e| crossing[e]).collect()).collect()
}

/// An edge of the contour grid: (vertical?, i, j) from node (i, j) to (i + 1, j) or (i, j + 1).
type Edge = (bool, usize, usize);

/// Where the zero set crosses each crossed edge, and its segments, each between two edges.
type Contour = (HashMap<Edge, (f64, f64)>, Vec<(Edge, Edge)>);

/// The marching squares of [`zero_contour`]: where `f` crosses zero on each grid edge, and the
/// segments of the zero set, each between two crossed edges of a cell.
fn contour_segments(
    f: &dyn Fn(f64, f64) -> f64,
    xs: std::ops::Range<f64>,
    ys: std::ops::Range<f64>,
    cells: usize,
) -> Contour {
    let n = cells + 1;
    let (hx, hy) = ((xs.end - xs.start) / cells as f64, (ys.end - ys.start) / cells as f64);
    let at = |i: usize, j: usize| (xs.start + hx * i as f64, ys.start + hy * j as f64);
    let v: Vec<f64> = (0..n * n).map(|k| f(at(k / n, k % n).0, at(k / n, k % n).1)).collect();
    let val = |i: usize, j: usize| v[i * n + j];
    let mut crossing: HashMap<Edge, (f64, f64)> = HashMap::new();
    let mut cross = |e: Edge| -> Option<Edge> {
        let (i1, j1) = if e.0 { (e.1, e.2 + 1) } else { (e.1 + 1, e.2) };
        let (a, b) = (val(e.1, e.2), val(i1, j1));
        if !(a.is_finite() && b.is_finite()) || (a >= 0.0) == (b >= 0.0) {
            return None;
        }
        let t = a / (a - b);
        let (p, q) = (at(e.1, e.2), at(i1, j1));
        crossing.entry(e).or_insert((p.0 + t * (q.0 - p.0), p.1 + t * (q.1 - p.1)));
        Some(e)
    };
    let mut segments: Vec<(Edge, Edge)> = Vec::new();
    for i in 0..cells {
        for j in 0..cells {
            let edges = [(false, i, j), (true, i + 1, j), (false, i, j + 1), (true, i, j)];
            let hits: Vec<Edge> = edges.iter().filter_map(|e| cross(*e)).collect();
            match hits.len() {
                2 => segments.push((hits[0], hits[1])),
                4 => {
                    // A saddle: pair the crossings by the sign at the centre.
                    let centre = 0.25 * (val(i, j) + val(i + 1, j) + val(i + 1, j + 1) + val(i, j + 1));
                    if (centre >= 0.0) == (val(i, j) >= 0.0) {
                        segments.push((hits[0], hits[1]));
                        segments.push((hits[2], hits[3]));
                    } else {
                        segments.push((hits[0], hits[3]));
                        segments.push((hits[1], hits[2]));
                    }
                }
                _ => {}
            }
        }
    }
    (crossing, segments)
}

/// Chains the segments into polylines through their shared edges.
fn chain_segments(segments: &[(Edge, Edge)]) -> Vec<VecDeque<Edge>> {
    let mut by_edge: HashMap<Edge, Vec<usize>> = HashMap::new();
    for (k, (a, b)) in segments.iter().enumerate() {
        by_edge.entry(*a).or_default().push(k);
        by_edge.entry(*b).or_default().push(k);
    }
    let mut used = vec![false; segments.len()];
    let mut chains = Vec::new();
    for start in 0..segments.len() {
        if used[start] {
            continue;
        }
        used[start] = true;
        let mut chain: VecDeque<Edge> = [segments[start].0, segments[start].1].into();
        for forward in [true, false] {
            loop {
                let end = if forward { *chain.back().unwrap() } else { *chain.front().unwrap() };
                let Some(&k) = by_edge[&end].iter().find(|k| !used[**k]) else { break };
                used[k] = true;
                let next = if segments[k].0 == end { segments[k].1 } else { segments[k].0 };
                if forward {
                    chain.push_back(next);
                } else {
                    chain.push_front(next);
                }
            }
        }
        chains.push(chain);
    }
    chains
}

/// What a legend entry shows.
#[derive(Clone, Copy)]
pub(crate) enum Glyph {
    /// A filled region.
    Fill(RGBColor),
    /// A line of the given width.
    Line(RGBColor, u32),
    /// A dashed line of the given width.
    Dashed(RGBColor, u32),
    /// A filled circle with a black rim.
    Dot(RGBColor),
    /// A filled diamond with a black rim.
    Diamond(RGBColor),
    /// A cross.
    Cross(RGBColor),
    /// An open ring.
    Ring(RGBColor),
    /// A filled triangle.
    Triangle(RGBColor),
    /// Text only (a note under the other entries).
    Note,
}

/// Pixel size of a legend row and of the glyph column.
const LEGEND_ROW_PX: i32 = 22;
const LEGEND_GLYPH_PX: i32 = 34;

/// A legend in its own area (below or beside a chart), `columns` columns, framed.
pub(crate) fn legend_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    entries: &[(Glyph, String)],
    columns: usize,
    font_px: u32,
) -> Result<(), FigureError> {
    let (w, h) = area.dim_in_pixel();
    area.draw(&Rectangle::new([(4, 2), (w as i32 - 4, h as i32 - 2)], BLACK.stroke_width(1)))?;
    let rows = entries.len().div_ceil(columns.max(1)) as i32;
    let col_w = (w as i32 - 20) / columns.max(1) as i32;
    for (k, (glyph, label)) in entries.iter().enumerate() {
        let (col, row) = (k as i32 / rows, k as i32 % rows);
        let (x, y) = (14 + col * col_w, 12 + row * LEGEND_ROW_PX + LEGEND_ROW_PX / 2);
        draw_glyph(area, *glyph, (x, y))?;
        let tx = if matches!(glyph, Glyph::Note) { x } else { x + LEGEND_GLYPH_PX };
        area.draw(&Text::new(
            label.clone(),
            (tx, y - font_px as i32 / 2 - 1),
            ("sans-serif", font_px).into_font().color(&BLACK),
        ))?;
    }
    Ok(())
}

/// Draws a legend glyph with its left end at pixel `(x, y)`.
fn draw_glyph<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    glyph: Glyph,
    (x, y): (i32, i32),
) -> Result<(), FigureError> {
    let mid = (x + 12, y);
    match glyph {
        Glyph::Fill(c) => area.draw(&Rectangle::new([(x, y - 7), (x + 24, y + 7)], c.filled()))?,
        Glyph::Line(c, w) => area.draw(&PathElement::new(vec![(x, y), (x + 26, y)], c.stroke_width(w)))?,
        Glyph::Dashed(c, w) => {
            area.draw(&plotters::element::DashedPathElement::new(vec![(x, y), (x + 26, y)], 6, 4, c.stroke_width(w)))?
        }
        Glyph::Dot(c) => {
            area.draw(&Circle::new(mid, 6, c.filled()))?;
            area.draw(&Circle::new(mid, 6, BLACK.stroke_width(1)))?;
        }
        Glyph::Diamond(c) => {
            let pts = vec![(mid.0, mid.1 - 8), (mid.0 + 8, mid.1), (mid.0, mid.1 + 8), (mid.0 - 8, mid.1)];
            area.draw(&Polygon::new(pts.clone(), c.filled()))?;
            area.draw(&PathElement::new([pts.clone(), vec![pts[0]]].concat(), BLACK.stroke_width(1)))?;
        }
        Glyph::Cross(c) => area.draw(&Cross::new(mid, 6, c.stroke_width(2)))?,
        Glyph::Ring(c) => area.draw(&Circle::new(mid, 8, c.stroke_width(2)))?,
        Glyph::Triangle(c) => area.draw(&TriangleMarker::new(mid, 7, c.filled()))?,
        Glyph::Note => {}
    }
    Ok(())
}

/// Map cells (centre x, centre y, colour), in column order (x outer, y rising), merged into
/// vertical runs of one colour: the same picture with far fewer rectangles (the SVG files
/// shrink by the run length). `cell` is the cell size (x, y).
pub(crate) fn cell_runs(
    cells: impl IntoIterator<Item = (f64, f64, RGBColor)>,
    cell: (f64, f64),
) -> Vec<Rectangle<(f64, f64)>> {
    let (hx, hy) = (cell.0 / 2.0, cell.1 / 2.0);
    // A run: column x, first and last centre y, colour.
    let mut runs: Vec<(f64, f64, f64, RGBColor)> = Vec::new();
    for (x, y, c) in cells {
        match runs.last_mut() {
            Some(r) if (r.0 - x).abs() < 1e-9 * hx && r.3 == c && (y - r.2 - cell.1).abs() < 1e-6 * cell.1 => r.2 = y,
            _ => runs.push((x, y, y, c)),
        }
    }
    runs.into_iter().map(|(x, y0, y1, c)| Rectangle::new([(x - hx, y0 - hy), (x + hx, y1 + hy)], c.filled())).collect()
}
