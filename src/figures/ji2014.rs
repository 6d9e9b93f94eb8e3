//! ji2014's figures, redrawn from the derived model with the dynamics on top: Fig. 2-3
//! (actuator and Cartesian workspaces with the singular curves of Section 4.2 and 5.2, and the
//! points of `scenarios/ji2014/grid.toml`), Fig. 4-6 (energy, torque and stiffness against
//! theta2, with the equilibrium of `scenarios/ji2014/fig4.toml`), Fig. 7-8 (the stiffness over
//! both workspaces, and the torque probe of `scenarios/ji2014/stiffness_grid.toml`).

use super::kit::{
    cell_runs, colour_at, colour_bar, legend_box, legend_panel, map_chart, range, rimmed_dot, run_scenario,
    titled_page, zero_contour, Chart, FigureError, Glyph, Plot, LIGHT_BLUES, VIRIDIS,
};
use super::Figure;
use crate::mechanisms::ji2014::analytic as ji;
use crate::mechanisms::ji2014::PAPER_ROOT_MARK;
use plotters::coord::Shift;
use plotters::element::ComposedElement;
use plotters::prelude::*;
use std::f64::consts::PI;

/// ji2014's figures.
pub(super) const FIGURES: &[Figure] = &[
    Figure {
        name: "ji2014-fig2",
        description: "ji2014 Fig. 2: actuator workspace (theta1, L3) with det J and the singular curves i-vi of Section 4.2 as derived (which printed ones are not singular), with the 110 points of grid.toml settled by the dynamics",
        size: SIZE,
        draw: |canvas| canvas.draw(&fig2_data()?),
    },
    Figure {
        name: "ji2014-fig3",
        description: "ji2014 Fig. 3: Cartesian workspace of D3 (how many stable inputs reach each point) with the images of the curves and the printed Eq. 34-37, with the settled D3 of grid.toml",
        size: SIZE,
        draw: |canvas| canvas.draw(&fig3_data()?),
    },
    Figure {
        name: "ji2014-fig4",
        description: "ji2014 Fig. 4-6: energy U, torque tau and stiffness K against theta2 (L3 = 6, K1 = 100, K2 = 10, theta1 = pi/10), with the equilibrium the dynamics settled on",
        size: FIG4_SIZE,
        draw: |canvas| canvas.draw(&fig4_data()?),
    },
    Figure {
        name: "ji2014-fig7",
        description: "ji2014 Fig. 7: stiffness K at the stable equilibrium over the actuator workspace (colour map, contours, symmetry line), with the dynamics' torque probe at 16 points (stiffness_grid.toml)",
        size: SIZE,
        draw: |canvas| canvas.draw(&fig7_data()?),
    },
    Figure {
        name: "ji2014-fig8",
        description: "ji2014 Fig. 8: stiffness K at the stable equilibrium over the Cartesian workspace of D3 (colour map, contours, the paper's symmetry line x = 0), with the dynamics' torque probe at the settled D3 of stiffness_grid.toml",
        size: SIZE,
        draw: |canvas| canvas.draw(&fig8_data()?),
    },
];

/// Size of an actuator- or Cartesian-workspace figure in pixels.
const SIZE: (u32, u32) = (1000, 1080);
/// Height of the legend panel under the chart [px].
const LEGEND_PX: u32 = 250;
/// Width of the colour bar beside the chart [px].
const COLOUR_BAR_PX: u32 = 120;
/// Cells per side of an analytic map.
const CELLS: usize = 160;
/// Samples along an analytic curve.
const CURVE_SAMPLES: usize = 400;
/// `L3` from which curves ii and iv are scanned for their smallest `|det J|` [m] (as in
/// FINDINGS.md; `det J` is proportional to `L3`, so it vanishes at `L3 = 0` on every curve).
const DET_SCAN_L3_MIN_M: f64 = 0.3;
/// Smallest `L3` of the contour maps [m] (`det J / L3` is undefined at `L3 = 0`).
const L3_MAP_MIN_M: f64 = 1e-6;

/// One point of `scenarios/ji2014/grid.toml` as the dynamics settled it.
struct GridPoint {
    l3: f64,
    theta1: f64,
    /// Settled on the analytic branch with the stability the perturbation test found equal to
    /// the analytic sign of K.
    agrees: bool,
    /// The branch landed on is the root that Eq. 5 picks with theta2 in [0, pi].
    paper_root: bool,
    /// Settled D3 [m] and its distance from the analytic D3 [m].
    x: f64,
    y: f64,
    d3_error_m: f64,
}

fn grid_points() -> Result<(ji::Params, Vec<GridPoint>), FigureError> {
    let (sc, report) = run_scenario("scenarios/ji2014/grid.toml")?;
    let p = ji::Params { l: sc.params["L"], k1: sc.params["K1"], k2: sc.params["K2"] };
    let points = report
        .points
        .iter()
        .map(|q| GridPoint {
            l3: q.inputs["L3"],
            theta1: q.inputs["theta1"],
            agrees: q.settled && q.within_tolerance && q.stable.is_some() && q.stable == q.analytic_stable,
            paper_root: q.branch.ends_with(PAPER_ROOT_MARK),
            x: q.simulated["x"],
            y: q.simulated["y"],
            d3_error_m: (q.simulated["x"] - q.analytic["x"]).hypot(q.simulated["y"] - q.analytic["y"]),
        })
        .collect();
    Ok((p, points))
}

/// `det J` [m/rad] at the stable equilibrium (the corrected Eq. 23-24).
fn det_j_stable(p: &ji::Params, l3: f64, theta1: f64) -> f64 {
    let e = ji::equilibria(p, l3, theta1)[0];
    ji::det_jacobian_closed_form(p, l3, theta1, e.theta2)
}

struct Fig2 {
    p: ji::Params,
    l3_max: f64,
    /// (theta1, L3, det J) at cell centres.
    cells: Vec<(f64, f64, f64)>,
    cell: (f64, f64),
    det_max: f64,
    /// Curve iii (eta1 = 0, Eq. 28) and curve iv (Eq. 33) as (theta1, L3) polylines.
    curve_iii: Vec<(f64, f64)>,
    curve_iv: Vec<(f64, f64)>,
    /// Zero sets inside the workspace of the derived Phi1 (curve v, Eq. 30) and of Eq. 24 as
    /// printed, both at the paper's root of Eq. 5.
    curve_v: Vec<Vec<(f64, f64)>>,
    curve_v_printed: Vec<Vec<(f64, f64)>>,
    /// K at L3 = 0 [N m/rad]; min det J on curve ii and iv, max |det J| on curve iii [m/rad].
    k_at_l3_zero: f64,
    det_min_ii: f64,
    det_max_iii: f64,
    det_min_iv: f64,
    neutral: (f64, f64),
    v_radius_m: f64,
    points: Vec<GridPoint>,
}

fn fig2_data() -> Result<Fig2, FigureError> {
    let (p, points) = grid_points()?;
    let l3_max = ji::PAPER_L3_MAX_OVER_L * p.l;
    let cell = (PI / CELLS as f64, l3_max / CELLS as f64);
    let mut cells = Vec::with_capacity(CELLS * CELLS);
    for i in 0..CELLS {
        for j in 0..CELLS {
            let (t1, l3) = ((i as f64 + 0.5) * cell.0, (j as f64 + 0.5) * cell.1);
            cells.push((t1, l3, det_j_stable(&p, l3, t1)));
        }
    }
    let det_max = cells.iter().map(|c| c.2).fold(0.0, f64::max);
    let samples = |lo: f64, hi: f64| (0..=CURVE_SAMPLES).map(move |k| lo + (hi - lo) * k as f64 / CURVE_SAMPLES as f64);
    let curve_iii: Vec<(f64, f64)> =
        samples(0.0, l3_max).filter_map(|l3| ji::curve_iii_theta1(&p, l3).map(|t1| (t1, l3))).collect();
    let curve_iv: Vec<(f64, f64)> = samples(0.0, PI)
        .map(|t1| (t1, ji::curve_iv_l3(&p, t1)))
        .filter(|(_, l3)| (0.0..=l3_max).contains(l3))
        .collect();
    // Curve v: Phi1 = 0 (Eq. 30), as det J / L3 = Phi1 / Phi2 (Eq. 23) so that the factor eta1
    // the two share cancels (their common zero, curve iii, is drawn on its own). Derived at the
    // stable equilibrium; Eq. 24 as printed at the paper's root of Eq. 5 and at the stable one.
    let det_over_l3 = |printed: bool, paper_root: bool| {
        move |t1: f64, l3: f64| {
            let th2 = if paper_root { ji::fk_paper(&p, l3, t1).theta2 } else { ji::equilibria(&p, l3, t1)[0].theta2 };
            let det = if printed {
                ji::det_jacobian_eq23(&p, l3, t1, th2)
            } else {
                ji::det_jacobian_eq23_corrected(&p, l3, t1, th2)
            };
            det.map_or(f64::NAN, |v| v / l3)
        }
    };
    let curve_v = zero_contour(&det_over_l3(false, false), 0.0..PI, L3_MAP_MIN_M..l3_max, CELLS);
    let mut curve_v_printed = zero_contour(&det_over_l3(true, true), 0.0..PI, L3_MAP_MIN_M..l3_max, CELLS);
    curve_v_printed.extend(zero_contour(&det_over_l3(true, false), 0.0..PI, L3_MAP_MIN_M..l3_max, CELLS));
    let k_at_l3_zero = ji::equilibria(&p, 0.0, 0.0)[0].stiffness;
    let det_min_ii = samples(DET_SCAN_L3_MIN_M, l3_max)
        .flat_map(|l3| [det_j_stable(&p, l3, 0.0), det_j_stable(&p, l3, PI)])
        .map(f64::abs)
        .fold(f64::INFINITY, f64::min);
    let det_max_iii = curve_iii.iter().map(|(t1, l3)| det_j_stable(&p, *l3, *t1).abs()).fold(0.0, f64::max);
    let det_min_iv = curve_iv
        .iter()
        .filter(|(_, l3)| *l3 >= DET_SCAN_L3_MIN_M)
        .map(|(t1, l3)| det_j_stable(&p, *l3, *t1).abs())
        .fold(f64::INFINITY, f64::min);
    let d1_star = ji::neutral_point(&p);
    let v_radius_m = p.l * (p.k1 + 2.0 * p.k2) / (2.0 * (p.k1 * p.k1 + p.k1 * p.k2 + p.k2 * p.k2).sqrt());
    Ok(Fig2 {
        p,
        l3_max,
        cells,
        cell,
        det_max,
        curve_iii,
        curve_iv,
        curve_v,
        curve_v_printed,
        k_at_l3_zero,
        det_min_ii,
        det_max_iii,
        det_min_iv,
        neutral: (d1_star.x, d1_star.y),
        v_radius_m,
        points,
    })
}

/// Colours of the singular curves.
const CURVE_I: RGBColor = RGBColor(0, 0, 0);
const CURVE_II: RGBColor = RGBColor(230, 120, 0);
const CURVE_III: RGBColor = RGBColor(200, 0, 0);
const CURVE_IV: RGBColor = RGBColor(150, 0, 170);
const CURVE_V: RGBColor = RGBColor(0, 140, 60);
const CURVE_VI: RGBColor = RGBColor(90, 90, 90);
/// Markers of the dynamics.
const AGREE: RGBColor = RGBColor(255, 255, 255);
const AGREE_PAPER_ROOT: RGBColor = RGBColor(255, 200, 0);
const DISAGREE: RGBColor = RGBColor(230, 0, 0);
/// A diamond marker's corners [px].
const DIAMOND_PX: [(i32, i32); 4] = [(0, -8), (8, 0), (0, 8), (-8, 0)];

impl Plot for Fig2 {
    fn plot<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), FigureError> {
        let d = self;
        let (agree, n) = (d.points.iter().filter(|q| q.agrees).count(), d.points.len());
        let root = titled_page(
            root,
            &format!(
                "ji2014 Fig. 2: actuator workspace and singular curves (L = {} m, K1 = {} N/m, K2 = {} N/m)",
                d.p.l, d.p.k1, d.p.k2
            ),
            20,
        )?;
        let (top, legend) = root.split_vertically(SIZE.1 - LEGEND_PX - 30);
        let (plot, bar) = top.split_horizontally(SIZE.0 - COLOUR_BAR_PX);
        let mut chart = map_chart(&plot, &format!(
                    "colour: det J at the stable equilibrium (Eq. 23, corrected Eq. 24); dynamics (grid.toml): {agree} of {n} points agree ({:.1} %)",
                    100.0 * agree as f64 / n as f64
                ), -MAP_PAD_RAD..PI + MAP_PAD_RAD, -MAP_PAD_M..d.l3_max + MAP_PAD_M, ("theta1 [rad]", "L3 [m]"))?;
        let colours = d.cells.iter().map(|(t1, l3, det)| (*t1, *l3, colour_at(LIGHT_BLUES, det / d.det_max)));
        chart.draw_series(cell_runs(colours, d.cell))?;
        d.draw_curves(&mut chart)?;
        draw_grid_points(&mut chart, &d.points, &|q| (q.theta1, q.l3), 5, true)?;
        colour_bar(&bar, LIGHT_BLUES, 0.0, d.det_max, "det J [m/rad]")?;
        legend_panel(&legend.margin(0, 8, 10, 10), &d.legend(), 1, 13)?;
        Ok(())
    }
}

impl Fig2 {
    /// The curves i-vi of Section 4.2 in the actuator workspace.
    fn draw_curves<DB: DrawingBackend>(&self, chart: &mut Chart<'_, DB>) -> Result<(), FigureError> {
        let d = self;
        // Curve vi (Eq. 31) and ii (Eq. 27): the edges of the range, ii dashed (not singular).
        chart.draw_series(LineSeries::new([(0.0, d.l3_max), (PI, d.l3_max)], CURVE_VI.stroke_width(3)))?;
        for t1 in [0.0, PI] {
            chart.draw_series(DashedLineSeries::new([(t1, 0.0), (t1, d.l3_max)], 10, 6, CURVE_II.stroke_width(4)))?;
        }
        chart.draw_series(DashedLineSeries::new(d.curve_iii.iter().copied(), 10, 6, CURVE_III.stroke_width(3)))?;
        chart.draw_series(DashedLineSeries::new(d.curve_iv.iter().copied(), 10, 6, CURVE_IV.stroke_width(3)))?;
        for line in &d.curve_v {
            chart.draw_series(LineSeries::new(line.iter().copied(), CURVE_V.stroke_width(3)))?;
        }
        for line in &d.curve_v_printed {
            chart.draw_series(DashedLineSeries::new(line.iter().copied(), 6, 4, CURVE_V.stroke_width(2)))?;
        }
        // Curve i (Eq. 26), the one singular curve: drawn last among the curves.
        chart.draw_series(LineSeries::new([(0.0, 0.0), (PI, 0.0)], CURVE_I.stroke_width(4)))?;
        Ok(())
    }

    /// Fig. 2's legend: the curves and the dynamics' markers.
    fn legend(&self) -> Vec<(Glyph, String)> {
        let d = self;
        let n = d.points.len();
        let paper_roots = d.points.iter().filter(|q| q.paper_root).count();
        let v_entry = if d.curve_v.is_empty() && d.curve_v_printed.is_empty() {
            (
                Glyph::Note,
                format!(
                    "v: Phi1 = 0 (Eq. 30): |eta| = L (K1+2K2), a circle of radius {:.3} m about D1* = ({:.3}, {:.3}) m, below the X axis: not in this workspace (printed Eq. 24 neither)",
                    d.v_radius_m, d.neutral.0, d.neutral.1
                ),
            )
        } else {
            (Glyph::Line(CURVE_V, 3), "v: Phi1 = 0 (Eq. 30; dashed: Eq. 24 as printed)".to_string())
        };
        vec![
            (Glyph::Line(CURVE_I, 4), format!("i: L3 = 0 (Eq. 26): det J = 0, singular; but not free: K = {:.1} N m/rad", d.k_at_l3_zero)),
            (Glyph::Dashed(CURVE_II, 4), format!("ii: sin theta1 = 0 (Eq. 27): NOT singular, det J >= {:.3} m/rad for L3 >= {DET_SCAN_L3_MIN_M} m; only the edge of the range", d.det_min_ii)),
            (Glyph::Dashed(CURVE_III, 3), format!("iii: eta1 = 0 (Eq. 28): NOT singular, |det J| <= {:.2} m/rad (finite); Eq. 5's [0, pi] root jumps by pi here", d.det_max_iii)),
            (Glyph::Dashed(CURVE_IV, 3), format!("iv: theta1 = theta2 (Eq. 33): NOT singular, det J >= {:.3} m/rad for L3 >= {DET_SCAN_L3_MIN_M} m", d.det_min_iv)),
            v_entry,
            (Glyph::Line(CURVE_VI, 3), "vi: L3 = 2L (Eq. 31): the actuator's limit, not a singularity".to_string()),
            (Glyph::Dot(AGREE), "dynamics: settled on the energy minimum within 1e-9, stable by perturbation, as K > 0 says".to_string()),
            (Glyph::Diamond(AGREE_PAPER_ROOT), format!("the same, and the minimum is the root Eq. 5 picks in [0, pi] ({paper_roots} of {n} points)")),
            (Glyph::Cross(DISAGREE), "dynamics and analytic stability disagree, or not settled".to_string()),
            (Glyph::Note, format!("Dashed: printed singular curves that prove not singular. Elsewhere Eq. 5's [0, pi] root is the energy maximum ({} of {n} points).", n - paper_roots)),
        ]
    }
}

/// The dynamics' verdict on the points of grid.toml, placed by `at`: a white dot of `radius`
/// where it agrees (where moreover the minimum is the root Eq. 5 picks, a yellow diamond if
/// `mark_paper_root`), a red cross where it does not.
fn draw_grid_points<DB: DrawingBackend>(
    chart: &mut Chart<'_, DB>,
    points: &[GridPoint],
    at: &dyn Fn(&GridPoint) -> (f64, f64),
    radius: i32,
    mark_paper_root: bool,
) -> Result<(), FigureError> {
    let dot = |q: &&GridPoint| q.agrees && !(mark_paper_root && q.paper_root);
    chart.draw_series(points.iter().filter(dot).map(|q| rimmed_dot(at(q), radius, AGREE, 1)))?;
    if mark_paper_root {
        let diamond = |q: &&GridPoint| q.agrees && q.paper_root;
        chart.draw_series(points.iter().filter(diamond).map(|q| rimmed_diamond(at(q), AGREE_PAPER_ROOT, 1)))?;
    }
    chart.draw_series(points.iter().filter(|q| !q.agrees).map(|q| Cross::new(at(q), 7, DISAGREE.stroke_width(3))))?;
    Ok(())
}

/// A diamond marker: a filled polygon and its rim, placed at a point of the chart.
type Diamond<DB> = ComposedElement<(f64, f64), DB, Polygon<(i32, i32)>, PathElement<(i32, i32)>>;

/// A diamond marker at `at`, filled with `fill`, with a black rim `rim_px` wide.
fn rimmed_diamond<DB: DrawingBackend>(at: (f64, f64), fill: RGBColor, rim_px: u32) -> Diamond<DB> {
    EmptyElement::at(at)
        + Polygon::new(DIAMOND_PX.to_vec(), fill.filled())
        + PathElement::new([&DIAMOND_PX[..], &DIAMOND_PX[..1]].concat(), BLACK.stroke_width(rim_px))
}

/// Which equilibria of the actuator workspace reach a point of the plane.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Reach {
    /// The stable equilibrium of one input (L3, theta1).
    StableOnce,
    /// The stable equilibria of two inputs.
    StableTwice,
    /// Only the energy maximum of some input (where the paper's Eq. 5 root mostly is).
    OnlyUnstable,
}

/// How the actuator workspace (`0 <= L3 <= l3_max`, `0 <= theta1 <= pi`) reaches `(x, y)`, by
/// the closed-form inverse kinematics (Eq. 48, each solution verified by Eq. 5).
fn reach(p: &ji::Params, l3_max: f64, x: f64, y: f64) -> Option<Reach> {
    let sols: Vec<_> = ji::inverse_kinematics(p, x, y).into_iter().filter(|s| s.l3 <= l3_max).collect();
    match sols.iter().filter(|s| s.stable).count() {
        0 if !sols.is_empty() => Some(Reach::OnlyUnstable),
        0 => None,
        1 => Some(Reach::StableOnce),
        _ => Some(Reach::StableTwice),
    }
}

/// D3 [m] of the stable equilibrium of the inputs.
fn d3_stable(p: &ji::Params, l3: f64, theta1: f64) -> (f64, f64) {
    let e = ji::equilibria(p, l3, theta1)[0];
    (e.x, e.y)
}

/// Cartesian window of Fig. 3 [m]: x and y ranges (the reach circle 3L fits).
const FIG3_X_M: (f64, f64) = (-3.2, 3.2);
const FIG3_Y_M: (f64, f64) = (-1.6, 3.2);

struct Fig3 {
    p: ji::Params,
    /// (x, y, reach) at cell centres.
    cells: Vec<(f64, f64, Reach)>,
    cell: (f64, f64),
    /// Area fractions [m^2] of the three reach classes.
    areas_m2: [f64; 3],
    /// Images through the stable equilibrium of curves ii (theta1 = 0, theta1 = pi), iii, iv and
    /// vi, and of curve i (one point).
    image_ii: [Vec<(f64, f64)>; 2],
    image_iii: Vec<(f64, f64)>,
    image_iv: Vec<(f64, f64)>,
    image_vi: Vec<(f64, f64)>,
    image_i: (f64, f64),
    /// Largest |Eq. 36 as printed| / (K1 L) on the image of curve iii.
    eq36_residual: f64,
    /// Range of |D3| / L on the image of curve iv.
    iv_radius: (f64, f64),
    /// The dynamics: grid.toml's points where they settled.
    points: Vec<GridPoint>,
    /// Largest distance of a settled D3 from the analytic one, relative to L.
    max_d3_error: f64,
}

fn fig3_data() -> Result<Fig3, FigureError> {
    let (p, grid) = grid_points()?;
    let l3_max = ji::PAPER_L3_MAX_OVER_L * p.l;
    let cell = ((FIG3_X_M.1 - FIG3_X_M.0) / CELLS as f64, (FIG3_Y_M.1 - FIG3_Y_M.0) / CELLS as f64);
    let mut cells = Vec::new();
    let mut areas_m2 = [0.0; 3];
    for i in 0..CELLS {
        for j in 0..CELLS {
            let (x, y) = (FIG3_X_M.0 + (i as f64 + 0.5) * cell.0, FIG3_Y_M.0 + (j as f64 + 0.5) * cell.1);
            if let Some(r) = reach(&p, l3_max, x, y) {
                let k = match r {
                    Reach::StableOnce => 0,
                    Reach::StableTwice => 1,
                    Reach::OnlyUnstable => 2,
                };
                areas_m2[k] += cell.0 * cell.1;
                cells.push((x, y, r));
            }
        }
    }
    let samples = |lo: f64, hi: f64| (0..=CURVE_SAMPLES).map(move |k| lo + (hi - lo) * k as f64 / CURVE_SAMPLES as f64);
    let image_ii = [0.0, PI].map(|t1| samples(0.0, l3_max).map(|l3| d3_stable(&p, l3, t1)).collect());
    let image_iii: Vec<(f64, f64)> =
        samples(0.0, l3_max).filter_map(|l3| ji::curve_iii_theta1(&p, l3).map(|t1| d3_stable(&p, l3, t1))).collect();
    let iv_inputs: Vec<(f64, f64)> = samples(0.0, PI)
        .map(|t1| (t1, ji::curve_iv_l3(&p, t1)))
        .filter(|(_, l3)| (0.0..=l3_max).contains(l3))
        .collect();
    let image_iv: Vec<(f64, f64)> = iv_inputs.iter().map(|(t1, l3)| d3_stable(&p, *l3, *t1)).collect();
    let image_vi = samples(0.0, PI).map(|t1| d3_stable(&p, l3_max, t1)).collect();
    let eq36_residual =
        image_iii.iter().map(|(x, y)| ji::curve_iii_eq36_as_printed(&p, *x, *y).abs()).fold(0.0, f64::max)
            / (p.k1 * p.l);
    let radii = image_iv.iter().map(|(x, y)| x.hypot(*y) / p.l);
    let iv_radius = radii.fold((f64::INFINITY, 0.0_f64), |(lo, hi), r| (lo.min(r), hi.max(r)));
    let max_d3_error = grid.iter().map(|q| q.d3_error_m).fold(0.0, f64::max) / p.l;
    Ok(Fig3 {
        p,
        cells,
        cell,
        areas_m2,
        image_ii,
        image_iii,
        image_iv,
        image_vi,
        image_i: d3_stable(&p, 0.0, 0.0),
        eq36_residual,
        iv_radius,
        points: grid,
        max_d3_error,
    })
}

/// Background colours of Fig. 3.
const REACH_ONCE: RGBColor = RGBColor(198, 219, 239);
const REACH_TWICE: RGBColor = RGBColor(120, 175, 220);
const REACH_UNSTABLE: RGBColor = RGBColor(228, 228, 228);

/// Points along a circle of radius `r` [m] about the origin.
fn circle(r: f64) -> Vec<(f64, f64)> {
    (0..=CURVE_SAMPLES)
        .map(|k| 2.0 * PI * k as f64 / CURVE_SAMPLES as f64)
        .map(|a| (r * a.cos(), r * a.sin()))
        .collect()
}

impl Plot for Fig3 {
    fn plot<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), FigureError> {
        let d = self;
        let (agree, n) = (d.points.iter().filter(|q| q.agrees).count(), d.points.len());
        let root = titled_page(
            root,
            &format!(
                "ji2014 Fig. 3: Cartesian workspace of D3 and the images of the curves (L = {} m, K1 = {} N/m, K2 = {} N/m)",
                d.p.l, d.p.k1, d.p.k2
            ),
            19,
        )?;
        let (plot, legend) = root.split_vertically(SIZE.1 - FIG3_LEGEND_PX - 30);
        let mut chart = map_chart(
            &plot,
            &format!(
                "dynamics (grid.toml): {agree} of {n} settled D3 agree, largest distance from the analytic D3 {:.1e} L",
                d.max_d3_error
            ),
            FIG3_X_M.0..FIG3_X_M.1,
            FIG3_Y_M.0..FIG3_Y_M.1,
            ("x [m]", "y [m]"),
        )?;
        let colours = d.cells.iter().map(|(x, y, r)| {
            let c = match r {
                Reach::StableOnce => REACH_ONCE,
                Reach::StableTwice => REACH_TWICE,
                Reach::OnlyUnstable => REACH_UNSTABLE,
            };
            (*x, *y, c)
        });
        chart.draw_series(cell_runs(colours, d.cell))?;
        d.draw_curves(&mut chart)?;
        draw_grid_points(&mut chart, &d.points, &|q| (q.x, q.y), 4, false)?;
        legend_panel(&legend.margin(0, 8, 10, 10), &d.legend(), 1, 13)?;
        Ok(())
    }
}

impl Fig3 {
    /// The printed Cartesian curves and the images of the actuator-space curves.
    fn draw_curves<DB: DrawingBackend>(&self, chart: &mut Chart<'_, DB>) -> Result<(), FigureError> {
        let d = self;
        // The printed Cartesian curves (Eq. 34, 36, 37), thin dashed.
        let dashed = |pts: Vec<(f64, f64)>, c: RGBColor| DashedLineSeries::new(pts, 8, 5, c.stroke_width(2));
        chart.draw_series(dashed(circle(d.p.l), CURVE_I))?;
        chart.draw_series(dashed(circle(3.0 * d.p.l), CURVE_IV))?;
        // Eq. 36 as printed is a line: y = (2 sqrt3 K1 x + 2 sqrt3 L (K2 - K1)) / (K1 + 2 K2).
        let eq36 = |x: f64| {
            (2.0 * ji::SQRT_3 * d.p.k1 * x + 2.0 * ji::SQRT_3 * d.p.l * (d.p.k2 - d.p.k1)) / (d.p.k1 + 2.0 * d.p.k2)
        };
        let eq36_line: Vec<(f64, f64)> = (0..=CURVE_SAMPLES)
            .map(|k| FIG3_X_M.0 + (FIG3_X_M.1 - FIG3_X_M.0) * k as f64 / CURVE_SAMPLES as f64)
            .map(|x| (x, eq36(x)))
            .filter(|(_, y)| (FIG3_Y_M.0..=FIG3_Y_M.1).contains(y))
            .collect();
        chart.draw_series(dashed(eq36_line, CURVE_III))?;
        // The images of the actuator-space curves through the stable equilibrium, solid.
        for line in &d.image_ii {
            chart.draw_series(LineSeries::new(line.iter().copied(), CURVE_II.stroke_width(3)))?;
        }
        chart.draw_series(LineSeries::new(d.image_iii.iter().copied(), CURVE_III.stroke_width(4)))?;
        chart.draw_series(LineSeries::new(d.image_iv.iter().copied(), CURVE_IV.stroke_width(3)))?;
        chart.draw_series(LineSeries::new(d.image_vi.iter().copied(), CURVE_VI.stroke_width(3)))?;
        chart.draw_series(std::iter::once(TriangleMarker::new(d.image_i, 9, CURVE_I.filled())))?;
        Ok(())
    }

    /// Fig. 3's legend: the reach classes, the curves and the dynamics' markers.
    fn legend(&self) -> Vec<(Glyph, String)> {
        let d = self;
        vec![
            (
                Glyph::Fill(REACH_ONCE),
                format!("stable equilibrium of one input (L3, theta1): {:.2} m^2", d.areas_m2[0]),
            ),
            (Glyph::Fill(REACH_TWICE), format!("stable equilibrium of two inputs: {:.2} m^2", d.areas_m2[1])),
            (
                Glyph::Fill(REACH_UNSTABLE),
                format!("only an energy maximum (most of the paper's Eq. 5 roots): {:.2} m^2", d.areas_m2[2]),
            ),
            (
                Glyph::Triangle(CURVE_I),
                format!("i: L3 = 0 maps to ONE point ({:.3}, {:.3}) m", d.image_i.0, d.image_i.1),
            ),
            (
                Glyph::Dashed(CURVE_I, 2),
                "Eq. 34 as printed (x^2 + y^2 = L^2): |D3 - D1| = L, not the image of i".to_string(),
            ),
            (
                Glyph::Line(CURVE_II, 3),
                "ii: images of theta1 = 0 and theta1 = pi (curves, not the region Sec. 5.2 says)".to_string(),
            ),
            (Glyph::Line(CURVE_III, 4), "iii: image of eta1 = 0, on the line of theta2 = pi".to_string()),
            (
                Glyph::Dashed(CURVE_III, 2),
                format!(
                    "Eq. 36 as printed (assumes theta2 = 0): off by up to {:.2} K1 L on the image",
                    d.eq36_residual
                ),
            ),
            (
                Glyph::Line(CURVE_IV, 3),
                format!("iv: image of Eq. 33, |D3| = L - L3 from {:.3} to {:.3} L", d.iv_radius.0, d.iv_radius.1),
            ),
            (
                Glyph::Dashed(CURVE_IV, 2),
                "Eq. 37 as printed (x^2 + y^2 = 9 L^2): only the reach circle of the maximum".to_string(),
            ),
            (
                Glyph::Line(CURVE_VI, 3),
                "vi: image of L3 = 2L; v (Phi1 = 0) has no image: it lies outside the actuator workspace".to_string(),
            ),
            (Glyph::Dot(AGREE), "dynamics: settled D3 on the stable analytic D3 within 1e-9 L, stable".to_string()),
            (Glyph::Cross(DISAGREE), "dynamics: disagrees with the analytic stability, or not settled".to_string()),
        ]
    }
}

/// Height of Fig. 3's legend panel [px].
const FIG3_LEGEND_PX: u32 = 310;

// ---------------------------------------------------------------------------
// Fig. 4-6: energy, torque and stiffness against theta2 at one input.
// ---------------------------------------------------------------------------

/// Samples of a curve against theta2.
const FIG4_SAMPLES: usize = 721;
/// Size of Fig. 4-6 in pixels.
const FIG4_SIZE: (u32, u32) = (900, 1100);

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

fn fig4_data() -> Result<Fig4, FigureError> {
    let (sc, report) = run_scenario("scenarios/ji2014/fig4.toml")?;
    let point = report.points.first().ok_or_else(|| FigureError::Data("the fig4 scenario settled no point".into()))?;
    if !point.settled {
        return Err(FigureError::Data("the fig4 scenario did not settle".into()));
    }
    let params = ji::Params { l: sc.params["L"], k1: sc.params["K1"], k2: sc.params["K2"] };
    let (l3, theta1) = (point.inputs["L3"], point.inputs["theta1"]);
    let theta2: Vec<f64> = (0..FIG4_SAMPLES)
        .map(|i| -std::f64::consts::PI + std::f64::consts::TAU * i as f64 / (FIG4_SAMPLES - 1) as f64)
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

impl Plot for Fig4 {
    fn plot<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), FigureError> {
        let d = self;
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
                .build_cartesian_2d(-std::f64::consts::PI..std::f64::consts::PI, range(ys))?;
            chart.configure_mesh().x_desc("theta2 [rad]").y_desc(ylabel).draw()?;
            chart
                .draw_series(LineSeries::new(d.theta2.iter().copied().zip(ys.iter().copied()), colour.stroke_width(2)))?
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
                    .draw_series(std::iter::once(Circle::new((*t, value_at(*t)), 7, style)))?
                    .label(label)
                    .legend(move |(x, y)| Circle::new((x + 10, y), 5, style));
            }
            let sim = d.simulated;
            chart
                .draw_series(std::iter::once(TriangleMarker::new((sim, value_at(sim)), 9, RED.filled())))?
                .label(format!("dynamics settled at theta2 = {sim:.9} rad"))
                .legend(|(x, y)| TriangleMarker::new((x + 10, y), 6, RED.filled()));
            legend_box(&mut chart, legend_at, 13)?;
        }
        Ok(())
    }
}
// ---------------------------------------------------------------------------
// Fig. 7-8: the stiffness at the stable equilibrium, with the dynamics' probe.
// ---------------------------------------------------------------------------

/// One point of `scenarios/ji2014/stiffness_grid.toml`: the dynamics' torque probe.
struct Probe {
    l3: f64,
    theta1: f64,
    /// Settled D3 [m].
    x: f64,
    y: f64,
    /// |K_probe - K| / K, K of Eq. 42 at the stable equilibrium; infinite when the probe failed.
    rel_error: f64,
}

fn probe_points() -> Result<(ji::Params, Vec<Probe>, f64), FigureError> {
    let (sc, report) = run_scenario("scenarios/ji2014/stiffness_grid.toml")?;
    let p = ji::Params { l: sc.params["L"], k1: sc.params["K1"], k2: sc.params["K2"] };
    let probes = report
        .points
        .iter()
        .map(|q| Probe {
            l3: q.inputs["L3"],
            theta1: q.inputs["theta1"],
            x: q.simulated["x"],
            y: q.simulated["y"],
            rel_error: match (q.simulated.get("K"), q.analytic.get("K")) {
                (Some(k), Some(ka)) if q.settled => ((k - ka) / ka).abs(),
                _ => f64::INFINITY,
            },
        })
        .collect();
    let tolerance = sc.probe.as_ref().and_then(|pr| pr.tolerance).unwrap_or(f64::NAN);
    Ok((p, probes, tolerance))
}

/// Relative-error classes of the probe markers: below the first bound, below the second, above.
const PROBE_ERROR_BOUNDS: [f64; 2] = [1e-9, 1e-6];

/// Stiffness levels drawn as contour lines [N m/rad].
const K_CONTOUR_STEP: f64 = 100.0;

/// Draws the probe markers, one series per error class (white circle, white diamond, red cross).
fn draw_probes<DB: DrawingBackend>(
    chart: &mut Chart<'_, DB>,
    probes: &[Probe],
    at: &dyn Fn(&Probe) -> (f64, f64),
) -> Result<(), FigureError> {
    let [lo, hi] = PROBE_ERROR_BOUNDS;
    chart.draw_series(probes.iter().filter(|q| q.rel_error < lo).map(|q| rimmed_dot(at(q), 7, AGREE, 2)))?;
    chart.draw_series(
        probes.iter().filter(|q| (lo..hi).contains(&q.rel_error)).map(|q| rimmed_diamond(at(q), AGREE, 2)),
    )?;
    chart.draw_series(
        probes.iter().filter(|q| q.rel_error >= hi).map(|q| Cross::new(at(q), 8, DISAGREE.stroke_width(3))),
    )?;
    Ok(())
}

/// Legend entries of the probe markers, with their counts.
fn probe_entries(probes: &[Probe], tolerance: f64) -> Vec<(Glyph, String)> {
    let [lo, hi] = PROBE_ERROR_BOUNDS;
    let count = |f: &dyn Fn(f64) -> bool| probes.iter().filter(|q| f(q.rel_error)).count();
    vec![
        (
            Glyph::Dot(AGREE),
            format!("dynamics' torque probe: |K_probe - K| / K < {lo:.0e} ({} points)", count(&|e| e < lo)),
        ),
        (
            Glyph::Diamond(AGREE),
            format!("the same, {lo:.0e} to {hi:.0e} ({} points)", count(&|e| (lo..hi).contains(&e))),
        ),
        (
            Glyph::Cross(DISAGREE),
            format!(
                "the same, {hi:.0e} or more, or the probe failed ({} points; tolerance {tolerance:.0e})",
                count(&|e| e >= hi)
            ),
        ),
    ]
}

struct Fig7 {
    p: ji::Params,
    l3_max: f64,
    /// (theta1, L3, K) at cell centres.
    cells: Vec<(f64, f64, f64)>,
    cell: (f64, f64),
    /// The colour scale [N m/rad]: the smallest K rounded down to K_CONTOUR_STEP, the largest K.
    k_min: f64,
    k_max: f64,
    /// Contour lines of K, every K_CONTOUR_STEP.
    contours: Vec<Vec<(f64, f64)>>,
    /// theta1 [rad] of the line |K| is symmetric about (the direction opposite D1*).
    symmetry_theta1: f64,
    curve_iii: Vec<(f64, f64)>,
    /// Columns (theta1) of the map where K does not grow with L3, the smallest theta1 [rad] of
    /// them, and the largest L3 [m] of their minima of K.
    columns_not_growing: usize,
    falls_from_theta1: f64,
    falls_up_to_l3: f64,
    /// Share of the cells where Eq. 47 as printed is negative (the paper's root is the maximum).
    eq47_negative: f64,
    probes: Vec<Probe>,
    tolerance: f64,
}

/// K [N m/rad] at the stable equilibrium, K = (L/2)|eta| (Eq. 42 at the minimum).
fn k_stable(p: &ji::Params, l3: f64, theta1: f64) -> f64 {
    ji::equilibria(p, l3, theta1)[0].stiffness
}

fn fig7_data() -> Result<Fig7, FigureError> {
    let (p, probes, tolerance) = probe_points()?;
    let l3_max = ji::PAPER_L3_MAX_OVER_L * p.l;
    let cell = (PI / CELLS as f64, l3_max / CELLS as f64);
    let mut cells = Vec::with_capacity(CELLS * CELLS);
    let mut negative = 0usize;
    for i in 0..CELLS {
        for j in 0..CELLS {
            let (t1, l3) = ((i as f64 + 0.5) * cell.0, (j as f64 + 0.5) * cell.1);
            cells.push((t1, l3, k_stable(&p, l3, t1)));
            if ji::stiffness_eq47(&p, l3, t1) < 0.0 {
                negative += 1;
            }
        }
    }
    let k_max = cells.iter().map(|c| c.2).fold(0.0, f64::max);
    let k_min = (cells.iter().map(|c| c.2).fold(f64::INFINITY, f64::min) / K_CONTOUR_STEP).floor() * K_CONTOUR_STEP;
    let mut contours = Vec::new();
    let mut level = K_CONTOUR_STEP;
    while level < k_max {
        contours.extend(zero_contour(&|t1, l3| k_stable(&p, l3, t1) - level, 0.0..PI, 0.0..l3_max, CELLS));
        level += K_CONTOUR_STEP;
    }
    // Cells are stored column by column (theta1 outer, L3 inner).
    let not_growing: Vec<&[(f64, f64, f64)]> =
        cells.chunks(CELLS).filter(|column| column.windows(2).any(|w| w[1].2 <= w[0].2)).collect();
    let falls_from_theta1 = not_growing.iter().map(|c| c[0].0).fold(f64::INFINITY, f64::min);
    let falls_up_to_l3 =
        not_growing.iter().filter_map(|c| c.iter().min_by(|a, b| a.2.total_cmp(&b.2)).map(|m| m.1)).fold(0.0, f64::max);
    let columns_not_growing = not_growing.len();
    let d1_star = ji::neutral_point(&p);
    let curve_iii = (0..=CURVE_SAMPLES)
        .map(|k| l3_max * k as f64 / CURVE_SAMPLES as f64)
        .filter_map(|l3| ji::curve_iii_theta1(&p, l3).map(|t1| (t1, l3)))
        .collect();
    Ok(Fig7 {
        p,
        l3_max,
        cells,
        cell,
        k_min,
        k_max,
        contours,
        symmetry_theta1: (-d1_star.y).atan2(-d1_star.x),
        curve_iii,
        columns_not_growing,
        falls_from_theta1,
        falls_up_to_l3,
        eq47_negative: negative as f64 / (CELLS * CELLS) as f64,
        probes,
        tolerance,
    })
}

/// The paper's symmetry line of Fig. 7, theta1 = 0.3 rad (Section 6.2).
const PAPER_FIG7_SYMMETRY_THETA1: f64 = 0.3;
/// Height of Fig. 7's and Fig. 8's legend panel [px].
const FIG7_LEGEND_PX: u32 = 190;
/// Margins of the actuator-space charts around the workspace, so that markers on its edges show
/// whole [rad], [m].
const MAP_PAD_RAD: f64 = 0.08;
const MAP_PAD_M: f64 = 0.06;
/// Colour of the contour lines of K and of the symmetry lines.
const K_LINES: RGBColor = RGBColor(255, 255, 255);
const PAPER_LINE: RGBColor = RGBColor(255, 120, 0);
/// The white lines of the map, as the legend (on white) shows them.
const LEGEND_WHITE_LINE: RGBColor = RGBColor(150, 150, 150);

/// A line drawn over a stiffness map: points, colour, width, dashed or solid.
struct MapLine {
    points: Vec<(f64, f64)>,
    colour: RGBColor,
    width: u32,
    dashed: bool,
}

/// What Fig. 7 and Fig. 8 share: a colour map of K with its contour lines, lines over it, the
/// torque probes, a colour bar and the legend panel.
struct StiffnessMap<'a> {
    title: String,
    caption: String,
    x: std::ops::Range<f64>,
    y: std::ops::Range<f64>,
    x_desc: &'static str,
    y_desc: &'static str,
    /// (x, y, K) at the cell centres.
    cells: &'a [(f64, f64, f64)],
    cell: (f64, f64),
    k_min: f64,
    k_max: f64,
    contours: &'a [Vec<(f64, f64)>],
    lines: Vec<MapLine>,
    probes: &'a [Probe],
    /// Where a probe is drawn in the map's coordinates.
    probe_at: &'a dyn Fn(&Probe) -> (f64, f64),
    tolerance: f64,
    legend: Vec<(Glyph, String)>,
}

impl Plot for StiffnessMap<'_> {
    fn plot<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), FigureError> {
        let m = self;
        let root = titled_page(root, &m.title, 20)?;
        let (top, legend) = root.split_vertically(SIZE.1 - FIG7_LEGEND_PX - 30);
        let (plot, bar) = top.split_horizontally(SIZE.0 - COLOUR_BAR_PX);
        let mut chart = map_chart(&plot, &m.caption, m.x.clone(), m.y.clone(), (m.x_desc, m.y_desc))?;
        let colours = m.cells.iter().map(|(x, y, k)| (*x, *y, colour_at(VIRIDIS, (k - m.k_min) / (m.k_max - m.k_min))));
        chart.draw_series(cell_runs(colours, m.cell))?;
        for line in m.contours {
            chart.draw_series(LineSeries::new(line.iter().copied(), K_LINES.mix(0.6).stroke_width(1)))?;
        }
        for l in &m.lines {
            let style = l.colour.stroke_width(l.width);
            if l.dashed {
                chart.draw_series(DashedLineSeries::new(l.points.iter().copied(), 10, 6, style))?;
            } else {
                chart.draw_series(LineSeries::new(l.points.iter().copied(), style))?;
            }
        }
        draw_probes(&mut chart, m.probes, m.probe_at)?;
        colour_bar(&bar, VIRIDIS, m.k_min, m.k_max, "K [N m/rad]")?;
        let mut entries = m.legend.clone();
        entries.extend(probe_entries(m.probes, m.tolerance));
        legend_panel(&legend.margin(0, 8, 10, 10), &entries, 1, 13)?;
        Ok(())
    }
}

impl Plot for Fig7 {
    fn plot<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), FigureError> {
        let d = self;
        let max_err = d.probes.iter().map(|q| q.rel_error).fold(0.0, f64::max);
        StiffnessMap {
                title: format!(
                    "ji2014 Fig. 7: stiffness K over the actuator workspace (L = {} m, K1 = {} N/m, K2 = {} N/m)",
                    d.p.l, d.p.k1, d.p.k2
                ),
                caption: format!(
                    "colour: K = (L/2)|eta| at the stable equilibrium (Eq. 42); probe (stiffness_grid.toml): max relative error {max_err:.1e}"
                ),
                x: -MAP_PAD_RAD..PI + MAP_PAD_RAD,
                y: -MAP_PAD_M..d.l3_max + MAP_PAD_M,
                x_desc: "theta1 [rad]",
                y_desc: "L3 [m]",
                cells: &d.cells,
                cell: d.cell,
                k_min: d.k_min,
                k_max: d.k_max,
                contours: &d.contours,
                lines: vec![
                    MapLine {
                        points: vec![(d.symmetry_theta1, 0.0), (d.symmetry_theta1, d.l3_max)],
                        colour: K_LINES,
                        width: 3,
                        dashed: false,
                    },
                    MapLine {
                        points: vec![(PAPER_FIG7_SYMMETRY_THETA1, 0.0), (PAPER_FIG7_SYMMETRY_THETA1, d.l3_max)],
                        colour: PAPER_LINE,
                        width: 3,
                        dashed: true,
                    },
                    MapLine { points: d.curve_iii.clone(), colour: CURVE_III, width: 3, dashed: true },
                ],
                probes: &d.probes,
                probe_at: &|q| (q.theta1, q.l3),
                tolerance: d.tolerance,
                legend: vec![
                    (Glyph::Line(LEGEND_WHITE_LINE, 1), format!(
                        "contour lines of K every {K_CONTOUR_STEP} N m/rad. The paper: K grows with L3. It does in {} of {CELLS} columns; for theta1 > {:.2} rad it falls first, up to L3 = {:.2} m",
                        CELLS - d.columns_not_growing, d.falls_from_theta1, d.falls_up_to_l3
                    )),
                    (Glyph::Line(LEGEND_WHITE_LINE, 3), format!("theta1 = {:.4} rad: K is exactly symmetric about it (the direction opposite D1*)", d.symmetry_theta1)),
                    (Glyph::Dashed(PAPER_LINE, 3), format!("theta1 = {PAPER_FIG7_SYMMETRY_THETA1} rad: the symmetry line Section 6.2 reads off Fig. 7 (wrong)")),
                    (Glyph::Dashed(CURVE_III, 3), format!("eta1 = 0 (to its right Eq. 47 as printed is NEGATIVE, -K, as the paper's root is the maximum): {:.1} % of the map", 100.0 * d.eq47_negative)),
                ],
            }
            .plot(root)
    }
}

/// Cartesian window of Fig. 8 [m]: the stable part of Fig. 3's workspace.
const FIG8_X_M: (f64, f64) = (-2.1, 1.2);
const FIG8_Y_M: (f64, f64) = (-1.2, 1.6);
/// The paper's symmetry line of Fig. 8, x = 0 (Section 6.2).
const PAPER_FIG8_SYMMETRY_X_M: f64 = 0.0;

/// K [N m/rad] of the stable equilibrium whose D3 is `(x, y)`, from an input of the actuator
/// workspace (closed-form IK, Eq. 48); None outside the stable workspace.
fn k_at_d3(p: &ji::Params, l3_max: f64, x: f64, y: f64) -> Option<f64> {
    ji::inverse_kinematics(p, x, y).into_iter().find(|s| s.stable && s.l3 <= l3_max).map(|s| s.stiffness)
}

struct Fig8 {
    p: ji::Params,
    /// (x, y, K) at the cell centres inside the stable workspace.
    cells: Vec<(f64, f64, f64)>,
    cell: (f64, f64),
    k_min: f64,
    k_max: f64,
    contours: Vec<Vec<(f64, f64)>>,
    /// Largest |K(x, y) - K(-x, y)| / K(x, y) over the cells whose mirror image is inside too,
    /// and how many such cells there are.
    mirror_asymmetry: f64,
    mirrored_cells: usize,
    /// Columns (x) of the map, and those where K grows with y over all their cells.
    columns: usize,
    columns_growing_with_y: usize,
    probes: Vec<Probe>,
    tolerance: f64,
}

fn fig8_data() -> Result<Fig8, FigureError> {
    let (p, probes, tolerance) = probe_points()?;
    let l3_max = ji::PAPER_L3_MAX_OVER_L * p.l;
    let cell = ((FIG8_X_M.1 - FIG8_X_M.0) / CELLS as f64, (FIG8_Y_M.1 - FIG8_Y_M.0) / CELLS as f64);
    let (mut cells, mut mirror_asymmetry, mut mirrored_cells) = (Vec::new(), 0.0_f64, 0usize);
    let (mut columns, mut columns_growing_with_y) = (0usize, 0usize);
    for i in 0..CELLS {
        let x = FIG8_X_M.0 + (i as f64 + 0.5) * cell.0;
        let column: Vec<(f64, f64, f64)> = (0..CELLS)
            .map(|j| FIG8_Y_M.0 + (j as f64 + 0.5) * cell.1)
            .filter_map(|y| k_at_d3(&p, l3_max, x, y).map(|k| (x, y, k)))
            .collect();
        if column.len() > 1 {
            columns += 1;
            if column.windows(2).all(|w| w[1].2 > w[0].2) {
                columns_growing_with_y += 1;
            }
        }
        for &(x, y, k) in &column {
            if let Some(km) = k_at_d3(&p, l3_max, 2.0 * PAPER_FIG8_SYMMETRY_X_M - x, y) {
                mirrored_cells += 1;
                mirror_asymmetry = mirror_asymmetry.max((k - km).abs() / k);
            }
        }
        cells.extend(column);
    }
    let k_max = cells.iter().map(|c| c.2).fold(0.0, f64::max);
    let k_min = (cells.iter().map(|c| c.2).fold(f64::INFINITY, f64::min) / K_CONTOUR_STEP).floor() * K_CONTOUR_STEP;
    let mut contours = Vec::new();
    let mut level = k_min + K_CONTOUR_STEP;
    while level < k_max {
        let f = |x: f64, y: f64| k_at_d3(&p, l3_max, x, y).map_or(f64::NAN, |k| k - level);
        contours.extend(zero_contour(&f, FIG8_X_M.0..FIG8_X_M.1, FIG8_Y_M.0..FIG8_Y_M.1, CELLS));
        level += K_CONTOUR_STEP;
    }
    Ok(Fig8 {
        p,
        cells,
        cell,
        k_min,
        k_max,
        contours,
        mirror_asymmetry,
        mirrored_cells,
        columns,
        columns_growing_with_y,
        probes,
        tolerance,
    })
}

impl Plot for Fig8 {
    fn plot<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), FigureError> {
        let d = self;
        let max_err = d.probes.iter().map(|q| q.rel_error).fold(0.0, f64::max);
        StiffnessMap {
                title: format!(
                    "ji2014 Fig. 8: stiffness K over the Cartesian workspace (L = {} m, K1 = {} N/m, K2 = {} N/m)",
                    d.p.l, d.p.k1, d.p.k2
                ),
                caption: format!("colour: K at the stable equilibrium with D3 = (x, y) (Eq. 42, IK by Eq. 48); probe: max relative error {max_err:.1e}"),
                x: FIG8_X_M.0..FIG8_X_M.1,
                y: FIG8_Y_M.0..FIG8_Y_M.1,
                x_desc: "x [m]",
                y_desc: "y [m]",
                cells: &d.cells,
                cell: d.cell,
                k_min: d.k_min,
                k_max: d.k_max,
                contours: &d.contours,
                lines: vec![MapLine {
                    points: vec![(PAPER_FIG8_SYMMETRY_X_M, FIG8_Y_M.0), (PAPER_FIG8_SYMMETRY_X_M, FIG8_Y_M.1)],
                    colour: PAPER_LINE,
                    width: 3,
                    dashed: true,
                }],
                probes: &d.probes,
                probe_at: &|q| (q.x, q.y),
                tolerance: d.tolerance,
                legend: vec![
                    (
                        Glyph::Line(LEGEND_WHITE_LINE, 1),
                        format!(
                            "contour lines of K every {K_CONTOUR_STEP} N m/rad. The paper: for a given x, K grows with y. It does in {} of {} columns",
                            d.columns_growing_with_y, d.columns
                        ),
                    ),
                    (
                        Glyph::Dashed(PAPER_LINE, 3),
                        format!(
                            "x = 0: the paper's symmetry line; K(x, y) and K(-x, y) differ by up to {:.0} % ({} cells with both inside)",
                            100.0 * d.mirror_asymmetry,
                            d.mirrored_cells
                        ),
                    ),
                ],
            }
            .plot(root)
    }
}
