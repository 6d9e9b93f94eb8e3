//! manriquez2019 Fig. 6-7: the form-finding grid (Table 2) as the positions of the platform
//! point M, in 3D (Fig. 6) and in the Y-Z plane (Fig. 7), classified by the analytic statics
//! (Eq. 18-23 with Eq. 26-27 as read) and by the dynamics (the platform released at rest at
//! each pose: `scenarios/manriquez2019/form_finding_grid.toml`).

use super::kit::{legend_box, range, read_scenario, titled_page, Chart, FigureError, Plot};
use super::Figure;
use crate::mechanisms::manriquez2019::{analytic, params_of};
use crate::scenario;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;

/// manriquez2019's figures.
pub(super) const FIGURES: &[Figure] = &[Figure {
    name: "manriquez2019-fig6",
    description: "manriquez2019 Fig. 6-7: the form-finding grid of Table 2 as positions of M, in 3D and in the Y-Z plane, classified by the statics, with the dynamics' verdict on 41 x 41 poses",
    size: SIZE,
    draw: |canvas| canvas.draw(&data()?),
}];

/// The figure's size in pixels: the 3D view and the Y-Z plane side by side.
const SIZE: (u32, u32) = (1500, 700);

/// The dynamics overlay takes every `DYNAMICS_STRIDE`-th value of Table 2's 121 per axis
/// (41 x 41 poses, the diagonal and the centre included): the full grid is `tensegrity sweep`'s
/// job (19 s, BENCHMARKS.md).
const DYNAMICS_STRIDE: usize = 3;

/// Extra height above the Y-Z plot for the legend, as a fraction of the data's height.
const LEGEND_HEADROOM: f64 = 0.3;

/// mm per m: the paper draws its workspace in mm.
const MM_PER_M: f64 = 1e3;

struct Data {
    /// Analytic: M [mm] and the statics' verdict, over the whole grid.
    analytic: Vec<([f64; 3], bool)>,
    /// Dynamics: M [mm] and whether the platform settled there (with both cables taut).
    dynamics: Vec<([f64; 3], bool)>,
    /// Agreement of the two verdicts over the dynamics' poses [%].
    agreement_percent: f64,
}

fn m_mm(p: &analytic::Params, t1: f64, t2: f64) -> [f64; 3] {
    let m = analytic::points(p, t1, t2).m * MM_PER_M;
    [m.x, m.y, m.z]
}

fn data() -> Result<Data, FigureError> {
    let path = Path::new("scenarios/manriquez2019/form_finding_grid.toml");
    let text = read_scenario(path)?;
    let full = "count = 121";
    if text.matches(full).count() != 2 {
        return Err(FigureError::Data(format!("{}: expected Table 2's grid of 121 x 121", path.display())));
    }
    let coarse = format!("count = {}", (121 - 1) / DYNAMICS_STRIDE + 1);
    let sc = scenario::parse(path, &text.replace(full, &coarse))?;
    let m = sc.mechanism();
    let p = params_of(&crate::mechanisms::with_defaults(m.as_ref(), &sc.params));
    let analytic = analytic::paper_grid()
        .into_iter()
        .map(|(t1, t2)| (m_mm(&p, t1, t2), analytic::statics(&p, t1, t2).equilibrium))
        .collect();
    let (rows, summary) = crate::study::sweep::sweep(&sc, 2, None, None, &|_, _| {})?;
    let dynamics = rows
        .iter()
        .map(|r| {
            let q = &r.point;
            (m_mm(&p, q.inputs["theta1"], q.inputs["theta2"]), q.settled && q.within_tolerance)
        })
        .collect();
    Ok(Data { analytic, dynamics, agreement_percent: summary.workspace.map_or(f64::NAN, |w| w.agreement_percent) })
}

/// The padded range of coordinate `k` of the points.
fn bounds(points: &[([f64; 3], bool)], k: usize) -> std::ops::Range<f64> {
    range(&points.iter().map(|(q, _)| q[k]).collect::<Vec<_>>())
}

impl Plot for Data {
    fn plot<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), FigureError> {
        let d = self;
        let root = titled_page(
            root,
            &format!(
                "manriquez2019 Fig. 6-7: form-finding grid (Table 2, 121 x 121), point M; dynamics on 41 x 41 poses agree at {:.1} %",
                d.agreement_percent
            ),
            19,
        )?;
        let (left, right) = root.split_horizontally(SIZE.0 / 2);
        let equilibrium = RGBColor(220, 40, 40);
        let not_equilibrium = RGBColor(60, 90, 220);
        let (xr, yr, zr) = (bounds(&d.analytic, 0), bounds(&d.analytic, 1), bounds(&d.analytic, 2));

        // Fig. 6: the 3D workspace.
        let mut c3 = ChartBuilder::on(&left)
            .margin(20)
            .caption("Fig. 6: 3D workspace of M, axes x (350-400), y, z [mm], statics' verdict", ("sans-serif", 16))
            .build_cartesian_3d(xr.clone(), yr.clone(), zr.clone())?;
        c3.with_projection(|mut pb| {
            pb.yaw = 0.6;
            pb.pitch = 0.35;
            pb.scale = 0.85;
            pb.into_matrix()
        });
        c3.configure_axes().label_style(("sans-serif", 12)).draw()?;
        c3.draw_series(d.analytic.iter().map(|(q, eq)| {
            Circle::new((q[0], q[1], q[2]), 1, if *eq { equilibrium } else { not_equilibrium }.filled())
        }))?;

        // Fig. 7: the Y-Z plane, with the dynamics' verdict.
        let mut c2: Chart<DB> = ChartBuilder::on(&right)
            .margin(20)
            .x_label_area_size(45)
            .y_label_area_size(60)
            .caption("Fig. 7: Y-Z plane, analytic and dynamics", ("sans-serif", 16))
            // Headroom above the workspace for the legend.
            .build_cartesian_2d(yr, zr.start..zr.end + LEGEND_HEADROOM * (zr.end - zr.start))?;
        c2.configure_mesh().x_desc("y of M [mm]").y_desc("z of M [mm]").draw()?;
        let n_eq = d.analytic.iter().filter(|(_, e)| *e).count();
        c2.draw_series(
            d.analytic.iter().filter(|(_, e)| *e).map(|(q, _)| Circle::new((q[1], q[2]), 1, equilibrium.filled())),
        )?
        .label(format!("statics: equilibrium ({n_eq} of {})", d.analytic.len()))
        .legend(move |(x, y)| Circle::new((x + 8, y), 4, equilibrium.filled()));
        c2.draw_series(
            d.analytic.iter().filter(|(_, e)| !*e).map(|(q, _)| Circle::new((q[1], q[2]), 1, not_equilibrium.filled())),
        )?
        .label(format!("statics: no equilibrium ({})", d.analytic.len() - n_eq))
        .legend(move |(x, y)| Circle::new((x + 8, y), 4, not_equilibrium.filled()));
        let settled = d.dynamics.iter().filter(|(_, s)| *s).count();
        c2.draw_series(
            d.dynamics.iter().filter(|(_, s)| *s).map(|(q, _)| Circle::new((q[1], q[2]), 4, BLACK.stroke_width(1))),
        )?
        .label(format!("dynamics: settled where released ({settled} of {})", d.dynamics.len()))
        .legend(|(x, y)| Circle::new((x + 8, y), 4, BLACK.stroke_width(1)));
        c2.draw_series(
            d.dynamics.iter().filter(|(_, s)| !*s).map(|(q, _)| Cross::new((q[1], q[2]), 5, BLACK.stroke_width(2))),
        )?
        .label("dynamics: drifts away (theta1 = theta2: cable map singular)")
        .legend(|(x, y)| Cross::new((x + 8, y), 5, BLACK.stroke_width(2)));
        legend_box(&mut c2, SeriesLabelPosition::UpperLeft, 12)?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    /// The agreement on the 41 x 41 overlay: every pose but the 40 of the singular diagonal
    /// (the centre is skipped) settles where released, as the statics say.
    #[test]
    fn the_overlay_disagrees_only_on_the_singular_diagonal() {
        let d = super::data().unwrap();
        assert_eq!(d.analytic.len(), 14641);
        assert_eq!(d.dynamics.len(), 41 * 41 - 1);
        let drifting = d.dynamics.iter().filter(|(_, s)| !*s).count();
        assert_eq!(drifting, 40);
        assert!((d.agreement_percent - 100.0 * 1640.0 / 1680.0).abs() < 1e-9, "{}", d.agreement_percent);
    }
}
