//! `tensegrity sweep S.toml --figure FILE.png|FILE.svg`: any sweep drawn against one of its
//! axes (an input or a swept parameter), one series per value of the other axes: per compared
//! quantity (checks, predictions, probed stiffness) the closed form as a line and the settled
//! values as dots; a probe's stiffness without a closed form as dots; the `[energy]` model's
//! equilibrium landed on (a line, the settled coordinates as dots) and its Hessian eigenvalues
//! there (lines); each natural frequency of a motion over the points (`[[motion.frequencies]]`:
//! the prediction as a line, the frequency measured from the motion as dots); below, log10 of
//! every error.

use super::kit::{self, range, titled_page, FigureError, Format, Plot};
use crate::study::sweep::Row;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;

/// Quantities drawn in panels of their own (the error panel shows them all).
const MAX_PANELS: usize = 6;
/// Width and height of a sweep figure [px]: a panel's height per quantity, plus the errors.
const WIDTH_PX: u32 = 900;
const PANEL_PX: u32 = 260;
/// Errors below this are drawn at it on the log axis (an exact match).
const ERROR_FLOOR: f64 = 1e-17;
/// Colours of the series (cycled).
const PALETTE: [RGBColor; 6] = [BLUE, RED, GREEN, MAGENTA, CYAN, BLACK];

/// What a sweep figure shows.
/// One series of a sweep plot: its label and its rows' (x, analytic, simulated, |error|) per
/// quantity.
type Series = (String, Vec<Vec<(f64, f64, f64, f64)>>);

struct SweepPlot {
    title: String,
    x: String,
    quantities: Vec<String>,
    /// Each quantity's panel caption: what its line and its dots are.
    captions: Vec<String>,
    /// Per series (one value of the other axes): its label and its rows' (x, analytic,
    /// simulated, |error|) per quantity, sorted by x; NaN where a point has no such value.
    series: Vec<Series>,
}

/// The axis to draw against: `x` if given (a column of the points), else the one with the
/// most distinct values.
fn x_axis(rows: &[Row], x: Option<&str>) -> Result<String, FigureError> {
    let keys: Vec<&String> = rows.first().map(|r| r.point.inputs.keys().collect()).unwrap_or_default();
    if let Some(x) = x {
        return match keys.iter().any(|k| *k == x) {
            true => Ok(x.to_string()),
            false => Err(FigureError::NotAnAxis {
                x: x.to_string(),
                axes: keys.iter().map(|k| k.as_str()).collect::<Vec<_>>().join(", "),
            }),
        };
    }
    let distinct = |k: &str| {
        let mut v: Vec<f64> = rows.iter().filter_map(|r| r.point.inputs.get(k).copied()).collect();
        v.sort_by(f64::total_cmp);
        v.dedup();
        v.len()
    };
    keys.iter()
        .max_by_key(|k| distinct(k))
        .map(|k| k.to_string())
        .ok_or_else(|| FigureError::Data("the sweep has no axis".into()))
}

/// Where a panel's values come from.
#[derive(Clone, Debug, PartialEq)]
enum Source {
    /// A quantity with a closed form (a check, a prediction, a probe's `expected`): the closed
    /// form as a line, the settled values as dots.
    Compared(String),
    /// A quantity only measured (a probe without a closed form): the settled values as dots.
    Measured(String),
    /// A coordinate of the `[energy]` model: the stationary point landed on as a line, the
    /// coordinate read off the settled state as dots.
    Equilibrium(String),
    /// The Hessian's eigenvalue K (from 0, ascending) at the stationary point landed on.
    Eigenvalue(usize),
    /// A natural frequency of the motion from each point: its prediction (a line) and the
    /// frequency measured from the motion (dots) [rad/s].
    Frequency(String),
}

impl Source {
    fn name(&self) -> String {
        match self {
            Source::Compared(q) | Source::Measured(q) => q.clone(),
            Source::Equilibrium(c) => format!("equilibrium {c}"),
            Source::Eigenvalue(k) => format!("eigenvalue {}", k + 1),
            Source::Frequency(f) => format!("{f} [rad/s]"),
        }
    }

    fn caption(&self) -> String {
        match self {
            Source::Compared(q) => format!("{q}: closed form (line), settled (dots)"),
            Source::Measured(q) => format!("{q}: measured (dots), no closed form"),
            Source::Equilibrium(c) => format!("{c}: energy model's equilibrium landed on (line), settled (dots)"),
            Source::Eigenvalue(k) => format!("energy model's Hessian eigenvalue {} at that equilibrium (line)", k + 1),
            Source::Frequency(f) => {
                format!("{f}: prediction (line; the modal analysis without a formula), free vibration (dots) [rad/s]")
            }
        }
    }

    /// The line's and the dots' value at one point (NaN where there is none).
    fn values(&self, p: &crate::report::PointReport) -> (f64, f64) {
        let landed = || p.energy.as_ref().and_then(|e| e.stationary.get(e.landed?));
        let nan = f64::NAN;
        match self {
            Source::Compared(q) => {
                (p.analytic.get(q).copied().unwrap_or(nan), p.simulated.get(q).copied().unwrap_or(nan))
            }
            Source::Measured(q) => (nan, p.simulated.get(q).copied().unwrap_or(nan)),
            Source::Equilibrium(c) => (
                landed().and_then(|s| s.coordinates.get(c).copied()).unwrap_or(nan),
                p.energy.as_ref().and_then(|e| e.measured.get(c).copied()).unwrap_or(nan),
            ),
            Source::Eigenvalue(k) => (landed().and_then(|s| s.eigenvalues.get(*k).copied()).unwrap_or(nan), nan),
            Source::Frequency(f) => {
                let f = p.frequencies.iter().find(|x| x.name == *f);
                (f.map_or(nan, |f| f.predicted_rad_per_s), f.map_or(nan, |f| f.corrected_rad_per_s))
            }
        }
    }

    /// The quantity whose errors are wrapped when it is an angle.
    fn angle_name(&self) -> Option<&str> {
        match self {
            Source::Compared(q) | Source::Equilibrium(q) => Some(q),
            _ => None,
        }
    }
}

/// The panels of a sweep: the natural frequencies of a motion from each point, the compared
/// quantities, the `measured` ones (a probe without a closed form), the energy model's
/// equilibrium coordinates and Hessian eigenvalues.
fn sources(rows: &[Row], measured: &[String]) -> Vec<Source> {
    let mut out: Vec<Source> = Vec::new();
    for f in rows.iter().flat_map(|r| &r.point.frequencies) {
        if !out.contains(&Source::Frequency(f.name.clone())) {
            out.push(Source::Frequency(f.name.clone()));
        }
    }
    for r in rows {
        for q in r.point.analytic.keys().filter(|q| r.point.simulated.contains_key(*q)) {
            if !out.contains(&Source::Compared(q.clone())) {
                out.push(Source::Compared(q.clone()));
            }
        }
    }
    let seen = |q: &String| rows.iter().any(|r| r.point.simulated.contains_key(q));
    out.extend(measured.iter().filter(|q| seen(q)).map(|q| Source::Measured(q.clone())));
    if let Some(e) = rows.iter().find_map(|r| r.point.energy.as_ref()) {
        out.extend(e.measured.keys().map(|c| Source::Equilibrium(c.clone())));
        out.extend((0..e.measured.len()).map(Source::Eigenvalue));
    }
    out
}

fn data(
    rows: &[Row],
    title: &str,
    x: Option<&str>,
    measured: &[String],
    is_angle: &dyn Fn(&str) -> bool,
) -> Result<SweepPlot, FigureError> {
    let x = x_axis(rows, x)?;
    let sources = sources(rows, measured);
    if sources.is_empty() {
        return Err(FigureError::Data(
            "the sweep compares or measures no quantity (no check, prediction, probe or energy model): nothing to draw"
                .into(),
        ));
    }
    let mut series: Vec<Series> = Vec::new();
    for r in rows.iter().filter(|r| r.point.settled) {
        let p = &r.point;
        let others: Vec<String> =
            p.inputs.iter().filter(|(k, _)| **k != x).map(|(k, v)| format!("{k} = {v:.4}")).collect();
        let label = if others.is_empty() { "settled".to_string() } else { others.join(", ") };
        let at = match series.iter().position(|(l, _)| *l == label) {
            Some(i) => i,
            None => {
                series.push((label, vec![Vec::new(); sources.len()]));
                series.len() - 1
            }
        };
        for (i, q) in sources.iter().enumerate() {
            let (a, s) = q.values(p);
            let d = s - a;
            let e = if q.angle_name().is_some_and(is_angle) { crate::mechanisms::wrap_angle(d) } else { d };
            series[at].1[i].push((p.inputs[&x], a, s, e.abs()));
        }
    }
    for (_, per_q) in &mut series {
        per_q.iter_mut().for_each(|v| v.sort_by(|a, b| a.0.total_cmp(&b.0)));
    }
    let captions = sources.iter().map(Source::caption).collect();
    let quantities = sources.iter().map(Source::name).collect();
    Ok(SweepPlot { title: title.to_string(), x, quantities, captions, series })
}

impl Plot for SweepPlot {
    fn plot<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), FigureError> {
        let d = self;
        let root = titled_page(root, &d.title, 20)?;
        let shown = d.quantities.len().min(MAX_PANELS);
        let panels = root.split_evenly((shown + 1, 1));
        let all = |f: fn(&(f64, f64, f64, f64)) -> f64, i: Option<usize>| -> Vec<f64> {
            d.series
                .iter()
                .flat_map(|(_, per_q)| per_q.iter().enumerate().filter(|(j, _)| i.is_none_or(|i| *j == i)))
                .flat_map(|(_, v)| v.iter().map(f))
                .collect()
        };
        let xs = range(&all(|p| p.0, None));
        for (i, q) in d.quantities.iter().take(shown).enumerate() {
            let mut ys = all(|p| p.1, Some(i));
            ys.extend(all(|p| p.2, Some(i)));
            ys.retain(|y| y.is_finite());
            let mut chart = ChartBuilder::on(&panels[i])
                .margin(10)
                .x_label_area_size(35)
                .y_label_area_size(80)
                .caption(d.captions[i].as_str(), ("sans-serif", 16))
                .build_cartesian_2d(xs.clone(), range(&ys))?;
            chart.configure_mesh().x_desc(d.x.as_str()).y_desc(q.as_str()).draw()?;
            for (k, (label, per_q)) in d.series.iter().enumerate() {
                let c = PALETTE[k % PALETTE.len()];
                let v = &per_q[i];
                chart
                    .draw_series(LineSeries::new(
                        v.iter().filter(|p| p.1.is_finite()).map(|p| (p.0, p.1)),
                        c.stroke_width(2),
                    ))?
                    .label(label.clone())
                    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(2)));
                chart.draw_series(
                    v.iter().filter(|p| p.2.is_finite()).map(|p| Circle::new((p.0, p.2), 4, c.filled())),
                )?;
            }
            if d.series.len() > 1 {
                chart.configure_series_labels().background_style(WHITE.mix(0.8)).border_style(BLACK).draw()?;
            }
        }
        let mut logs: Vec<f64> = all(|p| p.3.max(ERROR_FLOOR).log10(), None);
        logs.retain(|y| y.is_finite());
        let mut chart = ChartBuilder::on(&panels[shown])
            .margin(10)
            .x_label_area_size(35)
            .y_label_area_size(80)
            .caption("log10 |settled - analytic| (angles wrapped)", ("sans-serif", 16))
            .build_cartesian_2d(xs, range(&logs))?;
        chart.configure_mesh().x_desc(d.x.as_str()).y_desc("log10 |error|").draw()?;
        for (i, q) in d.quantities.iter().enumerate() {
            let c = PALETTE[i % PALETTE.len()];
            let points: Vec<(f64, f64)> = d
                .series
                .iter()
                .flat_map(|(_, per_q)| per_q[i].iter().filter(|p| p.3.is_finite()))
                .map(|p| (p.0, p.3.max(ERROR_FLOOR).log10()))
                .collect();
            chart
                .draw_series(points.iter().map(|p| Cross::new(*p, 5, c.stroke_width(2))))?
                .label(q.clone())
                .legend(move |(x, y)| Cross::new((x + 10, y), 5, c.stroke_width(2)));
        }
        chart.configure_series_labels().background_style(WHITE.mix(0.8)).border_style(BLACK).draw()?;
        Ok(())
    }
}

/// Draws the sweep `rows` of scenario `title` against axis `x` (default: the axis with the
/// most values) to `out`, PNG or SVG by its extension (written to a temporary file and
/// renamed when complete); `measured` names the quantities only measured (a probe without a
/// closed form), drawn as dots alone.
pub fn draw(
    rows: &[Row],
    (title, x): (&str, Option<&str>),
    measured: &[String],
    is_angle: &dyn Fn(&str) -> bool,
    out: &Path,
) -> Result<(), FigureError> {
    let d = data(rows, title, x, measured, is_angle)?;
    let format = Format::of(out).ok_or_else(|| FigureError::Extension(out.to_path_buf()))?;
    let size = (WIDTH_PX, PANEL_PX * (d.quantities.len().min(MAX_PANELS) as u32 + 1) + 40);
    kit::write(&[(out.to_path_buf(), format)], size, |canvas| canvas.draw(&d))
}
