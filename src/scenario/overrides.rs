//! `--set NAME=VALUE` on a scenario: a parameter (`NAME`, a number or an expression) or a
//! setting of `[sim]` or `[settle]` (`sim.KEY`, `settle.KEY`), replacing what the file says.
//!
//! Each override is read as one more line of TOML placed after the file's end, so that its
//! value is validated exactly as the file's own would be, and an error in it (a wrong type, an
//! unknown name, a value out of range) is located by line and column past the file's end and
//! then reported at its flag (`--set NAME=VALUE:1:COL: message`). A name the file's
//! `[actuation]` grid or points set at every point is refused at the sweep's key: the flag
//! would be ignored.

use super::error::{Ctx, ScenarioError};
use super::number::ParamMap;
use super::raw::{RawScenario, RawSettle, RawSim};
use serde::de::DeserializeOwned;

/// A `--set` flag that is not `NAME=VALUE`.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum OverrideError {
    /// No `=`.
    #[error("--set {0}: expected NAME=VALUE")]
    NoEquals(String),
    /// No name or no value around the `=`.
    #[error("--set {0}: expected NAME=VALUE with a name and a value")]
    Empty(String),
}

/// One `--set NAME=VALUE`, as given.
#[derive(Clone, Debug, PartialEq)]
pub struct Override {
    pub name: String,
    pub value: String,
}

impl Override {
    /// Parses `NAME=VALUE`.
    pub fn parse(flag: &str) -> Result<Override, OverrideError> {
        let (name, value) = flag.split_once('=').ok_or_else(|| OverrideError::NoEquals(flag.to_string()))?;
        let (name, value) = (name.trim(), value.trim());
        if name.is_empty() || value.is_empty() {
            return Err(OverrideError::Empty(flag.to_string()));
        }
        Ok(Override { name: name.to_string(), value: value.to_string() })
    }

    /// The flag as the user wrote it.
    fn flag(&self) -> String {
        format!("--set {}={}", self.name, self.value)
    }

    /// The override as a TOML line: the value as given where it is a TOML number or boolean,
    /// else as a string (an expression of the parameters).
    fn toml_line(&self, key: &str) -> String {
        let literal = toml::from_str::<toml::Table>(&format!("v = {}", self.value)).is_ok_and(|t| {
            matches!(t.get("v"), Some(toml::Value::Integer(_) | toml::Value::Float(_) | toml::Value::Boolean(_)))
        });
        let value = if literal { self.value.clone() } else { toml::Value::String(self.value.clone()).to_string() };
        format!("{key} = {value}")
    }
}

/// The file's text with the overrides' lines after its end (what errors are located in), and
/// the number of lines of the file itself.
pub(super) fn extended_source(source: &str, overrides: &[Override]) -> (String, usize) {
    let file_lines = source.split('\n').count();
    let mut text = source.to_string();
    for o in overrides {
        text.push('\n');
        text.push_str(&o.toml_line(key_of(o)));
    }
    (text, file_lines)
}

/// The TOML key of an override: the setting's own key for `sim.KEY` and `settle.KEY`.
fn key_of(o: &Override) -> &str {
    o.name.strip_prefix("sim.").or_else(|| o.name.strip_prefix("settle.")).unwrap_or(&o.name)
}

/// Applies every override to the file's sections; `ctx.source` is [`extended_source`]'s text.
pub(super) fn apply(
    ctx: &Ctx,
    raw: &mut RawScenario,
    overrides: &[Override],
    file_lines: usize,
) -> Result<(), ScenarioError> {
    for (i, o) in overrides.iter().enumerate() {
        let line_start = nth_line_start(ctx.source, file_lines + i);
        let snippet = padded(ctx.source, line_start, &o.toml_line(key_of(o)));
        if o.name.starts_with("sim.") {
            merge_sim(&mut raw.sim, read(ctx, &snippet)?);
        } else if o.name.starts_with("settle.") {
            merge_settle(&mut raw.settle, read(ctx, &snippet)?);
        } else {
            swept(ctx, raw, o)?;
            // A file's own structure has only the parameters it names: another name would be
            // set and silently unused.
            let named = raw.params.keys().any(|k| k.get_ref() == &o.name);
            if raw.mechanism.get_ref() == "custom" && !named {
                let known: Vec<&str> = raw.params.keys().map(|k| k.get_ref().as_str()).collect();
                let message =
                    format!("the scenario has no parameter '{}' (its [params]: {})", o.name, known.join(", "));
                return Err(ctx.err_at(line_start, message));
            }
            let entry: ParamMap = read(ctx, &snippet)?;
            for (k, mut v) in entry {
                // The file's unit and description stay with the new value.
                if let Some(old) = raw.params.remove(&k) {
                    let old = old.into_inner();
                    v.get_mut().unit = old.unit;
                    v.get_mut().description = old.description;
                }
                raw.params.insert(k, v);
            }
        }
    }
    Ok(())
}

/// A name the file's `[actuation]` grid or points set at every point (a swept parameter or
/// input) cannot be fixed by `--set`: its value would be replaced at every point and the flag
/// silently ignored. The error is located at the sweep's key and names the flag.
fn swept(ctx: &Ctx, raw: &RawScenario, o: &Override) -> Result<(), ScenarioError> {
    let a = raw.actuation.get_ref();
    let in_grid = a.grid.as_ref().and_then(|g| g.keys().find(|k| k.get_ref() == &o.name).map(|k| (k, "grid")));
    let in_points = || {
        a.points
            .iter()
            .flatten()
            .find_map(|p| p.get_ref().keys().find(|k| k.get_ref() == &o.name))
            .map(|k| (k, "points"))
    };
    let Some((key, how)) = in_grid.or_else(in_points) else { return Ok(()) };
    Err(ctx.err(
        key,
        format!(
            "{} conflicts with the file: '{}' is set here by [actuation] {how}, at every point, so the flag would be ignored; remove the flag, or change the {how} in the file",
            o.flag(),
            o.name
        ),
    ))
}

/// The byte offset where line `n` (from 0) of `text` starts.
fn nth_line_start(text: &str, n: usize) -> usize {
    text.match_indices('\n').nth(n.wrapping_sub(1)).map_or(0, |(i, _)| i + 1)
}

/// `line` preceded by white space and newlines standing for `text[..at]`, so that the spans
/// serde reads in it are offsets into `text`.
fn padded(text: &str, at: usize, line: &str) -> String {
    let mut s: String = text[..at].chars().map(|c| if c == '\n' { '\n' } else { ' ' }).collect();
    // A multi-byte character stood for by one space: pad to the same byte length.
    s.push_str(&" ".repeat(at.saturating_sub(s.len())));
    s.push_str(line);
    s
}

/// Reads a snippet as `T`, its error located in `ctx`.
fn read<T: DeserializeOwned>(ctx: &Ctx, snippet: &str) -> Result<T, ScenarioError> {
    toml::from_str(snippet)
        .map_err(|e| ctx.err_at(e.span().map_or(snippet.len(), |s| s.start), e.message().trim().into()))
}

/// Every setting `from` gives replaces `into`'s (every field named, so that a new setting
/// cannot be left out).
fn merge_sim(into: &mut RawSim, from: RawSim) {
    let RawSim {
        dt,
        substeps,
        pgs_iterations,
        approach_pgs_iterations,
        newton_damping,
        relaxation,
        body_damping,
        bounding_box,
        max_kinetic_energy,
        max_joint_gap,
    } = from;
    into.dt = dt.or(into.dt.take());
    into.substeps = substeps.or(into.substeps.take());
    into.pgs_iterations = pgs_iterations.or(into.pgs_iterations.take());
    into.approach_pgs_iterations = approach_pgs_iterations.or(into.approach_pgs_iterations.take());
    into.newton_damping = newton_damping.or(into.newton_damping.take());
    into.relaxation = relaxation.or(into.relaxation.take());
    into.body_damping = body_damping.or(into.body_damping.take());
    into.bounding_box = bounding_box.or(into.bounding_box.take());
    into.max_kinetic_energy = max_kinetic_energy.or(into.max_kinetic_energy.take());
    into.max_joint_gap = max_joint_gap.or(into.max_joint_gap.take());
}

fn merge_settle(into: &mut RawSettle, from: RawSettle) {
    let RawSettle { speed_tol, window, residual_force_tol, residual_torque_tol, max_time } = from;
    into.speed_tol = speed_tol.or(into.speed_tol.take());
    into.window = window.or(into.window.take());
    into.residual_force_tol = residual_force_tol.or(into.residual_force_tol.take());
    into.residual_torque_tol = residual_torque_tol.or(into.residual_torque_tol.take());
    into.max_time = max_time.or(into.max_time.take());
}

/// An error located past the file's end is the override's on that line: reported at its flag.
pub(super) fn at_flag(e: ScenarioError, overrides: &[Override], file_lines: usize) -> ScenarioError {
    match e.line.checked_sub(file_lines + 1).and_then(|i| overrides.get(i)) {
        Some(o) => ScenarioError { file: o.flag(), line: 1, col: e.col, message: e.message },
        None => e,
    }
}
