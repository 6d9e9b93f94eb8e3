//! Patterns: parts of a file written once and generated over an index range or over the
//! members of a group.
//!
//! - `[[structure.repeat]]` with `for = { i = "0..n" }` holds bodies, members, groups, joints
//!   and actuators generated for every `i` (end excluded), optionally rotated about an axis
//!   and offset (NTRT's substructures, MJCF's `<replicate>`).
//! - `[[quantities]]`, `[[predictions]]` and `[[equations]]` take the same `for`, over a range
//!   or over a group of members (`"cables"`, `"struts"`, `"springs"` or a member group's name).
//! - `sum(i in 0..n, EXPR)`, `min(...)` and `max(...)` in any model expression.
//!
//! In every string of a generated entry, `{EXPR}` is replaced by the value of an integer
//! expression of the loop variables and the parameters (`+ - * / %`, `mod`, parentheses;
//! `/` rounds down), so `"B{(i+1) mod n}"` names the next node around a ring. Braces whose
//! content names anything else stay as they are (an expression's quoted symbol,
//! `{spring AD.force}`). In expressions, a loop variable is also a plain symbol (`i*step`),
//! and a member variable names the member (`{c}.force`).

use super::error::{Ctx, ScenarioError};
use crate::file_model::expr::{ExprError, MAX_EXPRESSION_BYTES};
use crate::mechanisms::Values;
use std::cell::{Cell, RefCell};
use std::collections::BTreeSet;
use std::rc::Rc;
use toml::Spanned;

/// Most entries one range may generate: bounds work done at read, like the grids' counts.
pub const MAX_PATTERN_COUNT: i64 = 10_000;

/// Most bytes of names and expressions the patterns of one file may expand to, summed over
/// every structure of a topology sweep (with the file's text, read again for each one): the
/// work of reading them back is bounded before it is spent (9,900 looped sums of 450 terms,
/// about 50 MB, had taken 27.6 s and 7.4 GB).
pub const MAX_EXPANDED_BYTES: usize = 2 << 20;

/// What a loop variable stands for.
#[derive(Clone, Debug)]
pub(super) enum Binding {
    Index(i64),
    Member(String),
}

/// The parameters and the loop variables bound so far (innermost last).
#[derive(Clone, Debug)]
pub(super) struct Env<'a> {
    pub(super) params: &'a Values,
    pub(super) vars: Vec<(String, Binding)>,
    /// The parameters a range or template has read: they decide the structure's topology.
    pub(super) used: Rc<RefCell<BTreeSet<String>>>,
    /// The bytes expanded so far, shared by every structure of the file (`MAX_EXPANDED_BYTES`).
    pub(super) spent: Rc<Cell<usize>>,
}

/// The groups of members a `for` may name: (group, its members' names).
pub(super) type Groups = Vec<(String, Vec<String>)>;

impl<'a> Env<'a> {
    pub(super) fn new(params: &'a Values, spent: &Rc<Cell<usize>>) -> Self {
        Env { params, vars: Vec::new(), used: Rc::default(), spent: Rc::clone(spent) }
    }

    /// Counts `bytes` more of expanded text; an error past `MAX_EXPANDED_BYTES`.
    pub(super) fn spend(&self, bytes: usize) -> Result<(), ExprError> {
        let spent = self.spent.get().saturating_add(bytes);
        self.spent.set(spent);
        if spent > MAX_EXPANDED_BYTES {
            return Err(at(0, format!("the patterns expand past {MAX_EXPANDED_BYTES} bytes of names and expressions (summed over a topology sweep's structures); write fewer or shorter entries")));
        }
        Ok(())
    }

    fn with(&self, name: &str, b: Binding) -> Env<'a> {
        let mut e = self.clone();
        e.vars.push((name.to_string(), b));
        e
    }

    fn lookup(&self, name: &str) -> Option<&Binding> {
        self.vars.iter().rev().find(|(n, _)| n == name).map(|(_, b)| b)
    }

    /// The integer value of a name: a loop index or an integral parameter.
    fn integer(&self, name: &str) -> Result<Option<i64>, NotAnInteger> {
        match self.lookup(name) {
            Some(Binding::Index(v)) => return Ok(Some(*v)),
            Some(Binding::Member(_)) => return Err(NotAnInteger::Member(name.to_string())),
            None => {}
        }
        let Some(x) = self.params.get(name) else { return Ok(None) };
        self.used.borrow_mut().insert(name.to_string());
        if (x - x.round()).abs() <= 1e-9 && x.abs() < 1e15 {
            Ok(Some(x.round() as i64))
        } else {
            Err(NotAnInteger::Fraction { name: name.to_string(), value: *x })
        }
    }
}

/// A name in a whole-number expression that has no whole-number value.
#[derive(Debug, thiserror::Error)]
enum NotAnInteger {
    /// The name is a loop variable over members.
    #[error("'{0}' names a member, not a number")]
    Member(String),
    /// The name is a parameter whose value is not whole.
    #[error("parameter '{name}' = {value} is not a whole number")]
    Fraction { name: String, value: f64 },
}

/// An error at byte `offset` of a template string.
fn at(offset: usize, message: impl Into<String>) -> ExprError {
    ExprError { offset, message: message.into() }
}

/// The entries a `for` generates: each variable's bindings, as a list of environments.
pub(super) fn bindings<'a>(env: &Env<'a>, var: &str, over: &str, groups: &Groups) -> Result<Vec<Env<'a>>, ExprError> {
    if !is_identifier(var) {
        return Err(at(0, format!("a loop variable is a name such as i, got '{var}'")));
    }
    if let Some((a, b)) = over.split_once("..") {
        let lo = integer_expr(a, env)?.ok_or_else(|| at(0, format!("'{a}' is not a whole-number expression")))?;
        let hi = integer_expr(b, env)
            .map_err(|e| at(e.offset + a.len() + 2, e.message))?
            .ok_or_else(|| at(a.len() + 2, format!("'{b}' is not a whole-number expression")))?;
        if hi.checked_sub(lo).is_none_or(|n| !(0..=MAX_PATTERN_COUNT).contains(&n)) {
            return Err(at(0, format!("{over} gives {lo}..{hi}: at most {MAX_PATTERN_COUNT} entries, end >= start")));
        }
        return Ok((lo..hi).map(|v| env.with(var, Binding::Index(v))).collect());
    }
    let name = over.trim();
    match groups.iter().find(|(g, _)| g == name) {
        Some((_, members)) => Ok(members.iter().map(|m| env.with(var, Binding::Member(m.clone()))).collect()),
        None => {
            let known: Vec<&str> = groups.iter().map(|(g, _)| g.as_str()).collect();
            Err(at(0, format!("'{name}' is neither a range A..B nor a group of members ({})", known.join(", "))))
        }
    }
}

pub(super) fn is_identifier(s: &str) -> bool {
    let mut c = s.chars();
    c.next().is_some_and(|f| f.is_ascii_alphabetic() || f == '_') && c.all(|x| x.is_ascii_alphanumeric() || x == '_')
}

/// How a template is filled: a name (braces only) or an expression (braces, loop indices as
/// plain symbols, and aggregates).
#[derive(Clone, Copy, PartialEq)]
enum Mode {
    Name,
    Expr,
}

/// A name with its `{EXPR}` templates filled.
pub(super) fn fill_name(text: &str, env: &Env) -> Result<String, ExprError> {
    let out = fill(text, env, Mode::Name, &Groups::new())?;
    env.spend(out.len())?;
    Ok(out)
}

/// An expression with its templates, loop symbols and aggregates filled.
pub(super) fn fill_expr(text: &str, env: &Env, groups: &Groups) -> Result<String, ExprError> {
    let out = fill(text, env, Mode::Expr, groups)?;
    env.spend(out.len())?;
    Ok(out)
}

fn fill(text: &str, env: &Env, mode: Mode, groups: &Groups) -> Result<String, ExprError> {
    let mut out = String::with_capacity(text.len());
    let mut i = 0;
    let bytes = text.as_bytes();
    while i < text.len() {
        let c = bytes[i];
        if c == b'{' {
            let close = text[i..].find('}').map(|k| i + k).ok_or_else(|| at(i, "'{' without its '}'"))?;
            i = brace(text, i, close, env, mode, &mut out)?;
        } else if mode == Mode::Expr && (c.is_ascii_alphabetic() || c == b'_') && !after_name_char(bytes, i) {
            let end =
                i + text[i..].find(|ch: char| !(ch.is_ascii_alphanumeric() || ch == '_')).unwrap_or(text.len() - i);
            let word = &text[i..end];
            if let Some(next) = aggregate(text, i, end, env, groups)? {
                out.push_str(&next.0);
                i = next.1;
                continue;
            }
            match env.lookup(word) {
                Some(Binding::Index(v)) if !text[end..].starts_with('.') => out.push_str(&format!("({v})")),
                _ => out.push_str(word),
            }
            i = end;
        } else {
            let ch = text[i..].chars().next().expect("inside the text");
            out.push(ch);
            i += ch.len_utf8();
        }
    }
    Ok(out)
}

fn shifted(e: ExprError, by: usize) -> ExprError {
    at(e.offset + by, e.message)
}

/// Whether byte `i` continues a name or a dotted symbol (`B1.x`'s `x`).
fn after_name_char(bytes: &[u8], i: usize) -> bool {
    i > 0 && (bytes[i - 1].is_ascii_alphanumeric() || bytes[i - 1] == b'_' || bytes[i - 1] == b'.')
}

/// Fills the braces at `open..=close`; returns where the scan goes on.
fn brace(text: &str, open: usize, close: usize, env: &Env, mode: Mode, out: &mut String) -> Result<usize, ExprError> {
    let inner = &text[open + 1..close];
    if let Some(Binding::Member(m)) = env.lookup(inner.trim()) {
        let rest = &text[close + 1..];
        let attr_len =
            rest.strip_prefix('.').map(|r| 1 + r.find(|c: char| !c.is_ascii_alphanumeric()).unwrap_or(r.len()));
        match (mode, attr_len) {
            // A member name that is no plain symbol is quoted with its attribute.
            (Mode::Expr, Some(n)) if !is_identifier(m) => {
                out.push_str(&format!("{{{m}{}}}", &rest[..n]));
                return Ok(close + 1 + n);
            }
            _ => out.push_str(m),
        }
        return Ok(close + 1);
    }
    match integer_expr(inner, env).map_err(|e| shifted(e, open + 1))? {
        Some(v) => out.push_str(&v.to_string()),
        // Names nothing of the pattern's: an expression's quoted symbol, kept.
        None => out.push_str(&text[open..=close]),
    }
    Ok(close + 1)
}

/// `sum(i in RANGE, EXPR)`, `min(...)` or `max(...)` starting with the word at `start..end`:
/// the expansion and where the scan goes on, or None for anything else (`min(a, b)`).
fn aggregate(
    text: &str,
    start: usize,
    end: usize,
    env: &Env,
    groups: &Groups,
) -> Result<Option<(String, usize)>, ExprError> {
    let word = &text[start..end];
    if !matches!(word, "sum" | "min" | "max") {
        return Ok(None);
    }
    let rest = &text[end..];
    let Some(args) = rest.trim_start().strip_prefix('(') else { return Ok(None) };
    let args_start = text.len() - args.len();
    let mut parts = args.trim_start().splitn(3, char::is_whitespace);
    let (Some(var), Some("in")) = (parts.next(), parts.next()) else { return Ok(None) };
    let close = matching_paren(text, args_start).ok_or_else(|| at(start, format!("{word}( without its ')'")))?;
    let comma = top_level_comma(text, args_start, close)
        .ok_or_else(|| at(start, format!("{word}({var} in RANGE, EXPR) needs a comma before EXPR")))?;
    let range_start = text[args_start..].find(" in ").map(|k| args_start + k + 4).unwrap_or(args_start);
    let over = text[range_start..comma].trim();
    let envs = bindings(env, var, over, groups).map_err(|e| shifted(e, range_start))?;
    if envs.is_empty() {
        return Err(at(start, format!("{word} over an empty range {over}")));
    }
    let body = &text[comma + 1..close];
    let (mut terms, mut bytes) = (Vec::new(), 0);
    for e in &envs {
        let t = fill(body, e, Mode::Expr, groups).map_err(|e| shifted(e, comma + 1))?;
        bytes += t.len();
        // Bounded while it grows: the expansion could otherwise be the range times the body.
        if bytes > MAX_EXPRESSION_BYTES {
            return Err(at(start, format!("{word}(...) over {over} expands beyond {MAX_EXPRESSION_BYTES} bytes")));
        }
        terms.push(t.trim().to_string());
    }
    let joined = if word == "sum" {
        format!("({})", terms.iter().map(|t| format!("({t})")).collect::<Vec<_>>().join(" + "))
    } else {
        balanced(word, &terms)
    };
    Ok(Some((joined, close + 1)))
}

/// min or max of many terms as a balanced tree of two-argument calls (nesting log2 of them).
fn balanced(f: &str, terms: &[String]) -> String {
    match terms {
        [one] => one.clone(),
        _ => {
            let (a, b) = terms.split_at(terms.len() / 2);
            format!("{f}({}, {})", balanced(f, a), balanced(f, b))
        }
    }
}

fn matching_paren(text: &str, after_open: usize) -> Option<usize> {
    let mut depth = 1;
    for (k, c) in text[after_open..].char_indices() {
        match c {
            '(' => depth += 1,
            ')' => {
                depth -= 1;
                if depth == 0 {
                    return Some(after_open + k);
                }
            }
            _ => {}
        }
    }
    None
}

fn top_level_comma(text: &str, from: usize, to: usize) -> Option<usize> {
    let mut depth = 0;
    for (k, c) in text[from..to].char_indices() {
        match c {
            '(' => depth += 1,
            ')' => depth -= 1,
            ',' if depth == 0 => return Some(from + k),
            _ => {}
        }
    }
    None
}

/// The value of an integer expression of the loop indices and integral parameters, or None
/// when it names something else (then it is no template).
pub(super) fn integer_expr(text: &str, env: &Env) -> Result<Option<i64>, ExprError> {
    let tokens = match int_tokens(text) {
        Some(t) if !t.is_empty() => t,
        _ => return Ok(None),
    };
    let mut p = IntParser { tokens: &tokens, pos: 0, env, unknown: false };
    let v = p.sum()?;
    if p.unknown || p.pos != tokens.len() {
        return Ok(None);
    }
    Ok(Some(v))
}

#[derive(Debug, PartialEq)]
enum Tok {
    Int(i64),
    Name(String),
    Op(char),
}

/// Tokens of an integer expression, or None when the text has anything else.
fn int_tokens(text: &str) -> Option<Vec<(usize, Tok)>> {
    let mut out = Vec::new();
    let mut it = text.char_indices().peekable();
    while let Some(&(k, c)) = it.peek() {
        if c.is_whitespace() {
            it.next();
        } else if c.is_ascii_digit() {
            let mut v: i64 = 0;
            while let Some(&(_, d)) = it.peek().filter(|(_, d)| d.is_ascii_digit()) {
                v = v.checked_mul(10)?.checked_add(d.to_digit(10)? as i64)?;
                it.next();
            }
            out.push((k, Tok::Int(v)));
        } else if c.is_ascii_alphabetic() || c == '_' {
            let mut w = String::new();
            while let Some(&(_, d)) = it.peek().filter(|(_, d)| d.is_ascii_alphanumeric() || *d == '_') {
                w.push(d);
                it.next();
            }
            out.push((k, if w == "mod" { Tok::Op('%') } else { Tok::Name(w) }));
        } else if "+-*/%()".contains(c) {
            out.push((k, Tok::Op(c)));
            it.next();
        } else {
            return None;
        }
    }
    Some(out)
}

/// A recursive-descent reader of integer expressions.
struct IntParser<'t, 'e> {
    tokens: &'t [(usize, Tok)],
    pos: usize,
    env: &'t Env<'e>,
    /// A name that is neither a loop index nor a parameter was met.
    unknown: bool,
}

impl IntParser<'_, '_> {
    fn peek_op(&self) -> Option<char> {
        match self.tokens.get(self.pos) {
            Some((_, Tok::Op(c))) => Some(*c),
            _ => None,
        }
    }

    fn offset(&self) -> usize {
        self.tokens.get(self.pos).map_or(0, |(k, _)| *k)
    }

    fn sum(&mut self) -> Result<i64, ExprError> {
        let mut v = self.product()?;
        while let Some(op @ ('+' | '-')) = self.peek_op() {
            self.pos += 1;
            let r = self.product()?;
            v = if op == '+' { v.checked_add(r) } else { v.checked_sub(r) }
                .ok_or_else(|| at(self.offset(), "whole number out of range"))?;
        }
        Ok(v)
    }

    fn product(&mut self) -> Result<i64, ExprError> {
        let mut v = self.unary()?;
        while let Some(op @ ('*' | '/' | '%')) = self.peek_op() {
            let k = self.offset();
            self.pos += 1;
            let r = self.unary()?;
            v = match op {
                '*' => v.checked_mul(r),
                _ if r == 0 && !self.unknown => return Err(at(k, "division by zero in a name template")),
                _ if r == 0 => Some(0),
                '/' => v.checked_div_euclid(r),
                _ => v.checked_rem_euclid(r),
            }
            .ok_or_else(|| at(k, "whole number out of range"))?;
        }
        Ok(v)
    }

    fn unary(&mut self) -> Result<i64, ExprError> {
        if self.peek_op() == Some('-') {
            let k = self.offset();
            self.pos += 1;
            return self.unary()?.checked_neg().ok_or_else(|| at(k, "whole number out of range"));
        }
        let k = self.offset();
        match self.tokens.get(self.pos) {
            Some((_, Tok::Int(v))) => {
                self.pos += 1;
                Ok(*v)
            }
            Some((_, Tok::Name(n))) => {
                self.pos += 1;
                match self.env.integer(n).map_err(|e| at(k, e.to_string()))? {
                    Some(v) => Ok(v),
                    None => {
                        self.unknown = true;
                        Ok(0)
                    }
                }
            }
            Some((_, Tok::Op('('))) => {
                self.pos += 1;
                let v = self.sum()?;
                if self.peek_op() != Some(')') {
                    self.unknown = true;
                }
                self.pos += 1;
                Ok(v)
            }
            _ => {
                self.unknown = true;
                self.pos = self.tokens.len();
                Ok(0)
            }
        }
    }
}

/// A spanned string with its templates filled, kept at its place in the file.
pub(super) fn spanned_name(ctx: &Ctx, s: &Spanned<String>, env: &Env) -> Result<Spanned<String>, ScenarioError> {
    let text = fill_name(s.get_ref(), env).map_err(|e| super::number::expr_error(ctx, s.span().start, &e, "a name"))?;
    Ok(Spanned::new(s.span(), text))
}

/// A spanned expression with its templates filled, kept at its place in the file.
pub(super) fn spanned_expr(
    ctx: &Ctx,
    s: &Spanned<String>,
    env: &Env,
    groups: &Groups,
) -> Result<Spanned<String>, ScenarioError> {
    let text = fill_expr(s.get_ref(), env, groups)
        .map_err(|e| super::number::expr_error(ctx, s.span().start, &e, "an expression"))?;
    Ok(Spanned::new(s.span(), text))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn env(n: f64) -> Values {
        let mut v = Values::new();
        v.insert("n".into(), n);
        v.insert("r".into(), 0.5);
        v
    }

    #[test]
    fn a_name_template_wraps_around_the_ring_with_mod() {
        let p = env(5.0);
        let e = Env::new(&p, &Rc::default()).with("i", Binding::Index(4));
        assert_eq!(fill_name("B{(i+1) mod n}", &e).unwrap(), "B0");
        assert_eq!(fill_name("T{i}-{i % 2}", &e).unwrap(), "T4-0");
        assert_eq!(fill_name("{n-1}", &e).unwrap(), "4");
    }

    #[test]
    fn an_expression_sees_the_index_as_a_symbol_and_keeps_quoted_symbols() {
        let p = env(3.0);
        let e = Env::new(&p, &Rc::default()).with("i", Binding::Index(2));
        let t = fill_expr("r*cos(i*2*pi/n) + B{i}.x + {spring AD.force} + pi", &e, &Groups::new()).unwrap();
        assert_eq!(t, "r*cos((2)*2*pi/n) + B2.x + {spring AD.force} + pi");
    }

    #[test]
    fn aggregates_expand_over_ranges_and_groups() {
        let p = env(3.0);
        let groups = vec![("side".to_string(), vec!["side:B1-T3".to_string(), "s2".to_string()])];
        let e = Env::new(&p, &Rc::default());
        assert_eq!(fill_expr("sum(i in 0..n, B{i}.x)/n", &e, &groups).unwrap(), "((B0.x) + (B1.x) + (B2.x))/n");
        assert_eq!(fill_expr("max(c in side, {c}.force)", &e, &groups).unwrap(), "max({side:B1-T3.force}, s2.force)");
        assert_eq!(fill_expr("min(a, b)", &e, &groups).unwrap(), "min(a, b)");
        let e2 = e.with("s", Binding::Member("strut:a3-a4".into()));
        assert_eq!(
            fill_expr("{s}.force/min(c in side, {c}.force)", &e2, &groups).unwrap(),
            "{strut:a3-a4.force}/min({side:B1-T3.force}, s2.force)"
        );
    }

    #[test]
    fn a_range_beyond_the_limit_or_reversed_is_refused() {
        let p = env(3.0);
        let e = Env::new(&p, &Rc::default());
        assert!(bindings(&e, "i", "0..n", &Groups::new()).unwrap().len() == 3);
        assert!(bindings(&e, "i", "3..0", &Groups::new()).is_err());
        assert!(bindings(&e, "i", "0..100000", &Groups::new()).is_err());
        assert!(bindings(&e, "i", "0..r", &Groups::new()).is_err());
    }
}
