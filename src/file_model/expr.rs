//! Expressions of a scenario file's model (`"2*r*sin(pi/n)"`): compiled once against a known
//! list of symbols, evaluated with a slice of numbers in that list's order, differentiated to
//! the second order by forward differentiation (`dual.rs`). The rest of the testbed sees only
//! [`Expr`] and [`ExprError`]. The `exmex` crate checks the text; the expression's own tree
//! evaluates it (exmex 0.21 evaluated `sin(x^2 + y^2 + 1)` wrongly, and its symbolic
//! derivatives grew past any bound: README, Stack).
//!
//! Grammar: numbers (`1`, `2.5`, `1e-3`), symbols (`r`, `B1.x`, `side1.force`; any other name
//! between braces, `{spring AD.force}`), `+ - * / ^` with the usual precedence, parentheses,
//! the functions [`FUNCTIONS`] and the constants `pi` and `e`. Every error carries the byte
//! offset in the expression where it lies and, for an unknown name, the names that exist.

use super::dual::{self, Node};
use exmex::prelude::*;
use std::sync::Arc;

/// The functions an expression may call, with their number of arguments.
pub const FUNCTIONS: &[(&str, usize)] = &[
    ("sin", 1),
    ("cos", 1),
    ("tan", 1),
    ("asin", 1),
    ("acos", 1),
    ("atan", 1),
    ("atan2", 2),
    ("sqrt", 1),
    ("hypot", 2),
    ("abs", 1),
    ("min", 2),
    ("max", 2),
    ("pow", 2),
    ("exp", 1),
    ("ln", 1),
];

/// The symbol of time in every expression that may use it.
pub const TIME: &str = "t";

/// What `name` already means in an expression (a built-in constant or function, or time), if
/// anything: a name a file defines may not be one of these.
pub fn reserved_meaning(name: &str) -> Option<&'static str> {
    if CONSTANTS.iter().any(|(c, _)| *c == name) {
        Some("a built-in constant of the expressions")
    } else if FUNCTIONS.iter().any(|(f, _)| *f == name) {
        Some("a built-in function of the expressions")
    } else if name == TIME {
        Some("the time symbol of the expressions")
    } else {
        None
    }
}

/// The constants an expression may name, with the engine's spelling.
const CONSTANTS: &[(&str, &str)] = &[("pi", "PI"), ("e", "E")];

/// Largest number of symbols an expression may be compiled against (the engine's variable
/// names are `v` and this many digits, so that they sort in the list's order).
const SYMBOL_DIGITS: usize = 5;
const MAX_SYMBOLS: usize = 99_999;

/// Longest expression compiled [bytes of its text]. The shipped scenarios' longest is 151; a
/// longer text is refused before it is read, so that reading it stays linear in its size.
pub const MAX_EXPRESSION_BYTES: usize = 10_000;

/// Deepest nesting of an expression: parentheses, function calls, signs (`--x`) and powers
/// (`a^b^c`) each add a level. Refused before the engine parses it (deep nesting overflowed
/// the stack).
pub const MAX_EXPRESSION_DEPTH: usize = 64;

/// Why an expression does not compile or differentiate, at byte `offset` of its text.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("at byte {offset}: {message}")]
pub struct ExprError {
    pub offset: usize,
    pub message: String,
}

fn err(offset: usize, message: impl Into<String>) -> ExprError {
    ExprError { offset, message: message.into() }
}

/// A compiled expression of a list of symbols, or its first or second derivative.
#[derive(Clone, Debug)]
pub struct Expr {
    text: String,
    /// The compiled expression's tree (`dual.rs`), evaluated directly.
    tree: Arc<Node>,
    /// The symbols (indices in the list) the tree reads, ascending.
    order: Vec<usize>,
    /// The engine's text of the expression compiled, before any derivative.
    source: Arc<str>,
    /// The symbols it has been differentiated by, in order (at most [`MAX_DERIVATIVE_ORDER`]).
    wrt: Vec<usize>,
}

/// Highest order of a derivative: forward differentiation with hyper-dual numbers gives the
/// first and second (the energy models' gradients, Hessians, momenta and mass matrices).
const MAX_DERIVATIVE_ORDER: usize = 2;

impl Expr {
    /// Compiles `text` against `symbols` (the names it may use, in the order of the values
    /// [`Expr::eval`] gets; an empty name stands for a value this expression may not use).
    pub fn compile(text: &str, symbols: &[&str]) -> Result<Expr, ExprError> {
        if symbols.len() > MAX_SYMBOLS {
            return Err(err(0, format!("at most {MAX_SYMBOLS} symbols, got {}", symbols.len())));
        }
        if text.len() > MAX_EXPRESSION_BYTES {
            return Err(err(
                0,
                format!("an expression has at most {MAX_EXPRESSION_BYTES} bytes, this one {}", text.len()),
            ));
        }
        let tokens = tokenize(text)?;
        if tokens.is_empty() {
            return Err(err(0, "empty expression"));
        }
        let engine_text = Translator::new(text, symbols, &tokens).translate()?;
        // The engine checks the text; the tree evaluates it (exmex 0.21 evaluates a function of
        // two powers and a number, `sin(x^2 + y^2 + 1)`, wrongly: 1.0014 at (0.37, -0.21)).
        FlatEx::<f64>::parse(&engine_text).map_err(|e| err(0, format!("not a valid expression ({})", e.msg())))?;
        let tree = dual::parse(&engine_text).map_err(|e| err(0, format!("not a valid expression ({})", e.0)))?;
        Ok(Expr {
            text: text.to_string(),
            order: tree.symbols(),
            tree: Arc::new(tree),
            source: engine_text.into(),
            wrt: vec![],
        })
    }

    /// The engine's text of the expression compiled (before any derivative).
    #[cfg(test)]
    pub(crate) fn source(&self) -> &str {
        &self.source
    }

    /// The expression as written.
    pub fn text(&self) -> &str {
        &self.text
    }

    /// The indices (in the symbol list) of the symbols the expression uses.
    pub fn uses(&self) -> &[usize] {
        &self.order
    }

    /// The value with `values[i]` for symbol `i` of the list it was compiled against (NaN when
    /// a value is missing).
    pub fn eval(&self, values: &[f64]) -> f64 {
        match self.wrt[..] {
            [] => self.tree.value(values),
            [i] => self.tree.eval(values, Some(i), None).a,
            [i, j] => self.tree.eval(values, Some(i), Some(j)).ab,
            _ => f64::NAN,
        }
    }

    /// The partial derivative with respect to symbol `symbol` of the list (zero when the
    /// expression does not use it), exact to round-off: the compiled expression's tree
    /// differentiated forward (`dual.rs`), to the second order.
    pub fn derivative(&self, symbol: usize) -> Result<Expr, ExprError> {
        let text = if self.text.starts_with(DERIVATIVE_OF) {
            format!("{}'", self.text)
        } else {
            format!("{DERIVATIVE_OF}{}", self.text)
        };
        if !self.order.contains(&symbol) {
            let zero = Arc::new(Node::Number(0.0));
            return Ok(Expr { text, tree: zero, order: vec![], source: "0".into(), wrt: vec![] });
        }
        if self.wrt.len() >= MAX_DERIVATIVE_ORDER {
            return Err(err(0, format!("{}: derivatives of the third order and above are not taken", self.shown())));
        }
        let mut wrt = self.wrt.clone();
        wrt.push(symbol);
        Ok(Expr { text, tree: self.tree.clone(), order: self.order.clone(), source: self.source.clone(), wrt })
    }

    /// What evaluating the expression costs, in bytes of its text: the compiled text's length,
    /// times 1 + the derivative's order (a hyper-dual pass carries that many more numbers;
    /// measured: 10,000 Newton starts of an 11-sine potential's gradient and Hessian, 6 million
    /// unweighted, took 0.58 s a settle point).
    pub fn size(&self) -> usize {
        self.source.len() * (1 + self.wrt.len())
    }

    /// The expression for a message: its text, or its start when long.
    fn shown(&self) -> String {
        const SHOWN_CHARS: usize = 60;
        let mut t: String = self.text.chars().take(SHOWN_CHARS).collect();
        if t.len() < self.text.len() {
            t.push_str("...");
        }
        format!("'{t}'")
    }
}

/// How a derivative's text starts (`the derivative of V`, a second one `the derivative of V'`).
const DERIVATIVE_OF: &str = "the derivative of ";

#[derive(Clone, Copy, Debug, PartialEq)]
enum Kind {
    Number,
    /// A name: a function, a constant or a symbol.
    Name,
    /// A name between braces (the braces are part of the token).
    Braced,
    Op,
    Open,
    Close,
    Comma,
}

#[derive(Clone, Copy, Debug)]
struct Token {
    kind: Kind,
    start: usize,
    end: usize,
}

/// Splits `text` into tokens, each with its byte range.
fn tokenize(text: &str) -> Result<Vec<Token>, ExprError> {
    let b = text.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < b.len() {
        let c = b[i];
        let start = i;
        let kind = match c {
            b' ' | b'\t' | b'\n' | b'\r' => {
                i += 1;
                continue;
            }
            b'0'..=b'9' | b'.' => {
                i = number_end(b, i);
                Kind::Number
            }
            b'a'..=b'z' | b'A'..=b'Z' | b'_' => {
                i = name_end(b, i);
                Kind::Name
            }
            b'{' => {
                let close = text[i..].find('}').ok_or_else(|| err(i, "'{' without a closing '}'"))?;
                i += close + 1;
                Kind::Braced
            }
            b'+' | b'-' | b'*' | b'/' | b'^' => {
                i += 1;
                Kind::Op
            }
            b'(' => {
                i += 1;
                Kind::Open
            }
            b')' => {
                i += 1;
                Kind::Close
            }
            b',' => {
                i += 1;
                Kind::Comma
            }
            _ => {
                let ch = text[i..].chars().next().unwrap_or('?');
                return Err(err(i, format!("unexpected character '{ch}'")));
            }
        };
        out.push(Token { kind, start, end: i });
    }
    Ok(out)
}

/// The end of a number starting at `i`: digits, one point, an exponent.
fn number_end(b: &[u8], mut i: usize) -> usize {
    while i < b.len() && (b[i].is_ascii_digit() || b[i] == b'.') {
        i += 1;
    }
    if i < b.len() && (b[i] == b'e' || b[i] == b'E') {
        let mut j = i + 1;
        if j < b.len() && (b[j] == b'+' || b[j] == b'-') {
            j += 1;
        }
        if j < b.len() && b[j].is_ascii_digit() {
            i = j;
            while i < b.len() && b[i].is_ascii_digit() {
                i += 1;
            }
        }
    }
    i
}

/// The end of a name starting at `i`: identifier parts joined by dots (`B1.x`).
fn name_end(b: &[u8], mut i: usize) -> usize {
    let part = |c: u8| c.is_ascii_alphanumeric() || c == b'_';
    while i < b.len() && part(b[i]) {
        i += 1;
        if i + 1 < b.len() && b[i] == b'.' && (b[i + 1].is_ascii_alphabetic() || b[i + 1] == b'_') {
            i += 1;
        }
    }
    i
}

/// Parses the tokens (precedence: `+ -` below `* /` below unary `-` below `^`, which groups
/// to the right, so `-x^2` is `-(x^2)` and `2^-x` is `2^(-x)`) and writes them out fully
/// parenthesised in the engine's syntax, which then has no precedence of its own to apply.
struct Translator<'a> {
    text: &'a str,
    symbols: &'a [&'a str],
    tokens: &'a [Token],
    at: usize,
    /// How deeply the cursor is nested now (see [`MAX_EXPRESSION_DEPTH`]).
    depth: usize,
}

impl<'a> Translator<'a> {
    fn new(text: &'a str, symbols: &'a [&'a str], tokens: &'a [Token]) -> Self {
        Translator { text, symbols, tokens, at: 0, depth: 0 }
    }

    /// The whole expression.
    fn translate(mut self) -> Result<String, ExprError> {
        let out = self.sum()?;
        match self.tokens.get(self.at) {
            None => Ok(out),
            Some(t) if t.kind == Kind::Close => Err(err(t.start, "')' without an opening '('")),
            Some(t) if t.kind == Kind::Comma => Err(err(t.start, "',' outside a function's arguments")),
            Some(t) => Err(err(t.start, format!("expected an operator before '{}'", self.slice(t)))),
        }
    }

    fn slice(&self, t: &Token) -> &'a str {
        &self.text[t.start..t.end]
    }

    /// The operator at the cursor, if it is one of `ops`.
    fn op(&self, ops: &[&str]) -> Option<&'a str> {
        let t = self.tokens.get(self.at)?;
        let s = self.slice(t);
        (t.kind == Kind::Op && ops.contains(&s)).then_some(s)
    }

    /// Where the next token starts (the end of the text after the last).
    fn here(&self) -> usize {
        self.tokens.get(self.at).map_or(self.text.len(), |t| t.start)
    }

    /// Terms joined by `+ -` (written flat: the engine groups them left to right).
    fn sum(&mut self) -> Result<String, ExprError> {
        self.chain(&["+", "-"], Self::product)
    }

    /// Factors joined by `* /` (written flat, as a sum is).
    fn product(&mut self) -> Result<String, ExprError> {
        self.chain(&["*", "/"], Self::unary)
    }

    /// Operands read by `operand`, joined by the left-associative operators `ops` of one
    /// precedence, in one pair of parentheses (one level for the engine however long the chain).
    fn chain(
        &mut self,
        ops: &[&str],
        operand: fn(&mut Self) -> Result<String, ExprError>,
    ) -> Result<String, ExprError> {
        let first = operand(self)?;
        if self.op(ops).is_none() {
            return Ok(first);
        }
        let mut out = format!("({first}");
        while let Some(op) = self.op(ops) {
            self.at += 1;
            out.push_str(op);
            out.push_str(&operand(self)?);
        }
        out.push(')');
        Ok(out)
    }

    /// A signed operand, one level deeper than the operator before it.
    fn unary(&mut self) -> Result<String, ExprError> {
        self.depth += 1;
        if self.depth > MAX_EXPRESSION_DEPTH {
            return Err(err(
                self.here(),
                format!(
                    "nested deeper than {MAX_EXPRESSION_DEPTH} levels (parentheses, function calls, signs and powers)"
                ),
            ));
        }
        let out = self.signed();
        self.depth -= 1;
        out
    }

    fn signed(&mut self) -> Result<String, ExprError> {
        match self.op(&["-", "+"]) {
            Some(op) => {
                self.at += 1;
                let x = self.unary()?;
                Ok(if op == "-" { format!("(-{x})") } else { x })
            }
            None => self.power(),
        }
    }

    fn power(&mut self) -> Result<String, ExprError> {
        let base = self.primary()?;
        if self.op(&["^"]).is_some() {
            self.at += 1;
            return Ok(format!("({base}^{})", self.unary()?));
        }
        Ok(base)
    }

    fn primary(&mut self) -> Result<String, ExprError> {
        let Some(t) = self.tokens.get(self.at).copied() else {
            return Err(err(self.text.len(), "the expression ends where an operand is expected"));
        };
        self.at += 1;
        match t.kind {
            Kind::Number => {
                // Written out in full: the engine reads no exponents.
                let s = self.slice(&t);
                match s.parse::<f64>() {
                    Ok(x) if x.is_finite() => Ok(format!("{x}")),
                    _ => Err(err(t.start, format!("not a finite number: '{s}'"))),
                }
            }
            Kind::Open => {
                if self.tokens.get(self.at).is_some_and(|n| n.kind == Kind::Close) {
                    return Err(err(t.start, "empty parentheses"));
                }
                let inner = self.sum()?;
                self.close(&t)?;
                Ok(format!("({inner})"))
            }
            Kind::Name if self.tokens.get(self.at).is_some_and(|n| n.kind == Kind::Open) => self.call(&t),
            Kind::Name | Kind::Braced => self.name(&t),
            Kind::Close => Err(err(t.start, "')' where an operand is expected")),
            Kind::Comma => Err(err(t.start, "',' where an operand is expected")),
            Kind::Op => Err(err(t.start, format!("'{}' where an operand is expected", self.slice(&t)))),
        }
    }

    /// The ')' that closes the '(' token `open`.
    fn close(&mut self, open: &Token) -> Result<(), ExprError> {
        match self.tokens.get(self.at) {
            Some(t) if t.kind == Kind::Close => {
                self.at += 1;
                Ok(())
            }
            Some(t) if t.kind != Kind::Comma => {
                Err(err(t.start, format!("expected an operator or ')' before '{}'", self.slice(t))))
            }
            _ => Err(err(open.start, "'(' without a closing ')'")),
        }
    }

    /// A function call: the name `f`, then its '(' at the cursor.
    fn call(&mut self, f: &Token) -> Result<String, ExprError> {
        let name = self.slice(f);
        let Some(&(_, arity)) = FUNCTIONS.iter().find(|(n, _)| *n == name) else {
            return Err(err(f.start, format!("unknown function '{name}' (functions: {})", function_list())));
        };
        let open = self.tokens[self.at];
        self.at += 1;
        let mut a = Vec::new();
        loop {
            if self.tokens.get(self.at).is_some_and(|t| matches!(t.kind, Kind::Comma | Kind::Close)) {
                return Err(err(self.here(), "missing argument"));
            }
            a.push(self.sum()?);
            match self.tokens.get(self.at) {
                Some(t) if t.kind == Kind::Comma => self.at += 1,
                _ => break,
            }
        }
        self.close(&open)?;
        if a.len() != arity {
            return Err(err(f.start, format!("{name} takes {arity} argument(s), got {}", a.len())));
        }
        Ok(match name {
            "pow" => format!("({}^{})", a[0], a[1]),
            "hypot" => format!("sqrt({}^2+{}^2)", a[0], a[1]),
            // Infix, as the engine also reads them: its call form fails on a call of two
            // arguments in the second argument (`atan2(a, min(b, c))`, measured).
            _ if arity == 2 => format!("(({}) {name} ({}))", a[0], a[1]),
            _ => format!("{name}({})", a[0]),
        })
    }

    /// A constant or a symbol of the list, in the engine's spelling.
    fn name(&self, t: &Token) -> Result<String, ExprError> {
        let raw = self.slice(t);
        let name = if t.kind == Kind::Braced { &raw[1..raw.len() - 1] } else { raw };
        if t.kind == Kind::Name {
            if let Some((_, engine)) = CONSTANTS.iter().find(|(c, _)| *c == name) {
                return Ok(engine.to_string());
            }
            if FUNCTIONS.iter().any(|(f, _)| *f == name) {
                return Err(err(t.start, format!("function '{name}' needs its arguments in parentheses")));
            }
        }
        match self.symbols.iter().position(|s| !s.is_empty() && *s == name) {
            Some(i) => Ok(format!("v{i:0SYMBOL_DIGITS$}")),
            None => {
                let known: Vec<&str> = self.symbols.iter().copied().filter(|s| !s.is_empty()).collect();
                let known = if known.is_empty() { "none".to_string() } else { known.join(", ") };
                Err(err(
                    t.start,
                    format!(
                        "unknown symbol '{name}' (symbols here: {known}; constants: pi, e; functions: {})",
                        function_list()
                    ),
                ))
            }
        }
    }
}

fn function_list() -> String {
    FUNCTIONS.iter().map(|(f, _)| *f).collect::<Vec<_>>().join(", ")
}
