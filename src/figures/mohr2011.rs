//! mohr2011's workspace figures: Fig. 4 (horizontal slices of the kinematic workspace, Eq.
//! 17-18, at several heights), Fig. 5 (the slice z = 3 m of the static and kinematic
//! workspaces) and Fig. 6 (the paper's 3D view of the static workspace, Eq. 29-31, drawn as two
//! vertical slices), each with small dynamics grids from
//! `scenarios/mohr2011/workspace_grid_small.toml`.

use super::kit::{
    cell_runs, legend_box, legend_panel, read_scenario, rimmed_dot, swatch, titled_page, zero_contour, Chart,
    FigureError, Glyph, Plot,
};
use super::Figure;
use crate::mechanisms::mohr2011::analytic::{self as mohr, Region};
use crate::scenario::{self, Scenario};
use nalgebra::Vector3;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;

/// mohr2011's figures.
pub(super) const FIGURES: &[Figure] = &[
    Figure {
        name: "mohr2011-fig4",
        description: "mohr2011 Fig. 4: horizontal slices z = 1-5 m of the kinematic workspace (l_b = 2, l_o = 3 l_b) with the static boundary and the base triangle, with 9 x 9 points per slice settled by the dynamics",
        size: FIG4_SIZE,
        draw: |canvas| canvas.draw(&fig4_data()?),
    },
    Figure {
        name: "mohr2011-fig5",
        description: "mohr2011 Fig. 5: the horizontal slice z = 3 m of the static and kinematic workspaces (l_b = 2, l_o = 3 l_b), with a 9 x 9 grid classified by the dynamics",
        size: FIG5_SIZE,
        draw: |canvas| canvas.draw(&fig5_data()?),
    },
    Figure {
        name: "mohr2011-fig6",
        description: "mohr2011 Fig. 6: the static workspace (l_b = 2, l_o = 3 l_b) in the vertical slices x = 0 and y = 0, with 9 x 9 points per slice settled by the dynamics",
        size: FIG6_SIZE,
        draw: |canvas| canvas.draw(&fig6_data()?),
    },
];

/// The paper's parameters of Figs. 4-6: l_b = 2 m, l_o = l_max = 3 l_b, l_min = 0.
fn paper_params() -> mohr::Params {
    mohr::Params::PAPER
}

/// Cells per side of an analytic slice.
const CELLS: usize = 140;
/// Half-width of a horizontal slice [m] and of its dynamics grid [m].
const HALF_WIDTH_M: f64 = 4.0;
const GRID_HALF_WIDTH_M: f64 = 3.5;
/// Points per side of a dynamics grid (9 x 9 per slice).
const GRID_COUNT: usize = 9;
/// Threads of a dynamics sweep.
const SWEEP_JOBS: usize = 2;
/// Settle time per point [s] (the template allows 30 s). A point with a cable pair slack never
/// comes to rest (the platform keeps a free direction), so it runs the whole time: 12 s instead
/// of 30 s makes the grids 2.5 times faster. Every point of these grids that settles does so
/// within 11.1 s (z = 3 m, near the outer boundary); the rest did not settle in 30 s either.
const SETTLE_MAX_TIME_S: f64 = 12.0;

/// One grid point as the dynamics classified it.
#[derive(Clone, Copy)]
struct Settled {
    /// Centroid [m] asked for.
    at: Vector3<f64>,
    /// Inside the static workspace by the analytic model (no cable pair predicted slack).
    analytic_static: bool,
    /// Inside by the dynamics: settled, every cable taut, every check within tolerance.
    dynamics_static: bool,
}

/// A dynamics grid: the settled points and the points that cannot be assembled (a spring
/// longer than l_o, Eq. 18), with the agreement of the static classifications [%].
struct Grid {
    points: Vec<Settled>,
    not_assembled: Vec<Vector3<f64>>,
}

impl Grid {
    /// The points where the dynamics and the analytic model classify alike.
    fn agreeing(&self) -> usize {
        self.points.iter().filter(|q| q.analytic_static == q.dynamics_static).count()
    }

    fn agreement_percent(&self) -> f64 {
        100.0 * self.agreeing() as f64 / self.points.len().max(1) as f64
    }
}

/// The points of `grids` that agree, and all their (assembled) points.
fn tally<'a>(grids: impl Iterator<Item = &'a Grid>) -> (usize, usize) {
    grids.fold((0, 0), |(agree, points), g| (agree + g.agreeing(), points + g.points.len()))
}

/// `workspace_grid_small.toml` with the lines that start with the keys replaced (key, line).
fn small_grid_scenario(edits: &[(&str, String)]) -> Result<Scenario, FigureError> {
    let path = Path::new("scenarios/mohr2011/workspace_grid_small.toml");
    let mut text = read_scenario(path)?;
    for (key, line) in edits {
        text = replace_line(&text, key, line)?;
    }
    Ok(scenario::parse(path, &text)?)
}

/// Runs `workspace_grid_small.toml` with its grid replaced by `grid` (a TOML inline table of
/// x, y, z ranges).
fn dynamics_grid(grid: &str) -> Result<Grid, FigureError> {
    let sc = small_grid_scenario(&[
        ("grid = {", format!("grid = {grid}")),
        ("max_time = ", format!("max_time = {SETTLE_MAX_TIME_S:?}")),
    ])?;
    let centroid = |v: &crate::mechanisms::Values| Vector3::new(v["x"], v["y"], v["z"]);
    // The grid's centroids are converted to the cable lengths rho (Eq. 15) before the check
    // that drops them; the direct kinematics (Eq. 12-14) gives them back.
    let p = paper_params();
    let not_assembled =
        sc.skipped_points.iter().filter_map(|(v, _)| mohr::dkp(&p, &[v["rho1"], v["rho2"], v["rho3"]])).collect();
    let (rows, _) = crate::study::sweep::sweep(&sc, SWEEP_JOBS, None, None, &|_, _| {})?;
    let points = rows
        .iter()
        .map(|r| {
            let q = &r.point;
            Settled {
                at: centroid(&q.analytic),
                analytic_static: q.expected_slack.as_ref().is_some_and(|e| e.is_empty()),
                dynamics_static: q.settled && q.slack_cables.is_empty() && q.within_tolerance,
            }
        })
        .collect();
    Ok(Grid { points, not_assembled })
}

/// `src` with the line that starts with `key` replaced by `line`.
fn replace_line(src: &str, key: &str, line: &str) -> Result<String, FigureError> {
    let start = src
        .find(&format!("\n{key}"))
        .ok_or_else(|| FigureError::Data(format!("workspace_grid_small.toml has no '{key}'")))?
        + 1;
    let end = start + src[start..].find('\n').unwrap_or(src.len() - start);
    Ok(format!("{}{line}{}", &src[..start], &src[end..]))
}

/// `{ from = a, to = b, count = n }`.
fn range_toml(from: f64, to: f64, count: usize) -> String {
    format!("{{ from = {from}, to = {to}, count = {count} }}")
}

/// A continuous function whose zero set is the boundary of the static workspace: the smallest
/// of the Eq. 29-31 margins (in units of kappa / l_o^2) and of the Eq. 18 margin (l_o - l_i)/l_o.
fn static_boundary_function(p: &mohr::Params, c: &Vector3<f64>) -> f64 {
    let l_max = mohr::spring_lengths(p, c).iter().copied().fold(0.0, f64::max);
    let kinematic = (p.lo - l_max) / p.lo;
    if kinematic <= 0.0 {
        return kinematic;
    }
    let unit = p.kappa / (p.lo * p.lo);
    let statics = mohr::static_margins(p, c).iter().copied().fold(f64::INFINITY, f64::min) / unit;
    kinematic.min(statics)
}

/// Colours of the regions and markers.
const KINEMATIC: RGBColor = RGBColor(170, 215, 255);
const STATIC_LINE: RGBColor = RGBColor(0, 60, 160);
const BASE: RGBColor = RGBColor(0, 0, 0);
const HELD: RGBColor = RGBColor(0, 170, 0);
const NOT_HELD: RGBColor = RGBColor(220, 0, 0);
const NOT_ASSEMBLED: RGBColor = RGBColor(110, 110, 110);
const DISAGREE: RGBColor = RGBColor(0, 0, 0);

// ---------------------------------------------------------------------------
// Fig. 4: horizontal slices of the kinematic workspace.
// ---------------------------------------------------------------------------

/// Heights of the slices [m] (the paper's Fig. 4 shows "various heights"; l_o = 6 m).
const FIG4_HEIGHTS_M: [f64; 5] = [1.0, 2.0, 3.0, 4.0, 5.0];
const FIG4_SIZE: (u32, u32) = (1350, 960);

struct Slice {
    z: f64,
    /// (x, y) of the cell centres inside the kinematic workspace.
    cells: Vec<(f64, f64)>,
    /// The static workspace's boundary (Eq. 29-31 with Eq. 18).
    static_boundary: Vec<Vec<(f64, f64)>>,
    /// Areas [m^2] of the kinematic and the static workspace in the slice.
    areas_m2: (f64, f64),
    grid: Grid,
}

struct Fig4 {
    p: mohr::Params,
    cell: f64,
    slices: Vec<Slice>,
}

fn fig4_data() -> Result<Fig4, FigureError> {
    let p = paper_params();
    let cell = 2.0 * HALF_WIDTH_M / CELLS as f64;
    let g = GRID_HALF_WIDTH_M;
    let grid = format!(
        "{{ x = {}, y = {}, z = {} }}",
        range_toml(-g, g, GRID_COUNT),
        range_toml(-g, g, GRID_COUNT),
        range_toml(FIG4_HEIGHTS_M[0], FIG4_HEIGHTS_M[FIG4_HEIGHTS_M.len() - 1], FIG4_HEIGHTS_M.len())
    );
    let all = dynamics_grid(&grid)?;
    let slices = FIG4_HEIGHTS_M
        .iter()
        .map(|&z| {
            let mut cells = Vec::new();
            for i in 0..CELLS {
                for j in 0..CELLS {
                    let (x, y) = (-HALF_WIDTH_M + (i as f64 + 0.5) * cell, -HALF_WIDTH_M + (j as f64 + 0.5) * cell);
                    if mohr::classify(&p, &Vector3::new(x, y, z)).region != Region::OutsideKinematic {
                        cells.push((x, y));
                    }
                }
            }
            let static_boundary = zero_contour(
                &|x, y| static_boundary_function(&p, &Vector3::new(x, y, z)),
                -HALF_WIDTH_M..HALF_WIDTH_M,
                -HALF_WIDTH_M..HALF_WIDTH_M,
                CELLS,
            );
            let at_z = |c: &Vector3<f64>| (c.z - z).abs() < 1e-9;
            let grid = Grid {
                points: all.points.iter().filter(|q| at_z(&q.at)).copied().collect(),
                not_assembled: all.not_assembled.iter().filter(|c| at_z(c)).copied().collect(),
            };
            Slice { z, cells, static_boundary, areas_m2: mohr::slice_areas(&p, z, HALF_WIDTH_M, CELLS), grid }
        })
        .collect();
    Ok(Fig4 { p, cell, slices })
}

/// The base triangle A1A2A3 (Eq. 1), closed.
fn base_triangle(p: &mohr::Params) -> Vec<(f64, f64)> {
    let a = mohr::base_nodes(p);
    vec![(a[0].x, a[0].y), (a[1].x, a[1].y), (a[2].x, a[2].y), (a[0].x, a[0].y)]
}

impl Plot for Fig4 {
    fn plot<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), FigureError> {
        let d = self;
        let (agree, points) = tally(d.slices.iter().map(|s| &s.grid));
        let root = titled_page(
            root,
            &format!(
                "mohr2011 Fig. 4: horizontal slices of the kinematic workspace (l_b = {} m, l_min = 0, l_max = l_o = {} m)",
                d.p.lb, d.p.lo
            ),
            20,
        )?;
        let areas = root.split_evenly((2, 3));
        let h = HALF_WIDTH_M;
        for (area, s) in areas.iter().zip(&d.slices) {
            let mut chart = ChartBuilder::on(area)
                .margin(8)
                .x_label_area_size(35)
                .y_label_area_size(45)
                .caption(
                    format!(
                        "z = {} m: kinematic {:.1} m^2 (static {:.1} m^2); dynamics agree {:.0} %",
                        s.z,
                        s.areas_m2.0,
                        s.areas_m2.1,
                        s.grid.agreement_percent()
                    ),
                    ("sans-serif", 14),
                )
                .build_cartesian_2d(-h..h, -h..h)?;
            chart.configure_mesh().disable_mesh().x_desc("x [m]").y_desc("y [m]").draw()?;
            chart.draw_series(cell_runs(s.cells.iter().map(|(x, y)| (*x, *y, KINEMATIC)), (d.cell, d.cell)))?;
            for line in &s.static_boundary {
                chart.draw_series(DashedLineSeries::new(line.iter().copied(), 6, 4, STATIC_LINE.stroke_width(2)))?;
            }
            chart.draw_series(LineSeries::new(base_triangle(&d.p), BASE.stroke_width(2)))?;
            draw_grid(&mut chart, &s.grid, &|c| (c.x, c.y))?;
        }
        let entries = vec![
            (Glyph::Fill(KINEMATIC), "kinematic workspace (Eq. 17-18, z > 0)".to_string()),
            (Glyph::Dashed(STATIC_LINE, 2), "boundary of the static workspace (Eq. 29-31; Fig. 5)".to_string()),
            (Glyph::Line(BASE, 2), "base triangle A1A2A3 (Eq. 1)".to_string()),
            (Glyph::Dot(HELD), "dynamics: held there, every cable taut, within 1e-9".to_string()),
            (Glyph::Cross(NOT_HELD), "dynamics: assembled, but a cable pair went slack".to_string()),
            (Glyph::Ring(DISAGREE), format!("differs from the analytic class: not at rest in {SETTLE_MAX_TIME_S} s")),
            (Glyph::Dot(NOT_ASSEMBLED), "cannot be assembled: a spring longer than l_o".to_string()),
            (Glyph::Note, format!("9 x 9 points per slice: {agree} of {points} assembled points agree")),
            (Glyph::Note, "with the analytic static classification (the others lie on".to_string()),
            (Glyph::Note, "a boundary). Every assembled point lies in the kinematic".to_string()),
            (Glyph::Note, "workspace, and none outside.".to_string()),
        ];
        let legend_area = &areas[FIG4_HEIGHTS_M.len()];
        legend_panel(&legend_area.margin(40, 40, 10, 0), &entries, 1, 14)?;
        Ok(())
    }
}

/// The dynamics' markers of `grid`, placed by `at`.
fn draw_grid<'a, DB: DrawingBackend + 'a>(
    chart: &mut Chart<'a, DB>,
    grid: &Grid,
    at: &dyn Fn(&Vector3<f64>) -> (f64, f64),
) -> Result<(), FigureError> {
    chart.draw_series(grid.not_assembled.iter().map(|c| Circle::new(at(c), 3, NOT_ASSEMBLED.filled())))?;
    chart.draw_series(grid.points.iter().filter(|q| q.dynamics_static).map(|q| rimmed_dot(at(&q.at), 5, HELD, 1)))?;
    chart.draw_series(
        grid.points.iter().filter(|q| !q.dynamics_static).map(|q| Cross::new(at(&q.at), 5, NOT_HELD.stroke_width(2))),
    )?;
    chart.draw_series(
        grid.points
            .iter()
            .filter(|q| q.dynamics_static != q.analytic_static)
            .map(|q| Circle::new(at(&q.at), 10, DISAGREE.stroke_width(2))),
    )?;
    Ok(())
}

// ---------------------------------------------------------------------------
// Fig. 5: the horizontal slice z = 3 m of the static and kinematic workspaces.
// ---------------------------------------------------------------------------

/// Size of Fig. 5 in pixels.
const FIG5_SIZE: (u32, u32) = (900, 820);
/// Height of the slice [m].
const FIG5_Z_M: f64 = 3.0;
/// Cells per side of the slice.
const FIG5_CELLS: usize = 120;

struct Fig5 {
    /// Analytic class per cell centre: (x, y, region).
    cells: Vec<(f64, f64, Region)>,
    cell: f64,
    /// Dynamics: (x, y, inside the static workspace by the dynamics).
    points: Vec<(f64, f64, bool)>,
    agreement: f64,
}

fn fig5_data() -> Result<Fig5, FigureError> {
    let p = mohr::Params { lb: 2.0, lo: 6.0, kappa: 10.0, l_min: 0.0 };
    let cell = 2.0 * HALF_WIDTH_M / FIG5_CELLS as f64;
    let mut cells = Vec::new();
    for i in 0..FIG5_CELLS {
        for j in 0..FIG5_CELLS {
            let (x, y) = (-HALF_WIDTH_M + (i as f64 + 0.5) * cell, -HALF_WIDTH_M + (j as f64 + 0.5) * cell);
            cells.push((x, y, mohr::classify(&p, &Vector3::new(x, y, FIG5_Z_M)).region));
        }
    }
    // The dynamics: the small workspace grid scenario, at this slice, 9 x 9 points.
    let g = GRID_HALF_WIDTH_M;
    let (across, at_z) = (range_toml(-g, g, GRID_COUNT), range_toml(FIG5_Z_M, FIG5_Z_M, 1));
    let sc = small_grid_scenario(&[("grid = {", format!("grid = {{ x = {across}, y = {across}, z = {at_z} }}"))])?;
    let (rows, summary) = crate::study::sweep::sweep(&sc, SWEEP_JOBS, None, None, &|_, _| {})?;
    let points = rows
        .iter()
        .map(|r| {
            let q = &r.point;
            (q.analytic["x"], q.analytic["y"], q.settled && q.slack_cables.is_empty() && q.within_tolerance)
        })
        .collect();
    Ok(Fig5 { cells, cell, points, agreement: summary.workspace.map_or(f64::NAN, |w| w.agreement_percent) })
}

impl Plot for Fig5 {
    fn plot<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), FigureError> {
        let d = self;
        root.fill(&WHITE)?;
        let h = HALF_WIDTH_M;
        let mut chart = ChartBuilder::on(root)
            .margin(15)
            .x_label_area_size(45)
            .y_label_area_size(55)
            .caption(
                format!(
                    "mohr2011, slice z = {FIG5_Z_M} m (l_b = 2, l_o = 6): analytic classes, dynamics' verdict (agreement {:.1} %)",
                    d.agreement
                ),
                ("sans-serif", 17),
            )
            .build_cartesian_2d(-h..h, -h..h)?;
        chart.configure_mesh().x_desc("x [m]").y_desc("y [m]").draw()?;
        let static_c = RGBColor(170, 215, 255);
        let kin_c = RGBColor(235, 235, 235);
        let colours = d
            .cells
            .iter()
            .filter(|(_, _, r)| *r != Region::OutsideKinematic)
            .map(|(x, y, r)| (*x, *y, if *r == Region::Static { static_c } else { kin_c }));
        chart.draw_series(cell_runs(colours, (d.cell, d.cell)))?;
        // Legend entries for the background classes.
        swatch(&mut chart, "static workspace (Eq. 29-31)", static_c)?;
        swatch(&mut chart, "kinematic only (a cable pair slack)", kin_c)?;
        chart
            .draw_series(
                d.points
                    .iter()
                    .filter(|(_, _, inside)| *inside)
                    .map(|(x, y, _)| Circle::new((*x, *y), 6, GREEN.filled())),
            )?
            .label("dynamics: settled, every cable taut, within 1e-9")
            .legend(|(x, y)| Circle::new((x + 8, y), 5, GREEN.filled()));
        chart
            .draw_series(
                d.points
                    .iter()
                    .filter(|(_, _, inside)| !*inside)
                    .map(|(x, y, _)| Cross::new((*x, *y), 6, RED.stroke_width(2))),
            )?
            .label("dynamics: a cable slack or not settled")
            .legend(|(x, y)| Cross::new((x + 8, y), 5, RED.stroke_width(2)));
        legend_box(&mut chart, SeriesLabelPosition::LowerRight, 13)?;
        Ok(())
    }
}

// ---------------------------------------------------------------------------
// Fig. 6: the static workspace, in two vertical slices.
// ---------------------------------------------------------------------------

/// The two vertical planes of Fig. 6: x = 0 (the mechanism's plane of symmetry, through A3 and
/// the Z axis) and y = 0 (through the centroid O, parallel to A1A2).
#[derive(Clone, Copy)]
enum Plane {
    X0,
    Y0,
}

impl Plane {
    /// The centroid at horizontal coordinate `h` and height `z` [m].
    fn point(self, h: f64, z: f64) -> Vector3<f64> {
        match self {
            Plane::X0 => Vector3::new(0.0, h, z),
            Plane::Y0 => Vector3::new(h, 0.0, z),
        }
    }
    /// The horizontal coordinate of a centroid in this plane.
    fn horizontal(self, c: &Vector3<f64>) -> f64 {
        match self {
            Plane::X0 => c.y,
            Plane::Y0 => c.x,
        }
    }
    fn name(self) -> &'static str {
        match self {
            Plane::X0 => "x = 0",
            Plane::Y0 => "y = 0",
        }
    }
    fn axis(self) -> &'static str {
        match self {
            Plane::X0 => "y [m]",
            Plane::Y0 => "x [m]",
        }
    }
}

/// Height of the vertical slices [m] (the kinematic workspace ends below 5.6 m) and the heights
/// of the dynamics grid [m] (z = 0 is the singular base plane, Section 4.2).
const FIG6_Z_MAX_M: f64 = 6.0;
const FIG6_GRID_Z_M: (f64, f64) = (0.6, 5.4);
const FIG6_SIZE: (u32, u32) = (1300, 860);
const FIG6_LEGEND_PX: u32 = 150;

struct VerticalSlice {
    plane: Plane,
    /// (horizontal, z, region) at the cell centres inside the kinematic workspace.
    cells: Vec<(f64, f64, Region)>,
    cell: (f64, f64),
    /// Areas [m^2] of the kinematic and the static workspace in the slice.
    areas_m2: (f64, f64),
    /// Highest point [m] of the static workspace in the slice.
    static_top_m: f64,
    grid: Grid,
}

struct Fig6 {
    p: mohr::Params,
    slices: Vec<VerticalSlice>,
}

fn fig6_data() -> Result<Fig6, FigureError> {
    let p = paper_params();
    let cell = (2.0 * HALF_WIDTH_M / CELLS as f64, FIG6_Z_MAX_M / CELLS as f64);
    let g = GRID_HALF_WIDTH_M;
    let mut slices = Vec::new();
    for plane in [Plane::X0, Plane::Y0] {
        let mut cells = Vec::new();
        let (mut kinematic, mut statics, mut static_top_m) = (0usize, 0usize, 0.0_f64);
        for i in 0..CELLS {
            for j in 0..CELLS {
                let (h, z) = (-HALF_WIDTH_M + (i as f64 + 0.5) * cell.0, (j as f64 + 0.5) * cell.1);
                let region = mohr::classify(&p, &plane.point(h, z)).region;
                if region != Region::OutsideKinematic {
                    kinematic += 1;
                    if region == Region::Static {
                        statics += 1;
                        static_top_m = static_top_m.max(z);
                    }
                    cells.push((h, z, region));
                }
            }
        }
        let fixed = range_toml(0.0, 0.0, 1);
        let across = range_toml(-g, g, GRID_COUNT);
        let (x, y) = match plane {
            Plane::X0 => (fixed, across),
            Plane::Y0 => (across, fixed),
        };
        let grid = format!("{{ x = {x}, y = {y}, z = {} }}", range_toml(FIG6_GRID_Z_M.0, FIG6_GRID_Z_M.1, GRID_COUNT));
        let area = cell.0 * cell.1;
        slices.push(VerticalSlice {
            plane,
            cells,
            cell,
            areas_m2: (kinematic as f64 * area, statics as f64 * area),
            static_top_m,
            grid: dynamics_grid(&grid)?,
        });
    }
    Ok(Fig6 { p, slices })
}

const STATIC: RGBColor = RGBColor(170, 215, 255);
const KINEMATIC_ONLY: RGBColor = RGBColor(225, 225, 225);

impl Plot for Fig6 {
    fn plot<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), FigureError> {
        let d = self;
        let root = titled_page(
            root,
            &format!(
                "mohr2011 Fig. 6: the static workspace in two vertical slices (l_b = {} m, l_o = {} m)",
                d.p.lb, d.p.lo
            ),
            20,
        )?;
        let (top, legend) = root.split_vertically(FIG6_SIZE.1 - FIG6_LEGEND_PX - 30);
        let h = HALF_WIDTH_M;
        for (area, s) in top.split_evenly((1, 2)).iter().zip(&d.slices) {
            let mut chart = ChartBuilder::on(area)
                .margin(10)
                .x_label_area_size(40)
                .y_label_area_size(50)
                .caption(
                    format!(
                        "{}: static {:.1} m^2 of kinematic {:.1} m^2, up to z = {:.2} m; dynamics agree {:.0} %",
                        s.plane.name(),
                        s.areas_m2.1,
                        s.areas_m2.0,
                        s.static_top_m,
                        s.grid.agreement_percent()
                    ),
                    ("sans-serif", 15),
                )
                .build_cartesian_2d(-h..h, 0.0..FIG6_Z_MAX_M)?;
            chart.configure_mesh().disable_mesh().x_desc(s.plane.axis()).y_desc("z [m]").draw()?;
            let colours =
                s.cells.iter().map(|(x, z, r)| (*x, *z, if *r == Region::Static { STATIC } else { KINEMATIC_ONLY }));
            chart.draw_series(cell_runs(colours, s.cell))?;
            // The base A1A2A3 seen edge-on: its extent in this plane.
            let base: Vec<f64> = mohr::base_nodes(&d.p).iter().map(|a| s.plane.horizontal(a)).collect();
            let (lo, hi) = base.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| (a.min(*v), b.max(*v)));
            chart.draw_series(LineSeries::new([(lo, 0.0), (hi, 0.0)], BASE.stroke_width(5)))?;
            let plane = s.plane;
            draw_grid(&mut chart, &s.grid, &move |c| (plane.horizontal(c), c.z))?;
        }
        let (agree, points) = tally(d.slices.iter().map(|s| &s.grid));
        let entries = vec![
            (Glyph::Fill(STATIC), "static workspace (Eq. 17-18 and 29-31)".to_string()),
            (Glyph::Fill(KINEMATIC_ONLY), "kinematic only: a cable pair would be slack".to_string()),
            (Glyph::Line(BASE, 5), "the base triangle A1A2A3, edge-on (z = 0)".to_string()),
            (Glyph::Note, format!("9 x 9 points per slice: {agree} of {points} assembled points agree")),
            (Glyph::Dot(HELD), "dynamics: held there, every cable taut, within 1e-9".to_string()),
            (Glyph::Cross(NOT_HELD), "dynamics: assembled, but a cable pair went slack".to_string()),
            (Glyph::Ring(DISAGREE), format!("differs from the analytic class: not at rest in {SETTLE_MAX_TIME_S} s")),
            (Glyph::Dot(NOT_ASSEMBLED), "cannot be assembled: a spring longer than l_o".to_string()),
        ];
        legend_panel(&legend.margin(0, 8, 10, 10), &entries, 2, 14)?;
        Ok(())
    }
}
