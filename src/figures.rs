//! `tensegrity figure NAME`: the papers' figures, redrawn from the analytic model with the
//! dynamics' verdict overlaid, as PNG and SVG (plotters; text in the bundled DejaVu Sans).

use crate::mechanisms::ji2014::analytic as ji;
use crate::run::{run, RunOptions};
use crate::scenario;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::{Path, PathBuf};

mod manriquez2019;

/// The figures this command draws: (name, what it shows).
pub const FIGURES: &[(&str, &str)] = &[
    (
        "ji2014-fig4",
        "ji2014 Fig. 4-6: energy U, torque tau and stiffness K against theta2 (L3 = 6, K1 = 100, K2 = 10, theta1 = pi/10), with the equilibrium the dynamics settled on",
    ),
    (
        "furet2018-fig5",
        "furet2018 Fig. 5: workspace regions by number of inverse solutions (2 or 4) for b = 2/5, 2/3, 9/10 (L = 1), with the paper's Fig. 3 point",
    ),
    (
        "manriquez2019-fig6",
        "manriquez2019 Fig. 6-7: the form-finding grid of Table 2 as positions of M, in 3D and in the Y-Z plane, classified by the statics, with the dynamics' verdict on 41 x 41 poses",
    ),
    (
        "mohr2011-fig5",
        "mohr2011 Fig. 5: the horizontal slice z = 3 m of the static and kinematic workspaces (l_b = 2, l_o = 3 l_b), with a 9 x 9 grid classified by the dynamics",
    ),
];

/// Cells per side of an analytic workspace map.
const MAP_CELLS: usize = 120;

/// Samples of a curve against theta2.
const CURVE_SAMPLES: usize = 721;

/// Figure size in pixels.
const SIZE: (u32, u32) = (900, 1100);

static FONT: &[u8] = include_bytes!("../assets/fonts/DejaVuSans.ttf");

fn register_font() -> Result<(), String> {
    plotters::style::register_font("sans-serif", FontStyle::Normal, FONT)
        .map_err(|_| "the bundled font is invalid".to_string())
}

/// Draws figure `name` into `dir` as NAME.png and NAME.svg; returns the files written.
pub fn draw(name: &str, dir: &Path) -> Result<Vec<PathBuf>, String> {
    register_font()?;
    std::fs::create_dir_all(dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    let png = dir.join(format!("{name}.png"));
    let svg = dir.join(format!("{name}.svg"));
    match name {
        "ji2014-fig4" => {
            let data = ji2014_fig4_data()?;
            ji2014_fig4_plot(BitMapBackend::new(&png, SIZE).into_drawing_area(), &data)?;
            ji2014_fig4_plot(SVGBackend::new(&svg, SIZE).into_drawing_area(), &data)?;
        }
        "furet2018-fig5" => {
            let data = furet2018_fig5_data();
            furet2018_fig5_plot(BitMapBackend::new(&png, (1500, 560)).into_drawing_area(), &data)?;
            furet2018_fig5_plot(SVGBackend::new(&svg, (1500, 560)).into_drawing_area(), &data)?;
        }
        "mohr2011-fig5" => {
            let data = mohr2011_fig5_data()?;
            mohr2011_fig5_plot(BitMapBackend::new(&png, MAP_SIZE).into_drawing_area(), &data)?;
            mohr2011_fig5_plot(SVGBackend::new(&svg, MAP_SIZE).into_drawing_area(), &data)?;
        }
        "manriquez2019-fig6" => {
            let data = manriquez2019::data()?;
            manriquez2019::plot(BitMapBackend::new(&png, manriquez2019::SIZE).into_drawing_area(), &data)?;
            manriquez2019::plot(SVGBackend::new(&svg, manriquez2019::SIZE).into_drawing_area(), &data)?;
        }
        other => {
            let known: Vec<_> = FIGURES.iter().map(|(n, _)| *n).collect();
            return Err(format!("unknown figure '{other}' (expected one of: {})", known.join(", ")));
        }
    }
    Ok(vec![png, svg])
}

struct Fig4 {
    theta2: Vec<f64>,
    u: Vec<f64>,
    tau: Vec<f64>,
    k: Vec<f64>,
    /// Analytic equilibria: (theta2, stable).
    equilibria: Vec<(f64, bool)>,
    /// Where the dynamics settled (theta2), from `scenarios/ji2014/fig4.toml`.
    simulated: f64,
    params: ji::Params,
    l3: f64,
    theta1: f64,
}

fn ji2014_fig4_data() -> Result<Fig4, String> {
    let sc = scenario::load(Path::new("scenarios/ji2014/fig4.toml")).map_err(|e| e.to_string())?;
    let report = run(&sc, &RunOptions::default());
    let point = report.points.first().ok_or("the fig4 scenario settled no point")?;
    if !point.settled {
        return Err("the fig4 scenario did not settle".into());
    }
    let params = ji::Params { l: sc.params["L"], k1: sc.params["K1"], k2: sc.params["K2"] };
    let (l3, theta1) = (point.inputs["L3"], point.inputs["theta1"]);
    let theta2: Vec<f64> = (0..CURVE_SAMPLES)
        .map(|i| -std::f64::consts::PI + std::f64::consts::TAU * i as f64 / (CURVE_SAMPLES - 1) as f64)
        .collect();
    Ok(Fig4 {
        u: theta2.iter().map(|t| ji::potential_energy(&params, l3, theta1, *t)).collect(),
        tau: theta2.iter().map(|t| ji::torque(&params, l3, theta1, *t)).collect(),
        k: theta2.iter().map(|t| ji::stiffness(&params, l3, theta1, *t)).collect(),
        equilibria: ji::equilibria(&params, l3, theta1).iter().map(|e| (e.theta2, e.stable)).collect(),
        simulated: point.simulated["theta2"],
        theta2,
        params,
        l3,
        theta1,
    })
}

fn range(v: &[f64]) -> std::ops::Range<f64> {
    let (lo, hi) = v.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| (a.min(*x), b.max(*x)));
    let pad = 0.05 * (hi - lo).max(1e-12);
    (lo - pad)..(hi + pad)
}

fn ji2014_fig4_plot<DB: DrawingBackend>(root: DrawingArea<DB, Shift>, d: &Fig4) -> Result<(), String> {
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| format!("drawing failed: {e:?}");
    root.fill(&WHITE).map_err(err)?;
    let root = root
        .titled(
            &format!(
                "ji2014, L3 = {} m, theta1 = {:.4} rad, K1 = {} N/m, K2 = {} N/m",
                d.l3, d.theta1, d.params.k1, d.params.k2
            ),
            ("sans-serif", 22),
        )
        .map_err(err)?;
    let panels = root.split_evenly((3, 1));
    let curves: [(&str, &str, &Vec<f64>, RGBColor, SeriesLabelPosition); 3] = [
        ("U [J] (Eq. 4)", "energy", &d.u, BLUE, SeriesLabelPosition::UpperRight),
        ("tau [N m] (Eq. 41)", "torque", &d.tau, GREEN, SeriesLabelPosition::UpperRight),
        ("K [N m/rad] (Eq. 42)", "stiffness", &d.k, MAGENTA, SeriesLabelPosition::LowerRight),
    ];
    for (panel, (ylabel, what, ys, colour, legend_at)) in panels.iter().zip(curves) {
        let mut chart = ChartBuilder::on(panel)
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(70)
            .caption(format!("{what} against theta2"), ("sans-serif", 18))
            .build_cartesian_2d(-std::f64::consts::PI..std::f64::consts::PI, range(ys))
            .map_err(err)?;
        chart.configure_mesh().x_desc("theta2 [rad]").y_desc(ylabel).draw().map_err(err)?;
        chart
            .draw_series(LineSeries::new(d.theta2.iter().copied().zip(ys.iter().copied()), colour.stroke_width(2)))
            .map_err(err)?
            .label(format!("analytic {what}"))
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2)));
        let value_at = |t: f64| -> f64 {
            match what {
                "energy" => ji::potential_energy(&d.params, d.l3, d.theta1, t),
                "torque" => ji::torque(&d.params, d.l3, d.theta1, t),
                _ => ji::stiffness(&d.params, d.l3, d.theta1, t),
            }
        };
        for (t, stable) in &d.equilibria {
            let (label, style) = if *stable {
                ("analytic energy minimum", BLACK.filled())
            } else {
                ("analytic energy maximum", BLACK.stroke_width(2))
            };
            chart
                .draw_series(std::iter::once(Circle::new((*t, value_at(*t)), 7, style)))
                .map_err(err)?
                .label(label)
                .legend(move |(x, y)| Circle::new((x + 10, y), 5, style));
        }
        let sim = d.simulated;
        chart
            .draw_series(std::iter::once(TriangleMarker::new((sim, value_at(sim)), 9, RED.filled())))
            .map_err(err)?
            .label(format!("dynamics settled at theta2 = {sim:.9} rad"))
            .legend(|(x, y)| TriangleMarker::new((x + 10, y), 6, RED.filled()));
        legend_box(&mut chart, legend_at, 13).map_err(err)?;
    }
    root.present().map_err(err)?;
    Ok(())
}

/// Size of a workspace map in pixels.
const MAP_SIZE: (u32, u32) = (900, 820);

/// Height of the mohr2011 slice [m] and half-width of the map [m].
const MOHR_SLICE_Z_M: f64 = 3.0;
const MOHR_HALF_WIDTH_M: f64 = 4.0;

struct Fig5 {
    /// Analytic class per cell centre: (x, y, region).
    cells: Vec<(f64, f64, crate::mechanisms::mohr2011::analytic::Region)>,
    cell: f64,
    /// Dynamics: (x, y, inside the static workspace by the dynamics).
    points: Vec<(f64, f64, bool)>,
    agreement: f64,
}

fn mohr2011_fig5_data() -> Result<Fig5, String> {
    use crate::mechanisms::mohr2011::analytic as mohr;
    let p = mohr::Params { lb: 2.0, lo: 6.0, kappa: 10.0, l_min: 0.0 };
    let cell = 2.0 * MOHR_HALF_WIDTH_M / MAP_CELLS as f64;
    let mut cells = Vec::new();
    for i in 0..MAP_CELLS {
        for j in 0..MAP_CELLS {
            let (x, y) = (-MOHR_HALF_WIDTH_M + (i as f64 + 0.5) * cell, -MOHR_HALF_WIDTH_M + (j as f64 + 0.5) * cell);
            cells.push((x, y, mohr::classify(&p, &nalgebra::Vector3::new(x, y, MOHR_SLICE_Z_M)).region));
        }
    }
    // The dynamics: the small workspace grid scenario, at this slice, 9 x 9 points.
    let path = Path::new("scenarios/mohr2011/workspace_grid_small.toml");
    let src = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let start = src.find("grid = {").ok_or("workspace_grid_small.toml has no grid")?;
    let end = start + src[start..].find('\n').unwrap_or(src.len() - start);
    let grid = format!(
        "grid = {{ x = {{ from = -{h}, to = {h}, count = 9 }}, y = {{ from = -{h}, to = {h}, count = 9 }}, z = {{ from = {z}, to = {z}, count = 1 }} }}",
        h = MOHR_HALF_WIDTH_M - 0.5,
        z = MOHR_SLICE_Z_M
    );
    let text = format!("{}{}{}", &src[..start], grid, &src[end..]);
    let sc = scenario::parse(path, &text).map_err(|e| e.to_string())?;
    let (rows, summary) = crate::sweep::sweep(&sc, 2, None, None, &|_, _| {}).map_err(|e| e.to_string())?;
    let points = rows
        .iter()
        .map(|r| {
            let q = &r.point;
            (q.analytic["x"], q.analytic["y"], q.settled && q.slack_cables.is_empty() && q.within_tolerance)
        })
        .collect();
    Ok(Fig5 { cells, cell, points, agreement: summary.workspace.map_or(f64::NAN, |w| w.agreement_percent) })
}

fn mohr2011_fig5_plot<DB: DrawingBackend>(root: DrawingArea<DB, Shift>, d: &Fig5) -> Result<(), String> {
    use crate::mechanisms::mohr2011::analytic::Region;
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| format!("drawing failed: {e:?}");
    root.fill(&WHITE).map_err(err)?;
    let h = MOHR_HALF_WIDTH_M;
    let mut chart = ChartBuilder::on(&root)
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(55)
        .caption(
            format!(
                "mohr2011, slice z = {MOHR_SLICE_Z_M} m (l_b = 2, l_o = 6): analytic classes, dynamics' verdict (agreement {:.1} %)",
                d.agreement
            ),
            ("sans-serif", 17),
        )
        .build_cartesian_2d(-h..h, -h..h)
        .map_err(err)?;
    chart.configure_mesh().x_desc("x [m]").y_desc("y [m]").draw().map_err(err)?;
    let static_c = RGBColor(170, 215, 255);
    let kin_c = RGBColor(235, 235, 235);
    let half = d.cell / 2.0;
    chart
        .draw_series(d.cells.iter().filter(|(_, _, r)| *r != Region::OutsideKinematic).map(|(x, y, r)| {
            let c = if *r == Region::Static { static_c } else { kin_c };
            Rectangle::new([(x - half, y - half), (x + half, y + half)], c.filled())
        }))
        .map_err(err)?;
    // Legend entries for the background classes.
    swatch(&mut chart, "static workspace (Eq. 29-31)", static_c).map_err(err)?;
    swatch(&mut chart, "kinematic only (a cable pair slack)", kin_c).map_err(err)?;
    chart
        .draw_series(
            d.points.iter().filter(|(_, _, inside)| *inside).map(|(x, y, _)| Circle::new((*x, *y), 6, GREEN.filled())),
        )
        .map_err(err)?
        .label("dynamics: settled, every cable taut, within 1e-9")
        .legend(|(x, y)| Circle::new((x + 8, y), 5, GREEN.filled()));
    chart
        .draw_series(
            d.points
                .iter()
                .filter(|(_, _, inside)| !*inside)
                .map(|(x, y, _)| Cross::new((*x, *y), 6, RED.stroke_width(2))),
        )
        .map_err(err)?
        .label("dynamics: a cable slack or not settled")
        .legend(|(x, y)| Cross::new((x + 8, y), 5, RED.stroke_width(2)));
    legend_box(&mut chart, SeriesLabelPosition::LowerRight, 13).map_err(err)?;
    root.present().map_err(err)?;
    Ok(())
}

/// The b values of furet2018's Fig. 5 (L = 1).
const FURET_FIG5_B: [f64; 3] = [2.0 / 5.0, 2.0 / 3.0, 9.0 / 10.0];

/// Cells per side of a furet2018 solution-count map over [-2L, 2L]^2.
const FURET_MAP_CELLS: usize = 160;

struct FuretFig5 {
    /// Per b: (b, cells (x, y, count), area fractions (2, 4)).
    panels: Vec<(f64, Vec<(f64, f64, usize)>, (f64, f64))>,
    cell: f64,
}

fn furet2018_fig5_data() -> FuretFig5 {
    use crate::mechanisms::furet2018::analytic as furet;
    let half = 2.0;
    let cell = 2.0 * half / FURET_MAP_CELLS as f64;
    let panels = FURET_FIG5_B
        .iter()
        .map(|&b| {
            let p = furet::Params { l: 1.0, b };
            let mut cells = Vec::new();
            for i in 0..FURET_MAP_CELLS {
                for j in 0..FURET_MAP_CELLS {
                    let (x, y) = (-half + (i as f64 + 0.5) * cell, -half + (j as f64 + 0.5) * cell);
                    cells.push((x, y, furet::solution_count(&p, x, y)));
                }
            }
            let n = cells.iter().filter(|c| c.2 > 0 && c.2 != usize::MAX).count().max(1) as f64;
            let f2 = cells.iter().filter(|c| c.2 == 2).count() as f64 / n;
            let f4 = cells.iter().filter(|c| c.2 == 4).count() as f64 / n;
            (b, cells, (f2, f4))
        })
        .collect();
    FuretFig5 { panels, cell }
}

fn furet2018_fig5_plot<DB: DrawingBackend>(root: DrawingArea<DB, Shift>, d: &FuretFig5) -> Result<(), String> {
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| format!("drawing failed: {e:?}");
    root.fill(&WHITE).map_err(err)?;
    let root = root
        .titled("furet2018 (L = 1): workspace by number of inverse solutions (analytic, Eq. 6-12)", ("sans-serif", 20))
        .map_err(err)?;
    let two = RGBColor(190, 220, 250);
    let four = RGBColor(250, 170, 120);
    let half = d.cell / 2.0;
    for (area, (b, cells, (f2, f4))) in root.split_evenly((1, 3)).iter().zip(&d.panels) {
        let mut chart = ChartBuilder::on(area)
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(45)
            .caption(
                format!("b = {b:.3} m: 2 solutions {:.1} %, 4 solutions {:.1} %", 100.0 * f2, 100.0 * f4),
                ("sans-serif", 15),
            )
            // Headroom above the workspace for the legend.
            .build_cartesian_2d(-2.0..2.0, -2.0..2.8)
            .map_err(err)?;
        chart.configure_mesh().disable_mesh().x_desc("x [m]").y_desc("y [m]").draw().map_err(err)?;
        chart
            .draw_series(cells.iter().filter(|c| c.2 == 2 || c.2 == 4).map(|(x, y, n)| {
                let c = if *n == 4 { four } else { two };
                Rectangle::new([(x - half, y - half), (x + half, y + half)], c.filled())
            }))
            .map_err(err)?;
        swatch(&mut chart, "2 solutions", two).map_err(err)?;
        swatch(&mut chart, "4 solutions", four).map_err(err)?;
        if (*b - 2.0 / 3.0).abs() < 1e-12 {
            chart
                .draw_series(std::iter::once(TriangleMarker::new((0.03, 1.6), 7, BLACK.filled())))
                .map_err(err)?
                .label("Fig. 3 point (0.03, 1.6): 4 solutions")
                .legend(|(x, y)| TriangleMarker::new((x + 8, y), 5, BLACK.filled()));
        }
        legend_box(&mut chart, SeriesLabelPosition::UpperLeft, 12).map_err(err)?;
    }
    root.present().map_err(err)?;
    Ok(())
}

type Chart<'a, DB> =
    ChartContext<'a, DB, Cartesian2d<plotters::coord::types::RangedCoordf64, plotters::coord::types::RangedCoordf64>>;

/// A legend entry for a filled region of colour `colour` (the region itself is drawn cell by
/// cell, without a label).
fn swatch<'a, DB: DrawingBackend + 'a>(
    chart: &mut Chart<'a, DB>,
    label: &str,
    colour: RGBColor,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    chart
        .draw_series(std::iter::empty::<Rectangle<(f64, f64)>>())?
        .label(label)
        .legend(move |(x, y)| Rectangle::new([(x, y - 5), (x + 15, y + 5)], colour.filled()));
    Ok(())
}

/// The legend box of every figure: framed, on a translucent white background.
fn legend_box<'a, DB: DrawingBackend + 'a>(
    chart: &mut Chart<'a, DB>,
    position: SeriesLabelPosition,
    font_px: u32,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    chart
        .configure_series_labels()
        .position(position)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", font_px))
        .draw()
}
