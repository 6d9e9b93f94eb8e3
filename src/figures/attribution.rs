//! `tensegrity attribute --figure`: one bar per compared value, split by relaxation, each share
//! as a percentage of the model's value (values without one, a file model's largest error, and
//! values at a point some level did not settle are left out: the table and the CSV hold them),
//! the interaction in grey.

use super::kit::{self, FigureError, Format, Plot};
use crate::study::attribution::AttributionReport;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::PathBuf;

/// The figure's size \[px\].
const SIZE: (u32, u32) = (1200, 700);

/// Each relaxation's colour, in turn.
const COLOURS: [RGBColor; 6] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
];
const INTERACTION: RGBColor = RGBColor(150, 150, 150);

/// The bars: a label and the segments (colour, share in %).
struct Bars {
    title: String,
    names: Vec<String>,
    bars: Vec<(String, Vec<(usize, f64)>)>,
}

/// Writes the attribution figure of `report` into `outputs`.
pub fn write(report: &AttributionReport, outputs: &[(PathBuf, Format)]) -> Result<(), FigureError> {
    let interaction = report.relaxations.len();
    let bars = report
        .items
        .iter()
        .filter(|it| it.model.is_finite() && it.model != 0.0)
        .filter(|it| it.interaction.is_finite() && it.shares.iter().all(|s| s.is_finite()))
        .map(|it| {
            let percent = 100.0 / it.model.abs();
            let mut parts: Vec<(usize, f64)> = it.shares.iter().map(|s| s * percent).enumerate().collect();
            parts.push((interaction, it.interaction * percent));
            let at = it.point.map_or(String::new(), |p| format!(" @{p}"));
            (format!("{}{at}", it.name), parts)
        })
        .collect();
    let mut names: Vec<String> = report.relaxations.iter().map(|r| r.relaxation.name.clone()).collect();
    names.push("interaction".into());
    let figure = Bars { title: format!("What each relaxation costs the model: {}", report.scenario), names, bars };
    kit::write(outputs, SIZE, |canvas| canvas.draw(&figure))
}

impl Plot for Bars {
    fn plot<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), FigureError> {
        let area = kit::titled_page(root, &self.title, 22)?;
        let stack = |positive: bool| -> Vec<f64> {
            self.bars.iter().map(|(_, p)| p.iter().map(|(_, v)| *v).filter(|v| (*v > 0.0) == positive).sum()).collect()
        };
        let (top, bottom) = (stack(true), stack(false));
        let hi = top.iter().fold(0.0f64, |a, b| a.max(*b));
        let lo = bottom.iter().fold(0.0f64, |a, b| a.min(*b));
        let pad = 0.05 * (hi - lo).max(1e-12);
        let n = self.bars.len().max(1) as f64;
        let mut chart = ChartBuilder::on(&area)
            .margin(20)
            .x_label_area_size(120)
            .y_label_area_size(80)
            .build_cartesian_2d(-0.5..n - 0.5, (lo - pad)..(hi + pad))?;
        let labels: Vec<String> = self.bars.iter().map(|(l, _)| l.clone()).collect();
        chart
            .configure_mesh()
            .disable_x_mesh()
            .x_labels(self.bars.len().max(1))
            .x_label_formatter(&|x| labels.get(x.round() as usize).cloned().unwrap_or_default())
            .x_label_style(("sans-serif", 13).into_font().transform(FontTransform::Rotate90))
            .y_desc("share of the model's value [%]")
            .draw()?;
        for (k, name) in self.names.iter().enumerate() {
            kit::swatch(&mut chart, name, colour(k, self.names.len()))?;
        }
        for (i, (_, parts)) in self.bars.iter().enumerate() {
            let (mut up, mut down) = (0.0, 0.0);
            for (k, v) in parts {
                let base = if *v >= 0.0 { &mut up } else { &mut down };
                let x = i as f64;
                let rect =
                    Rectangle::new([(x - 0.35, *base), (x + 0.35, *base + v)], colour(*k, self.names.len()).filled());
                chart.draw_series(std::iter::once(rect))?;
                *base += v;
            }
        }
        chart.configure_series_labels().background_style(WHITE).border_style(BLACK).draw()?;
        Ok(())
    }
}

/// Relaxation `k`'s colour; the last of `n` is the interaction's.
fn colour(k: usize, n: usize) -> RGBColor {
    if k + 1 == n {
        INTERACTION
    } else {
        COLOURS[k % COLOURS.len()]
    }
}
