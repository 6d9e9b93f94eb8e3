//! `tensegrity figure NAME`: the papers' figures, redrawn from the analytic model with the
//! dynamics' verdict overlaid, as PNG and SVG (plotters; text in the bundled DejaVu Sans).

use crate::mechanisms::ji2014::analytic as ji;
use crate::run::{run, RunOptions};
use crate::scenario;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::{Path, PathBuf};

mod furet2018;
mod ji2014;
mod manriquez2019;
mod mohr2011;
pub mod sweep;

/// The figures this command draws: (name, what it shows).
pub const FIGURES: &[(&str, &str)] = &[
    (
        "ji2014-fig2",
        "ji2014 Fig. 2: actuator workspace (theta1, L3) with det J and the singular curves i-vi of Section 4.2 as derived (which printed ones are not singular), with the 110 points of grid.toml settled by the dynamics",
    ),
    (
        "ji2014-fig3",
        "ji2014 Fig. 3: Cartesian workspace of D3 (how many stable inputs reach each point) with the images of the curves and the printed Eq. 34-37, with the settled D3 of grid.toml",
    ),
    (
        "ji2014-fig4",
        "ji2014 Fig. 4-6: energy U, torque tau and stiffness K against theta2 (L3 = 6, K1 = 100, K2 = 10, theta1 = pi/10), with the equilibrium the dynamics settled on",
    ),
    (
        "ji2014-fig7",
        "ji2014 Fig. 7: stiffness K at the stable equilibrium over the actuator workspace (colour map, contours, symmetry line), with the dynamics' torque probe at 16 points (stiffness_grid.toml)",
    ),
    (
        "ji2014-fig8",
        "ji2014 Fig. 8: stiffness K at the stable equilibrium over the Cartesian workspace of D3 (colour map, contours, the paper's symmetry line x = 0), with the dynamics' torque probe at the settled D3 of stiffness_grid.toml",
    ),
    (
        "mohr2011-fig4",
        "mohr2011 Fig. 4: horizontal slices z = 1-5 m of the kinematic workspace (l_b = 2, l_o = 3 l_b) with the static boundary and the base triangle, with 9 x 9 points per slice settled by the dynamics",
    ),
    (
        "mohr2011-fig5",
        "mohr2011 Fig. 5: the horizontal slice z = 3 m of the static and kinematic workspaces (l_b = 2, l_o = 3 l_b), with a 9 x 9 grid classified by the dynamics",
    ),
    (
        "mohr2011-fig6",
        "mohr2011 Fig. 6: the static workspace (l_b = 2, l_o = 3 l_b) in the vertical slices x = 0 and y = 0, with 9 x 9 points per slice settled by the dynamics",
    ),
    (
        "furet2018-fig4",
        "furet2018 Fig. 4: the two aspects and the singular curves (theta1 = -theta2 +- pi, Eq. 14) in the joint space (L = 1, b = 2/3), where the printed Eq. 13 differs, and Fig. 3's four solutions with non-singular paths",
    ),
    (
        "furet2018-fig5",
        "furet2018 Fig. 5: workspace regions by number of inverse solutions (2 or 4) for b = 2/5, 2/3, 9/10 (L = 1), with the paper's Fig. 3 point",
    ),
    (
        "manriquez2019-fig6",
        "manriquez2019 Fig. 6-7: the form-finding grid of Table 2 as positions of M, in 3D and in the Y-Z plane, classified by the statics, with the dynamics' verdict on 41 x 41 poses",
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

/// Draws figure `name` into `dir` as NAME.png and NAME.svg (each written to a temporary file
/// and renamed when complete, `output`); returns the files written.
pub fn draw(name: &str, dir: &Path) -> Result<Vec<PathBuf>, String> {
    register_font()?;
    std::fs::create_dir_all(dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    let (png_out, svg_out) = (dir.join(format!("{name}.png")), dir.join(format!("{name}.svg")));
    for p in [&png_out, &svg_out] {
        crate::output::check_replaceable(p)?;
    }
    let (png, svg) = (crate::output::partial_path(&png_out), crate::output::partial_path(&svg_out));
    let drawn = draw_to(name, &png, &svg);
    if let Err(e) = drawn {
        crate::output::discard(&png);
        crate::output::discard(&svg);
        return Err(e);
    }
    crate::output::commit(&png, &png_out)?;
    crate::output::commit(&svg, &svg_out)?;
    Ok(vec![png_out, svg_out])
}

/// Draws figure `name` to the files `png` and `svg`.
fn draw_to(name: &str, png: &Path, svg: &Path) -> Result<(), String> {
    let (png, svg) = (png.to_path_buf(), svg.to_path_buf());
    match name {
        "ji2014-fig4" => {
            let data = ji2014_fig4_data()?;
            ji2014_fig4_plot(BitMapBackend::new(&png, SIZE).into_drawing_area(), &data)?;
            ji2014_fig4_plot(SVGBackend::new(&svg, SIZE).into_drawing_area(), &data)?;
        }
        "ji2014-fig2" => ji2014::draw_fig2(&png, &svg)?,
        "ji2014-fig3" => ji2014::draw_fig3(&png, &svg)?,
        "ji2014-fig7" => ji2014::draw_fig7(&png, &svg)?,
        "ji2014-fig8" => ji2014::draw_fig8(&png, &svg)?,
        "mohr2011-fig4" => mohr2011::draw_fig4(&png, &svg)?,
        "mohr2011-fig6" => mohr2011::draw_fig6(&png, &svg)?,
        "furet2018-fig4" => furet2018::draw_fig4(&png, &svg)?,
        "furet2018-fig5" => {
            let data = furet2018_fig5_data()?;
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
    Ok(())
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

/// Loads and runs a scenario whose results a figure draws (findings left out); a run that
/// stopped early (divergence, bad model) is an error naming the file.
pub(super) fn run_scenario(path: &str) -> Result<(scenario::Scenario, crate::report::ScenarioReport), String> {
    let sc = scenario::load(Path::new(path)).map_err(|e| e.to_string())?;
    let report = run(&sc, &RunOptions { skip_findings: true, ..Default::default() });
    match &report.error {
        Some(e) => Err(format!("{path}: {e}")),
        None => Ok((sc, report)),
    }
}

fn ji2014_fig4_data() -> Result<Fig4, String> {
    let (sc, report) = run_scenario("scenarios/ji2014/fig4.toml")?;
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
    let root = titled_page(
        root,
        &format!(
            "ji2014, L3 = {} m, theta1 = {:.4} rad, K1 = {} N/m, K2 = {} N/m",
            d.l3, d.theta1, d.params.k1, d.params.k2
        ),
        22,
    )?;
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
    let colours = d
        .cells
        .iter()
        .filter(|(_, _, r)| *r != Region::OutsideKinematic)
        .map(|(x, y, r)| (*x, *y, if *r == Region::Static { static_c } else { kin_c }));
    chart.draw_series(cell_runs(colours, (d.cell, d.cell))).map_err(err)?;
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
    /// Dynamics at b = 2/3 (`scenarios/furet2018/workspace_grid.toml`): per end point (x, y),
    /// the number of inverse solutions the simulation reached within the checks' tolerance.
    reached: Vec<(f64, f64, usize)>,
}

/// The number of inverse solutions the dynamics reached at each end point of
/// `workspace_grid.toml` (every solution of each grid point built, settled and checked).
fn furet2018_reached_counts() -> Result<Vec<(f64, f64, usize)>, String> {
    let (_, r) = run_scenario("scenarios/furet2018/workspace_grid.toml")?;
    let mut counts: std::collections::BTreeMap<(i64, i64), (f64, f64, usize)> = Default::default();
    // Grid coordinates keyed to the micrometre.
    let key = |v: f64| (v * 1e6).round() as i64;
    for p in r.points.iter().filter(|p| p.settled && p.within_tolerance) {
        let (x, y) = (p.analytic["x"], p.analytic["y"]);
        counts.entry((key(x), key(y))).or_insert((x, y, 0)).2 += 1;
    }
    Ok(counts.into_values().collect())
}

fn furet2018_fig5_data() -> Result<FuretFig5, String> {
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
    Ok(FuretFig5 { panels, cell, reached: furet2018_reached_counts()? })
}

fn furet2018_fig5_plot<DB: DrawingBackend>(root: DrawingArea<DB, Shift>, d: &FuretFig5) -> Result<(), String> {
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| format!("drawing failed: {e:?}");
    let root =
        titled_page(root, "furet2018 (L = 1): workspace by number of inverse solutions (analytic, Eq. 6-12)", 20)?;
    let two = RGBColor(190, 220, 250);
    let four = RGBColor(250, 170, 120);
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
        let colours =
            cells.iter().filter(|c| c.2 == 2 || c.2 == 4).map(|(x, y, n)| (*x, *y, if *n == 4 { four } else { two }));
        chart.draw_series(cell_runs(colours, (d.cell, d.cell))).map_err(err)?;
        swatch(&mut chart, "2 solutions", two).map_err(err)?;
        swatch(&mut chart, "4 solutions", four).map_err(err)?;
        if (*b - 2.0 / 3.0).abs() < 1e-12 {
            chart
                .draw_series(std::iter::once(TriangleMarker::new((0.03, 1.6), 7, BLACK.filled())))
                .map_err(err)?
                .label("Fig. 3 point (0.03, 1.6): 4 solutions")
                .legend(|(x, y)| TriangleMarker::new((x + 8, y), 5, BLACK.filled()));
            for (n, label) in [(2, "dynamics: 2 solutions reached"), (4, "dynamics: 4 solutions reached")] {
                let size = if n == 4 { 5 } else { 2 };
                chart
                    .draw_series(
                        d.reached
                            .iter()
                            .filter(|r| r.2 == n)
                            .map(move |r| Circle::new((r.0, r.1), size, BLACK.filled())),
                    )
                    .map_err(err)?
                    .label(label)
                    .legend(move |(x, y)| Circle::new((x + 8, y), size, BLACK.filled()));
            }
        }
        legend_box(&mut chart, SeriesLabelPosition::UpperLeft, 12).map_err(err)?;
    }
    root.present().map_err(err)?;
    Ok(())
}

pub(crate) type Chart<'a, DB> =
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

/// A figure's page: white, with its title on top in a font of `font_px`; the area below it.
pub(crate) fn titled_page<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    title: &str,
    font_px: u32,
) -> Result<DrawingArea<DB, Shift>, String> {
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| format!("drawing failed: {e:?}");
    root.fill(&WHITE).map_err(err)?;
    root.titled(title, ("sans-serif", font_px)).map_err(err)
}

/// The chart of a workspace map on `area`: `caption` above, axes over the ranges [rad or m]
/// labelled (x, y), no grid lines (the map's cells cover it).
pub(crate) fn map_chart<'a, DB: DrawingBackend>(
    area: &'a DrawingArea<DB, Shift>,
    caption: &str,
    x: std::ops::Range<f64>,
    y: std::ops::Range<f64>,
    (x_desc, y_desc): (&str, &str),
) -> Result<Chart<'a, DB>, String> {
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| format!("drawing failed: {e:?}");
    let mut chart = ChartBuilder::on(area)
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(60)
        .caption(caption, ("sans-serif", 16))
        .build_cartesian_2d(x, y)
        .map_err(err)?;
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc(x_desc)
        .y_desc(y_desc)
        .axis_desc_style(("sans-serif", 16))
        .draw()
        .map_err(err)?;
    Ok(chart)
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
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
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
    use std::collections::HashMap;
    let n = cells + 1;
    let (hx, hy) = ((xs.end - xs.start) / cells as f64, (ys.end - ys.start) / cells as f64);
    let at = |i: usize, j: usize| (xs.start + hx * i as f64, ys.start + hy * j as f64);
    let v: Vec<f64> = (0..n * n).map(|k| f(at(k / n, k % n).0, at(k / n, k % n).1)).collect();
    let val = |i: usize, j: usize| v[i * n + j];
    // An edge: (vertical?, i, j) from node (i, j) to (i + 1, j) or (i, j + 1).
    type Edge = (bool, usize, usize);
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
    // Chain the segments into polylines through their shared edges.
    let mut by_edge: HashMap<Edge, Vec<usize>> = HashMap::new();
    for (k, (a, b)) in segments.iter().enumerate() {
        by_edge.entry(*a).or_default().push(k);
        by_edge.entry(*b).or_default().push(k);
    }
    let mut used = vec![false; segments.len()];
    let mut lines = Vec::new();
    for start in 0..segments.len() {
        if used[start] {
            continue;
        }
        used[start] = true;
        let mut chain: std::collections::VecDeque<Edge> = [segments[start].0, segments[start].1].into();
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
        lines.push(chain.iter().map(|e| crossing[e]).collect());
    }
    lines
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
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
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
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
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
