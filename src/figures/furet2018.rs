//! furet2018's figures: Fig. 4 (the singular curves and the two aspects in the joint space
//! (theta1, theta2), from the derived det J, with where the printed Eq. 13 differs) and Fig. 5
//! (the workspace by number of inverse solutions for three b).

use super::kit::{
    cell_runs, legend_box, legend_panel, map_chart, rimmed_dot, run_scenario, swatch, titled_page, zero_contour,
    FigureError, Glyph, Plot,
};
use super::Figure;
use crate::mechanisms::furet2018::analytic as furet;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::f64::consts::PI;

/// furet2018's figures.
pub(super) const FIGURES: &[Figure] = &[
    Figure {
        name: "furet2018-fig4",
        description: "furet2018 Fig. 4: the two aspects and the singular curves (theta1 = -theta2 +- pi, Eq. 14) in the joint space (L = 1, b = 2/3), where the printed Eq. 13 differs, and Fig. 3's four solutions with non-singular paths",
        size: FIG4_SIZE,
        draw: |canvas| canvas.draw(&fig4_data()?),
    },
    Figure {
        name: "furet2018-fig5",
        description: "furet2018 Fig. 5: workspace regions by number of inverse solutions (2 or 4) for b = 2/5, 2/3, 9/10 (L = 1), with the paper's Fig. 3 point",
        size: FIG5_SIZE,
        draw: |canvas| canvas.draw(&fig5_data()?),
    },
];

/// Size of Fig. 4 in pixels.
const FIG4_SIZE: (u32, u32) = (1000, 1120);
const LEGEND_PX: u32 = 290;
/// Cells per side of the joint-space map over [-pi, pi]^2.
const CELLS: usize = 240;
/// Samples along a singular curve.
const CURVE_SAMPLES: usize = 720;
/// Grid of the search for a non-singular path (as in `findings`), and samples per path
/// segment for its smallest |det J|.
const PATH_GRID: usize = 192;
const PATH_SAMPLES: usize = 200;
/// theta2 [rad] where FINDINGS.md compares Eq. 13 as printed with det J on the first family.
const FOLD_CHECK_THETA2: f64 = 0.5;

struct Fig4 {
    p: furet::Params,
    /// (theta1, theta2, aspect, the printed Eq. 13 has the other sign) at cell centres.
    cells: Vec<(f64, f64, i8, bool)>,
    cell: f64,
    /// Area fractions of the + aspect and of the cells where Eq. 13 as printed has the wrong sign.
    plus_fraction: f64,
    printed_wrong_sign: f64,
    /// The first family theta1 = -theta2 +- pi and Eq. 14, as polylines in the square.
    folded: Vec<Vec<(f64, f64)>>,
    eq14: Vec<Vec<(f64, f64)>>,
    /// Largest |det J| [m^2/rad^2] on the two families (should be rounding).
    det_on_curves: f64,
    /// The zero set of Eq. 13 as printed.
    printed_zero: Vec<Vec<(f64, f64)>>,
    /// Eq. 13 as printed [m^4/rad^2] on the first family at theta2 = FOLD_CHECK_THETA2.
    printed_on_fold: f64,
    /// The inverse solutions of Fig. 3 and a non-singular path between the two of each aspect,
    /// with its smallest |det J|.
    solutions: Vec<furet::IkSolution>,
    paths: Vec<(Vec<(f64, f64)>, f64)>,
    /// Dynamics (`ik_solutions.toml`): the settled (theta1, theta2) of each solution, and the
    /// largest distance of its end point from (0.03, 1.6) [m].
    settled: Vec<(f64, f64)>,
    settled_max_miss_m: f64,
    /// Dynamics (`cuspidal_path.toml`): the smallest det J along the simulated path from
    /// solution 1 to solution 3, and the end point's distance from (0.03, 1.6) [m].
    cusp_min_det: f64,
    cusp_miss_m: f64,
}

/// Runs a furet2018 scenario for the figure's dynamics overlay: it must meet its declared
/// verdict (the modules' interference fails on purpose; everything the figure draws passes).
fn run_as_declared(path: &str) -> Result<crate::report::ScenarioReport, FigureError> {
    let (_, r) = run_scenario(path)?;
    if r.as_expected != Some(true) {
        return Err(FigureError::Verdict { path: path.to_string(), failures: format!("{:?}", r.failures) });
    }
    Ok(r)
}

/// Splits a sampled curve where it wraps around the square (a jump larger than pi).
fn split_at_wraps(points: impl Iterator<Item = (f64, f64)>) -> Vec<Vec<(f64, f64)>> {
    let mut lines: Vec<Vec<(f64, f64)>> = vec![Vec::new()];
    for q in points {
        let current = lines.last_mut().unwrap();
        if current.last().is_some_and(|l: &(f64, f64)| (l.0 - q.0).abs() > PI || (l.1 - q.1).abs() > PI) {
            lines.push(vec![q]);
        } else {
            current.push(q);
        }
    }
    lines.into_iter().filter(|l| l.len() > 1).collect()
}

/// Maps an unwrapped joint-space path into the square, split where it wraps.
fn wrapped(path: &[(f64, f64)]) -> Vec<Vec<(f64, f64)>> {
    // Densify first so that the split happens next to the edge.
    const STEPS: usize = 100;
    let dense = path.windows(2).flat_map(|w| {
        (0..STEPS).map(move |k| {
            let s = k as f64 / STEPS as f64;
            (w[0].0 + s * (w[1].0 - w[0].0), w[0].1 + s * (w[1].1 - w[0].1))
        })
    });
    let last = path.last().copied().into_iter();
    split_at_wraps(dense.chain(last).map(|(a, b)| (furet::wrap_angle(a), furet::wrap_angle(b))))
}

fn fig4_data() -> Result<Fig4, FigureError> {
    let p = furet::Params::PAPER;
    let cell = 2.0 * PI / CELLS as f64;
    let mut cells = Vec::with_capacity(CELLS * CELLS);
    for i in 0..CELLS {
        for j in 0..CELLS {
            let (t1, t2) = (-PI + (i as f64 + 0.5) * cell, -PI + (j as f64 + 0.5) * cell);
            let det = furet::det_jacobian(&p, t1, t2);
            let printed = furet::det_jacobian_eq13_as_printed(&p, t1, t2);
            cells.push((t1, t2, furet::aspect(&p, t1, t2), (printed > 0.0) != (det > 0.0)));
        }
    }
    let n = cells.len() as f64;
    let plus_fraction = cells.iter().filter(|c| c.2 > 0).count() as f64 / n;
    let printed_wrong_sign = cells.iter().filter(|c| c.3).count() as f64 / n;
    let theta2s = || (0..=CURVE_SAMPLES).map(|k| -PI + 2.0 * PI * k as f64 / CURVE_SAMPLES as f64);
    let folded = split_at_wraps(theta2s().map(|t2| (furet::singular_theta1_folded(t2), t2)));
    let eq14 = split_at_wraps(theta2s().map(|t2| (furet::singular_theta1_eq14(&p, t2), t2)));
    let det_on_curves = folded
        .iter()
        .chain(&eq14)
        .flatten()
        .map(|(t1, t2)| furet::det_jacobian(&p, *t1, *t2).abs())
        .fold(0.0, f64::max);
    let printed_zero = zero_contour(&|t1, t2| furet::det_jacobian_eq13_as_printed(&p, t1, t2), -PI..PI, -PI..PI, CELLS);
    let printed_on_fold =
        furet::det_jacobian_eq13_as_printed(&p, furet::singular_theta1_folded(FOLD_CHECK_THETA2), FOLD_CHECK_THETA2);
    let (x, y) = furet::PAPER_FIG3_POINT;
    let solutions = furet::inverse_kinematics(&p, x, y);
    let paths = [1i8, -1]
        .iter()
        .filter_map(|a| {
            let pair: Vec<_> = solutions.iter().filter(|s| s.aspect == *a).collect();
            let [s, t] = pair[..] else { return None };
            let path = furet::nonsingular_path(&p, (s.theta1, s.theta2), (t.theta1, t.theta2), PATH_GRID)?;
            let clearance = furet::min_abs_det_along(&p, &path, PATH_SAMPLES);
            Some((path, clearance))
        })
        .collect();
    let (x, y) = furet::PAPER_FIG3_POINT;
    let miss = |v: &crate::mechanisms::Values| (v["x"] - x).hypot(v["y"] - y);
    let ik = run_as_declared("scenarios/furet2018/ik_solutions.toml")?;
    let settled = ik.points.iter().map(|q| (q.simulated["theta1"], q.simulated["theta2"])).collect();
    let settled_max_miss_m = ik.points.iter().map(|q| miss(&q.simulated)).fold(0.0, f64::max);
    let cusp = run_as_declared("scenarios/furet2018/cuspidal_path.toml")?;
    let cusp_min_det = cusp.trajectory_ranges.get("detJ").map_or(f64::NAN, |r| r.min);
    let cusp_miss_m = cusp.points.last().map_or(f64::NAN, |q| miss(&q.simulated));
    Ok(Fig4 {
        p,
        cells,
        cell,
        plus_fraction,
        printed_wrong_sign,
        folded,
        eq14,
        det_on_curves,
        printed_zero,
        printed_on_fold,
        solutions,
        paths,
        settled,
        settled_max_miss_m,
        cusp_min_det,
        cusp_miss_m,
    })
}

const PLUS: RGBColor = RGBColor(198, 219, 239);
const MINUS: RGBColor = RGBColor(253, 208, 162);
/// Darkening of the cells where the printed Eq. 13 has the other sign.
const WRONG_SIGN_SHADE: f64 = 0.22;
const FOLDED: RGBColor = RGBColor(0, 0, 0);
const EQ14: RGBColor = RGBColor(180, 0, 0);
const PRINTED: RGBColor = RGBColor(130, 0, 170);
const PATH: RGBColor = RGBColor(0, 110, 0);

/// `colour` darkened by `shade` (0: unchanged, 1: black).
fn darken(colour: RGBColor, shade: f64) -> RGBColor {
    let f = |c: u8| (c as f64 * (1.0 - shade)).round() as u8;
    RGBColor(f(colour.0), f(colour.1), f(colour.2))
}

impl Plot for Fig4 {
    fn plot<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), FigureError> {
        let d = self;
        let root = titled_page(
            root,
            &format!(
                "furet2018 Fig. 4: singular curves and aspects in the joint space (L = {} m, b = {:.3} m)",
                d.p.l, d.p.b
            ),
            20,
        )?;
        let (top, legend) = root.split_vertically(FIG4_SIZE.1 - LEGEND_PX - 30);
        let mut chart = map_chart(
            &top,
            "colour: sign of det J (derived from Eq. 3); crosses: the dynamics' settled solutions",
            -PI..PI,
            -PI..PI,
            ("theta1 [rad]", "theta2 [rad]"),
        )?;
        let colours = d.cells.iter().map(|(t1, t2, aspect, wrong)| {
            let base = if *aspect > 0 { PLUS } else { MINUS };
            (*t1, *t2, if *wrong { darken(base, WRONG_SIGN_SHADE) } else { base })
        });
        chart.draw_series(cell_runs(colours, (d.cell, d.cell)))?;
        for line in &d.printed_zero {
            chart.draw_series(DashedLineSeries::new(line.iter().copied(), 7, 5, PRINTED.stroke_width(2)))?;
        }
        for line in &d.folded {
            chart.draw_series(LineSeries::new(line.iter().copied(), FOLDED.stroke_width(3)))?;
        }
        for line in &d.eq14 {
            chart.draw_series(LineSeries::new(line.iter().copied(), EQ14.stroke_width(3)))?;
        }
        for (path, _) in &d.paths {
            for line in wrapped(path) {
                chart.draw_series(LineSeries::new(line, PATH.stroke_width(2)))?;
            }
        }
        chart.draw_series(
            d.solutions
                .iter()
                .map(|s| rimmed_dot((s.theta1, s.theta2), 7, if s.aspect > 0 { WHITE } else { BLACK }, 2)),
        )?;
        chart.draw_series(d.settled.iter().map(|(t1, t2)| Cross::new((*t1, *t2), 11, RED.stroke_width(2))))?;
        legend_panel(&legend.margin(0, 8, 10, 10), &d.legend(), 1, 13)?;
        Ok(())
    }
}

impl Fig4 {
    /// Fig. 4's legend: the aspects, the curves, the solutions and the dynamics.
    fn legend(&self) -> Vec<(Glyph, String)> {
        let d = self;
        let clearances: Vec<String> = d.paths.iter().map(|(_, c)| format!("{c:.4}")).collect();
        vec![
            (Glyph::Fill(PLUS), format!("aspect det J > 0: {:.1} % of the square", 100.0 * d.plus_fraction)),
            (Glyph::Fill(MINUS), format!("aspect det J < 0: {:.1} %", 100.0 * (1.0 - d.plus_fraction))),
            (Glyph::Line(FOLDED, 3), "theta1 = -theta2 +- pi (Sec. 3): folded back, end point at the origin".to_string()),
            (
                Glyph::Line(EQ14, 3),
                format!("Eq. 14: ICRs aligned with the end point; |det J| <= {:.1e} on both curves", d.det_on_curves),
            ),
            (
                Glyph::Dashed(PRINTED, 2),
                "zero set of Eq. 13 as printed: not det J = 0 (wrong signs and l1^2 for l1 l2)".to_string(),
            ),
            (
                Glyph::Fill(darken(PLUS, WRONG_SIGN_SHADE)),
                format!(
                    "darker: Eq. 13 as printed has the other sign ({:.1} % of the square)",
                    100.0 * d.printed_wrong_sign
                ),
            ),
            (
                Glyph::Note,
                format!(
                    "On the folded line at theta2 = {FOLD_CHECK_THETA2} rad, Eq. 13 as printed gives {:.7} instead of 0.",
                    d.printed_on_fold
                ),
            ),
            (Glyph::Dot(WHITE), "Fig. 3's inverse solutions at (0.03, 1.6) m in the + aspect".to_string()),
            (Glyph::Dot(BLACK), "... and in the - aspect: two in each (cuspidal)".to_string()),
            (
                Glyph::Line(PATH, 2),
                format!("non-singular paths between them, smallest |det J| {} m^2/rad^2", clearances.join(" and ")),
            ),
            (
                Glyph::Cross(RED),
                format!(
                    "dynamics: each solution driven to and settled, end point within {:.1e} m of (0.03, 1.6)",
                    d.settled_max_miss_m
                ),
            ),
            (
                Glyph::Note,
                format!(
                    "Dynamics along the + aspect's path (cuspidal_path.toml): det J >= {:.4}, end point back within {:.1e} m.",
                    d.cusp_min_det, d.cusp_miss_m
                ),
            ),
        ]
    }
}

// ---------------------------------------------------------------------------
// Fig. 5: the workspace by number of inverse solutions, for three b.
// ---------------------------------------------------------------------------

/// Size of Fig. 5 in pixels.
const FIG5_SIZE: (u32, u32) = (1500, 560);

/// The b values of furet2018's Fig. 5 (L = 1).
const FIG5_B: [f64; 3] = [2.0 / 5.0, 2.0 / 3.0, 9.0 / 10.0];

/// Cells per side of a furet2018 solution-count map over [-2L, 2L]^2.
const FIG5_CELLS: usize = 160;

/// One panel of Fig. 5: b, the cells (x, y, count) and the area fractions with 2 and 4 solutions.
type Fig5Panel = (f64, Vec<(f64, f64, usize)>, (f64, f64));

struct Fig5 {
    /// Per b: (b, cells (x, y, count), area fractions (2, 4)).
    panels: Vec<Fig5Panel>,
    cell: f64,
    /// Dynamics at b = 2/3 (`scenarios/furet2018/workspace_grid.toml`): per end point (x, y),
    /// the number of inverse solutions the simulation reached within the checks' tolerance.
    reached: Vec<(f64, f64, usize)>,
}

/// The number of inverse solutions the dynamics reached at each end point of
/// `workspace_grid.toml` (every solution of each grid point built, settled and checked).
fn fig5_reached_counts() -> Result<Vec<(f64, f64, usize)>, FigureError> {
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

fn fig5_data() -> Result<Fig5, FigureError> {
    use crate::mechanisms::furet2018::analytic as furet;
    let half = 2.0;
    let cell = 2.0 * half / FIG5_CELLS as f64;
    let panels = FIG5_B
        .iter()
        .map(|&b| {
            let p = furet::Params { l: 1.0, b };
            let mut cells = Vec::new();
            for i in 0..FIG5_CELLS {
                for j in 0..FIG5_CELLS {
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
    Ok(Fig5 { panels, cell, reached: fig5_reached_counts()? })
}

impl Plot for Fig5 {
    fn plot<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), FigureError> {
        let d = self;
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
                .build_cartesian_2d(-2.0..2.0, -2.0..2.8)?;
            chart.configure_mesh().disable_mesh().x_desc("x [m]").y_desc("y [m]").draw()?;
            let colours = cells
                .iter()
                .filter(|c| c.2 == 2 || c.2 == 4)
                .map(|(x, y, n)| (*x, *y, if *n == 4 { four } else { two }));
            chart.draw_series(cell_runs(colours, (d.cell, d.cell)))?;
            swatch(&mut chart, "2 solutions", two)?;
            swatch(&mut chart, "4 solutions", four)?;
            if (*b - 2.0 / 3.0).abs() < 1e-12 {
                chart
                    .draw_series(std::iter::once(TriangleMarker::new((0.03, 1.6), 7, BLACK.filled())))?
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
                        )?
                        .label(label)
                        .legend(move |(x, y)| Circle::new((x + 8, y), size, BLACK.filled()));
                }
            }
            legend_box(&mut chart, SeriesLabelPosition::UpperLeft, 12)?;
        }
        Ok(())
    }
}
