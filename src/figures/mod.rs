//! `tensegrity figure NAME`: the papers' figures, redrawn from the analytic model with the
//! dynamics' verdict overlaid, as PNG and SVG (plotters; text in the bundled DejaVu Sans).
//!
//! Each paper's figures live in its own file, `src/figures/PAPER.rs` (`ji2014.rs`,
//! `mohr2011.rs`, `furet2018.rs`, `manriquez2019.rs`), as that file's list `FIGURES`: one
//! [`Figure`] entry per figure (name, description, size in pixels, draw function). Adding a
//! figure is one entry in its paper's `FIGURES` in `src/figures/PAPER.rs` (plus its draw
//! function there); [`all`], [`find`], [`draw`] and `tensegrity figure --list` then know it. A
//! draw function computes the figure's data once and hands it to [`Canvas::draw`], the one
//! writer of both the PNG and the SVG file (`kit.rs`, with the axes, legends and colour maps
//! every figure shares). `sweep.rs` draws `tensegrity sweep --figure` with the same kit.

pub mod attribution;
mod furet2018;
mod ji2014;
mod kit;
mod manriquez2019;
mod mohr2011;
pub mod sweep;

pub use kit::Format;
pub use kit::{Canvas, FigureError, Plot};
use std::path::{Path, PathBuf};

/// A figure `tensegrity figure` draws.
pub struct Figure {
    /// The name on the command line and of its files, NAME.png and NAME.svg.
    pub name: &'static str,
    /// What it shows (`tensegrity figure --list`).
    pub description: &'static str,
    /// Width and height \[px\].
    pub size: (u32, u32),
    /// Computes the figure's data and draws it into both files of the canvas.
    pub draw: fn(&Canvas) -> Result<(), FigureError>,
}

/// Every paper's figures, in the order `--list` shows them.
const PAPERS: &[&[Figure]] = &[ji2014::FIGURES, mohr2011::FIGURES, furet2018::FIGURES, manriquez2019::FIGURES];

/// The figures this command draws.
pub fn all() -> impl Iterator<Item = &'static Figure> {
    PAPERS.iter().flat_map(|paper| paper.iter())
}

/// The figure named `name`.
pub fn find(name: &str) -> Option<&'static Figure> {
    all().find(|f| f.name == name)
}

/// Draws figure `name` into `out_dir` as NAME.png and NAME.svg (each written to a temporary
/// file and renamed when both are complete, `crate::output`); returns the files written.
pub fn draw(name: &str, out_dir: &Path) -> Result<Vec<PathBuf>, FigureError> {
    let figure = find(name).ok_or_else(|| FigureError::Unknown {
        name: name.to_string(),
        known: all().map(|f| f.name).collect::<Vec<_>>().join(", "),
    })?;
    std::fs::create_dir_all(out_dir).map_err(|source| FigureError::CreateDir { dir: out_dir.to_path_buf(), source })?;
    let files = [Format::Png, Format::Svg].map(|f| (out_dir.join(format!("{name}.{}", f.extension())), f));
    kit::write(&files, figure.size, figure.draw)?;
    Ok(files.into_iter().map(|(path, _)| path).collect())
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    /// `find` and the files NAME.png, NAME.svg need every figure to have its own name.
    #[test]
    fn every_figure_has_its_own_name() {
        let mut names: Vec<&str> = super::all().map(|f| f.name).collect();
        let count = names.len();
        names.sort_unstable();
        names.dedup();
        assert_eq!(names.len(), count, "{names:?}");
        assert!(super::all().all(|f| super::find(f.name).is_some_and(|g| std::ptr::eq(f, g))));
    }

    /// An unknown name is refused before anything is written, naming the figures there are.
    #[test]
    fn an_unknown_figure_is_refused_with_the_known_names() {
        let dir = Path::new("/nonexistent/tensegrity-figures");
        let e = super::draw("no-such-figure", dir).unwrap_err();
        assert!(matches!(e, super::FigureError::Unknown { .. }));
        assert!(e.to_string().starts_with("unknown figure 'no-such-figure' (expected one of: ji2014-fig2, "), "{e}");
        assert!(!dir.exists());
    }
}
