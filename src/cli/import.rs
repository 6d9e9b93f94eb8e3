//! `tensegrity import`: a structure from another tool's format, written as a scenario file.

use super::args::ImportFormat;
use super::{bad_input, write_output, CliError, Outcome};
use crate::import::matrices::MatrixOptions;
use crate::import::ntrt::Axes;

pub fn import(format: ImportFormat) -> Result<Outcome, CliError> {
    match format {
        ImportFormat::Ntrt { file, out, keep_axes } => {
            let axes = if keep_axes { Axes::Keep } else { Axes::ZUp };
            let imported = crate::import::ntrt::import(&file, axes).map_err(bad_input)?;
            for s in &imported.skipped {
                eprintln!("skipped: {s}");
            }
            imported.chosen.iter().for_each(|c| eprintln!("chose: {c}"));
            write_output(out.as_deref(), &[file], &imported.toml)
        }
        ImportFormat::Matrices {
            n,
            cb,
            cs,
            out,
            bar_mass,
            bar_radius,
            string_stiffness,
            string_tension,
            uniform_tension,
            clusters,
        } => {
            let o = MatrixOptions {
                bar_mass_kg: bar_mass,
                bar_radius_m: bar_radius,
                string_stiffness_n_per_m: string_stiffness,
                string_tension_n: string_tension,
                uniform_tension,
                clusters: clusters.clone(),
            };
            o.validate().map_err(bad_input)?;
            let imported = crate::import::matrices::import(&n, &cb, &cs, &o).map_err(bad_input)?;
            imported.chosen.iter().for_each(|c| eprintln!("chose: {c}"));
            let inputs: Vec<std::path::PathBuf> = [n, cb, cs].into_iter().chain(clusters).collect();
            write_output(out.as_deref(), &inputs, &imported.toml)
        }
    }
}
