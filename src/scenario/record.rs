//! `[record]`: where to write the run's recording.

use super::error::{Ctx, ScenarioError};
use super::raw::RawRecord;
use std::path::PathBuf;

/// `[record]`: a path ending in `.rrd`.
pub(super) fn record(ctx: &Ctx, raw: &Option<RawRecord>) -> Result<Option<PathBuf>, ScenarioError> {
    let Some(r) = raw else { return Ok(None) };
    let p = r.path.get_ref();
    if !p.ends_with(".rrd") {
        return Err(ctx.err(&r.path, format!("record.path must end in .rrd, got '{p}'")));
    }
    Ok(Some(PathBuf::from(p)))
}
