//! Errors at a place in the file (`file.toml:LINE:COL: message`), and the checks on single
//! values that every section shares.

use super::raw::SpannedMap;
use crate::mechanisms::Values;
use std::collections::BTreeMap;
use toml::Spanned;

/// An error in a scenario file, at a line and column (both from 1).
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
#[error("{file}:{line}:{col}: {message}")]
pub struct ScenarioError {
    pub file: String,
    pub line: usize,
    pub col: usize,
    pub message: String,
}

/// The file being parsed: its name and text, to turn a byte offset into a line and column.
pub(super) struct Ctx<'a> {
    pub(super) file: String,
    pub(super) source: &'a str,
}

impl Ctx<'_> {
    /// An error at byte `offset` of the source (clamped to its end).
    pub(super) fn err_at(&self, offset: usize, message: String) -> ScenarioError {
        let offset = offset.min(self.source.len());
        let before = &self.source[..offset];
        let line = before.matches('\n').count() + 1;
        let col = before.rsplit('\n').next().map(|l| l.chars().count()).unwrap_or(0) + 1;
        ScenarioError { file: self.file.clone(), line, col, message }
    }

    /// An error at the start of a spanned value.
    pub(super) fn err<T>(&self, at: &Spanned<T>, message: impl Into<String>) -> ScenarioError {
        self.err_at(at.span().start, message.into())
    }
}

/// The parser's words for the kinds of value, as the file says them (a message never names a
/// Rust type).
const FILE_WORDS: [(&str, &str); 8] = [
    ("expected f64", "expected a number"),
    ("expected f32", "expected a number"),
    ("expected i64", "expected a whole number"),
    ("expected u64", "expected a whole number >= 0"),
    ("expected usize", "expected a whole number >= 0"),
    ("expected u32", "expected a whole number >= 0"),
    ("expected a sequence", "expected a list [...]"),
    ("expected a map", "expected a table"),
];

/// A parser's message in the file's words ([`FILE_WORDS`]).
pub(super) fn in_file_words(message: &str) -> String {
    FILE_WORDS.iter().fold(message.to_string(), |m, (parser, file)| m.replace(parser, file))
}

/// A number read from the file: a plain one, or an expression's value.
pub(super) trait Numeric {
    fn number(&self) -> f64;
}

impl Numeric for f64 {
    fn number(&self) -> f64 {
        *self
    }
}

impl Numeric for super::number::Num {
    fn number(&self) -> f64 {
        self.value()
    }
}

/// The value, if it is a finite number.
pub(super) fn finite<N: Numeric>(ctx: &Ctx, v: &Spanned<N>, what: &str) -> Result<f64, ScenarioError> {
    let x = v.get_ref().number();
    if x.is_finite() {
        Ok(x)
    } else {
        Err(ctx.err(v, format!("{what} must be a finite number, got {x}")))
    }
}

/// The value, if it is a finite number > 0.
pub(super) fn positive_value<N: Numeric>(ctx: &Ctx, v: &Spanned<N>, what: &str) -> Result<f64, ScenarioError> {
    let x = finite(ctx, v, what)?;
    if x > 0.0 {
        Ok(x)
    } else {
        Err(ctx.err(v, format!("{what} must be > 0, got {x}")))
    }
}

/// An optional value that must be a finite number > 0; `default` when absent.
pub(super) fn positive(ctx: &Ctx, v: &Option<Spanned<f64>>, what: &str, default: f64) -> Result<f64, ScenarioError> {
    match v {
        None => Ok(default),
        Some(s) => positive_value(ctx, s, what),
    }
}

/// An optional whole number from 1 to `max`; `default` when absent.
pub(super) fn count(
    ctx: &Ctx,
    v: &Option<Spanned<i64>>,
    what: &str,
    default: usize,
    max: i64,
) -> Result<usize, ScenarioError> {
    match v {
        None => Ok(default),
        Some(s) => {
            let x = *s.get_ref();
            if (1..=max).contains(&x) {
                Ok(x as usize)
            } else {
                Err(ctx.err(s, format!("{what} must be a whole number from 1 to {max}, got {x}")))
            }
        }
    }
}

/// A table of named numbers, each finite.
pub(super) fn values(ctx: &Ctx, m: &SpannedMap) -> Result<Values, ScenarioError> {
    m.iter().map(|(k, v)| Ok((k.get_ref().clone(), finite(ctx, v, k.get_ref())?))).collect()
}

/// Where the value of key `key` starts in a table, if the table has that key.
pub(super) fn value_at<V>(map: &BTreeMap<Spanned<String>, Spanned<V>>, key: &str) -> Option<usize> {
    map.iter().find(|(k, _)| k.get_ref() == key).map(|(_, v)| v.span().start)
}

/// Rejects the first key of `map` that is not in `known`: "unknown {what} 'k' for {mechanism}
/// (expected one of: ...)".
pub(super) fn known_keys<V>(
    ctx: &Ctx,
    map: &BTreeMap<Spanned<String>, V>,
    known: &[&str],
    what: &str,
    mechanism: &str,
) -> Result<(), ScenarioError> {
    match map.keys().find(|k| !known.contains(&k.get_ref().as_str())) {
        None => Ok(()),
        Some(k) => Err(ctx.err(
            k,
            format!("unknown {what} '{}' for {mechanism} (expected one of: {})", k.get_ref(), known.join(", ")),
        )),
    }
}
