//! `[params]` and `[start]`: named numbers the mechanism declares.

use super::error::{known_keys, value_at, values, Ctx, ScenarioError};
use super::number::{param_values, ParamMap};
use super::raw::SpannedMap;
use crate::file_model::params::ParamTable;
use crate::mechanisms::{self, Mechanism, Values};

/// Parameters: known symbols, each a finite number or an expression of the others, in the
/// mechanism's unit where the file names one, then the mechanism's own ranges; the result
/// holds every parameter, the missing ones at the mechanism's defaults.
pub(super) fn params(ctx: &Ctx, m: &dyn Mechanism, raw: &ParamMap) -> Result<Values, ScenarioError> {
    let known: Vec<_> = m.params().iter().map(|p| p.symbol).collect();
    known_keys(ctx, raw, &known, "parameter", m.name())?;
    for (k, p) in raw {
        let spec = m.params().iter().find(|s| s.symbol == k.get_ref());
        if let (Some(unit), Some(spec)) = (&p.get_ref().unit, spec) {
            if unit != spec.unit {
                return Err(ctx.err(
                    p,
                    format!("parameter '{}' is in {} (unit = \"{}\"), not {unit}", spec.symbol, spec.unit, spec.unit),
                ));
            }
        }
    }
    let given = param_values(ctx, raw)?;
    let params = mechanisms::with_defaults(m, &given);
    if let Err(e) = m.validate_params(&params) {
        // At the symbol's key; when the file leaves that symbol at its default, at a given
        // parameter the message names (b must be shorter than L: at L), else the first one.
        let message = e.to_string();
        let named = |k: &str| message.split(|c: char| !(c.is_alphanumeric() || c == '_')).any(|w| w == k);
        let at = e
            .symbol()
            .and_then(|sym| value_at(raw, sym))
            .or_else(|| raw.keys().find(|k| named(k.get_ref())).and_then(|k| value_at(raw, k.get_ref())))
            .or_else(|| raw.keys().next().map(|k| k.span().start))
            .unwrap_or(0);
        return Err(ctx.err_at(at, message));
    }
    Ok(params)
}

/// The start of the free coordinates: known keys, finite.
pub(super) fn start(ctx: &Ctx, m: &dyn Mechanism, raw: &SpannedMap) -> Result<Values, ScenarioError> {
    let known: Vec<_> = m.start_keys().iter().map(|(key, _)| *key).collect();
    known_keys(ctx, raw, &known, "start key", m.name())?;
    let spanned = |key: &str| raw.iter().find(|(k, _)| k.get_ref() == key);
    for (k, v) in m.start_flags().iter().filter_map(|f| spanned(f)) {
        if ![0.0, 1.0].contains(v.get_ref()) {
            let key = k.get_ref();
            return Err(ctx.err(v, format!("{key} is a flag: 0 or 1, got {}", v.get_ref())));
        }
    }
    for (a, b) in m.start_exclusive() {
        if let (Some(_), Some((k, _))) = (spanned(a), spanned(b)) {
            return Err(ctx.err(k, format!("[start] {b} means nothing with {a}: the start is given by one of them")));
        }
    }
    values(ctx, raw)
}

/// Every parameter's value at a settle point that sets some of them (a sweep over
/// parameters): the scenario's values `base` (every parameter of the mechanism), the point's
/// entries that name a parameter in their place, and the file's expressions of those
/// evaluated again.
pub(crate) fn params_at(table: &ParamTable, base: &Values, point: &Values) -> Values {
    let set: Values = point.iter().filter(|(k, _)| base.contains_key(*k)).map(|(k, v)| (k.clone(), *v)).collect();
    if set.is_empty() {
        return base.clone();
    }
    let mut out = base.clone();
    out.extend(table.evaluate(&set));
    out.extend(set);
    out
}

/// The parameters of a custom file's `[params]` (`table`) that nothing reads: no word of the
/// file outside `[params]` (a key or a string anywhere else: the structure's expressions and
/// patterns, the model, the checks, the motion, the inputs, `[[sensitivities]]`) and no word
/// of a `--set` flag's value names one, and no parameter that is read derives from it. A word is a
/// run of letters, digits and `_`: a parameter named in a description counts as read, which
/// errs on the side of differentiating it. One pass over the text, however many parameters.
pub(super) fn unread(source: &str, overrides: &[super::overrides::Override], table: &ParamTable) -> Vec<String> {
    let Ok(file) = source.parse::<toml::Table>() else { return Vec::new() };
    let mut words = std::collections::HashSet::new();
    let mut add = |text: &str| {
        words.extend(text.split(|c: char| !(c.is_alphanumeric() || c == '_')).map(str::to_string));
    };
    fn walk(v: &toml::Value, add: &mut dyn FnMut(&str)) {
        match v {
            toml::Value::String(s) => add(s),
            toml::Value::Array(a) => a.iter().for_each(|v| walk(v, add)),
            toml::Value::Table(t) => t.iter().for_each(|(k, v)| {
                add(k);
                walk(v, add)
            }),
            _ => {}
        }
    }
    for (k, v) in file.iter().filter(|(k, _)| *k != "params") {
        add(k);
        walk(v, &mut add);
    }
    // A flag on a parameter is its definition in the table; one on `[sim]` or `[settle]` a value.
    for o in overrides.iter().filter(|o| !table.has(&o.name)) {
        add(&o.value);
    }
    table.unreached(|name| words.contains(name))
}
