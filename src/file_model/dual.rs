//! An expression's tree, its value and its derivatives by forward differentiation (`expr.rs`):
//! the tree is evaluated with
//! hyper-dual numbers x + a e1 + b e2 + ab e1 e2 (e1^2 = e2^2 = 0), seeded with a = 1 on the
//! symbol of the first derivative and b = 1 on the second's, so that one pass gives f, df/dx_i
//! and d2f/dx_i dx_j exactly (to round-off; no step, no truncation). Its cost is one pass over
//! the tree per value, linear in the expression's size, where the symbolic engine's derivative
//! text had grown with its square and more (a prism's 18-term spring energy overflowed the
//! stack).
//!
//! The tree is read from the engine's text that `expr.rs` writes (fully parenthesised chains,
//! numbers in full, symbol `i` as `v` and its index, `PI`, `E`, the two-argument functions
//! infix: `((y) atan2 (x))`).

/// A node of an expression's tree.
#[derive(Clone, Debug, PartialEq)]
pub enum Node {
    Number(f64),
    /// Symbol `i` of the list the expression was compiled against.
    Symbol(usize),
    Negate(Box<Node>),
    Binary(Op, Box<Node>, Box<Node>),
    Call(Function, Box<Node>),
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Op {
    Add,
    Sub,
    Mul,
    Div,
    Pow,
    Min,
    Max,
    Atan2,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Function {
    Sin,
    Cos,
    Tan,
    Asin,
    Acos,
    Atan,
    Sqrt,
    Abs,
    Exp,
    Ln,
}

impl Function {
    fn named(name: &str) -> Option<Function> {
        Some(match name {
            "sin" => Function::Sin,
            "cos" => Function::Cos,
            "tan" => Function::Tan,
            "asin" => Function::Asin,
            "acos" => Function::Acos,
            "atan" => Function::Atan,
            "sqrt" => Function::Sqrt,
            "abs" => Function::Abs,
            "exp" => Function::Exp,
            "ln" => Function::Ln,
            _ => return None,
        })
    }

    /// f at `x`.
    fn apply(self, x: f64) -> f64 {
        match self {
            Function::Sin => x.sin(),
            Function::Cos => x.cos(),
            Function::Tan => x.tan(),
            Function::Asin => x.asin(),
            Function::Acos => x.acos(),
            Function::Atan => x.atan(),
            Function::Sqrt => x.sqrt(),
            Function::Abs => x.abs(),
            Function::Exp => x.exp(),
            Function::Ln => x.ln(),
        }
    }

    /// f, f' and f'' at `x`.
    fn with_derivatives(self, x: f64) -> (f64, f64, f64) {
        match self {
            Function::Sin => (x.sin(), x.cos(), -x.sin()),
            Function::Cos => (x.cos(), -x.sin(), -x.cos()),
            Function::Tan => {
                let t = x.tan();
                (t, 1.0 + t * t, 2.0 * t * (1.0 + t * t))
            }
            Function::Asin => (x.asin(), 1.0 / (1.0 - x * x).sqrt(), x / (1.0 - x * x).powf(1.5)),
            Function::Acos => (x.acos(), -1.0 / (1.0 - x * x).sqrt(), -x / (1.0 - x * x).powf(1.5)),
            Function::Atan => (x.atan(), 1.0 / (1.0 + x * x), -2.0 * x / (1.0 + x * x).powi(2)),
            Function::Sqrt => {
                let s = x.sqrt();
                (s, 0.5 / s, -0.25 / (s * x))
            }
            Function::Abs => (x.abs(), x.signum(), 0.0),
            Function::Exp => (x.exp(), x.exp(), x.exp()),
            Function::Ln => (x.ln(), 1.0 / x, -1.0 / (x * x)),
        }
    }
}

/// A hyper-dual number: a value, its derivatives along two directions and the mixed second.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HyperDual {
    pub v: f64,
    pub a: f64,
    pub b: f64,
    pub ab: f64,
}

impl HyperDual {
    fn constant(v: f64) -> Self {
        HyperDual { v, a: 0.0, b: 0.0, ab: 0.0 }
    }

    /// f(self) from f, f', f'' at the value (the chain rule to second order).
    fn chain(self, (f, d1, d2): (f64, f64, f64)) -> Self {
        HyperDual { v: f, a: d1 * self.a, b: d1 * self.b, ab: d1 * self.ab + d2 * self.a * self.b }
    }

    fn is_constant(self) -> bool {
        self.a == 0.0 && self.b == 0.0 && self.ab == 0.0
    }

    fn add(self, o: Self) -> Self {
        HyperDual { v: self.v + o.v, a: self.a + o.a, b: self.b + o.b, ab: self.ab + o.ab }
    }

    fn neg(self) -> Self {
        HyperDual { v: -self.v, a: -self.a, b: -self.b, ab: -self.ab }
    }

    fn mul(self, o: Self) -> Self {
        HyperDual {
            v: self.v * o.v,
            a: self.a * o.v + self.v * o.a,
            b: self.b * o.v + self.v * o.b,
            ab: self.ab * o.v + self.a * o.b + self.b * o.a + self.v * o.ab,
        }
    }

    fn recip(self) -> Self {
        let r = 1.0 / self.v;
        self.chain((r, -r * r, 2.0 * r * r * r))
    }

    fn pow(self, o: Self) -> Self {
        if o.is_constant() {
            let p = o.v;
            if p == 0.0 {
                return HyperDual::constant(1.0);
            }
            let x = self.v;
            return self.chain((x.powf(p), p * x.powf(p - 1.0), p * (p - 1.0) * x.powf(p - 2.0)));
        }
        // x^y = exp(y ln x).
        let exponent = o.mul(self.chain(Function::Ln.with_derivatives(self.v)));
        exponent.chain(Function::Exp.with_derivatives(exponent.v))
    }

    /// atan2(self, x): the derivatives of atan(y / x), or of -atan(x / y) where |x| < |y|
    /// (they differ from atan2 by a constant), at the value atan2(y, x).
    fn atan2(self, x: Self) -> Self {
        let turn = if x.v.abs() >= self.v.abs() {
            self.mul(x.recip()).chain(Function::Atan.with_derivatives(self.v / x.v))
        } else {
            x.mul(self.recip()).chain(Function::Atan.with_derivatives(x.v / self.v)).neg()
        };
        HyperDual { v: self.v.atan2(x.v), ..turn }
    }
}

impl Node {
    /// The value at `values` (indexed by symbol; NaN for a symbol without one).
    pub fn value(&self, values: &[f64]) -> f64 {
        match self {
            Node::Number(x) => *x,
            Node::Symbol(k) => values.get(*k).copied().unwrap_or(f64::NAN),
            Node::Negate(x) => -x.value(values),
            Node::Call(f, x) => f.apply(x.value(values)),
            Node::Binary(op, x, y) => {
                let (x, y) = (x.value(values), y.value(values));
                match op {
                    Op::Add => x + y,
                    Op::Sub => x - y,
                    Op::Mul => x * y,
                    Op::Div => x / y,
                    Op::Pow => x.powf(y),
                    Op::Min => x.min(y),
                    Op::Max => x.max(y),
                    Op::Atan2 => x.atan2(y),
                }
            }
        }
    }

    /// The value at `values` (indexed by symbol) with its derivatives along symbols `i` (the
    /// `a` part) and `j` (`b`), and the mixed second derivative (`ab`).
    pub fn eval(&self, values: &[f64], i: Option<usize>, j: Option<usize>) -> HyperDual {
        match self {
            Node::Number(x) => HyperDual::constant(*x),
            Node::Symbol(k) => HyperDual {
                v: values.get(*k).copied().unwrap_or(f64::NAN),
                a: if i == Some(*k) { 1.0 } else { 0.0 },
                b: if j == Some(*k) { 1.0 } else { 0.0 },
                ab: 0.0,
            },
            Node::Negate(x) => x.eval(values, i, j).neg(),
            Node::Call(f, x) => {
                let x = x.eval(values, i, j);
                x.chain(f.with_derivatives(x.v))
            }
            Node::Binary(op, x, y) => {
                let (x, y) = (x.eval(values, i, j), y.eval(values, i, j));
                match op {
                    Op::Add => x.add(y),
                    Op::Sub => x.add(y.neg()),
                    Op::Mul => x.mul(y),
                    Op::Div => x.mul(y.recip()),
                    Op::Pow => x.pow(y),
                    Op::Min => {
                        if y.v < x.v {
                            y
                        } else {
                            x
                        }
                    }
                    Op::Max => {
                        if y.v > x.v {
                            y
                        } else {
                            x
                        }
                    }
                    Op::Atan2 => x.atan2(y),
                }
            }
        }
    }

    /// The symbols the tree reads, ascending.
    pub fn symbols(&self) -> Vec<usize> {
        let mut out = Vec::new();
        self.collect_symbols(&mut out);
        out.sort_unstable();
        out.dedup();
        out
    }

    fn collect_symbols(&self, out: &mut Vec<usize>) {
        match self {
            Node::Number(_) => {}
            Node::Symbol(k) => out.push(*k),
            Node::Negate(x) | Node::Call(_, x) => x.collect_symbols(out),
            Node::Binary(_, x, y) => {
                x.collect_symbols(out);
                y.collect_symbols(out);
            }
        }
    }
}

/// Why a tree could not be read from an engine text.
#[derive(Clone, Debug, PartialEq)]
pub struct TreeError(pub String);

/// Reads the engine text `text` into a tree.
pub fn parse(text: &str) -> Result<Node, TreeError> {
    let mut p = Parser { b: text.as_bytes(), at: 0 };
    let node = p.expression()?;
    p.skip_space();
    if p.at != p.b.len() {
        return Err(p.error("text after the expression"));
    }
    Ok(node)
}

struct Parser<'a> {
    b: &'a [u8],
    at: usize,
}

impl Parser<'_> {
    fn error(&self, what: &str) -> TreeError {
        TreeError(format!("{what} at byte {} of the engine's text", self.at))
    }

    fn skip_space(&mut self) {
        while self.at < self.b.len() && self.b[self.at] == b' ' {
            self.at += 1;
        }
    }

    fn peek(&mut self) -> Option<u8> {
        self.skip_space();
        self.b.get(self.at).copied()
    }

    fn eat(&mut self, c: u8) -> Result<(), TreeError> {
        match self.peek() {
            Some(x) if x == c => {
                self.at += 1;
                Ok(())
            }
            _ => Err(self.error(&format!("expected '{}'", c as char))),
        }
    }

    /// A sum, or two sums joined by an infix function (`min`, `max`, `atan2`).
    fn expression(&mut self) -> Result<Node, TreeError> {
        let left = self.sum()?;
        let op = match self.word_ahead() {
            Some("min") => Op::Min,
            Some("max") => Op::Max,
            Some("atan2") => Op::Atan2,
            _ => return Ok(left),
        };
        self.skip_word();
        let right = self.sum()?;
        Ok(Node::Binary(op, Box::new(left), Box::new(right)))
    }

    fn sum(&mut self) -> Result<Node, TreeError> {
        let mut node = self.product()?;
        while let Some(c @ (b'+' | b'-')) = self.peek() {
            self.at += 1;
            let op = if c == b'+' { Op::Add } else { Op::Sub };
            node = Node::Binary(op, Box::new(node), Box::new(self.product()?));
        }
        Ok(node)
    }

    fn product(&mut self) -> Result<Node, TreeError> {
        let mut node = self.unary()?;
        while let Some(c @ (b'*' | b'/')) = self.peek() {
            self.at += 1;
            let op = if c == b'*' { Op::Mul } else { Op::Div };
            node = Node::Binary(op, Box::new(node), Box::new(self.unary()?));
        }
        Ok(node)
    }

    fn unary(&mut self) -> Result<Node, TreeError> {
        if self.peek() == Some(b'-') {
            self.at += 1;
            return Ok(Node::Negate(Box::new(self.unary()?)));
        }
        let base = self.primary()?;
        if self.peek() == Some(b'^') {
            self.at += 1;
            return Ok(Node::Binary(Op::Pow, Box::new(base), Box::new(self.unary()?)));
        }
        Ok(base)
    }

    fn primary(&mut self) -> Result<Node, TreeError> {
        match self.peek() {
            Some(b'(') => {
                self.at += 1;
                let inner = self.expression()?;
                self.eat(b')')?;
                Ok(inner)
            }
            Some(b'0'..=b'9' | b'.') => self.number(),
            Some(_) => self.named(),
            None => Err(self.error("the text ends where an operand is expected")),
        }
    }

    fn number(&mut self) -> Result<Node, TreeError> {
        let start = self.at;
        while self.at < self.b.len() && (self.b[self.at].is_ascii_digit() || self.b[self.at] == b'.') {
            self.at += 1;
        }
        let text = std::str::from_utf8(&self.b[start..self.at]).map_err(|_| self.error("not a number"))?;
        text.parse().map(Node::Number).map_err(|_| self.error("not a number"))
    }

    /// The word at the cursor (letters, digits, '_'), not consumed.
    fn word_ahead(&mut self) -> Option<&str> {
        self.skip_space();
        let end = self.word_end();
        (end > self.at).then(|| std::str::from_utf8(&self.b[self.at..end]).ok()).flatten()
    }

    fn word_end(&self) -> usize {
        let mut end = self.at;
        while end < self.b.len() && (self.b[end].is_ascii_alphanumeric() || self.b[end] == b'_') {
            end += 1;
        }
        end
    }

    fn skip_word(&mut self) {
        self.at = self.word_end();
    }

    /// A constant, a symbol or a call of a one-argument function.
    fn named(&mut self) -> Result<Node, TreeError> {
        let Some(word) = self.word_ahead().map(str::to_string) else {
            return Err(self.error("expected an operand"));
        };
        self.skip_word();
        match word.as_str() {
            "PI" => return Ok(Node::Number(std::f64::consts::PI)),
            "E" => return Ok(Node::Number(std::f64::consts::E)),
            _ => {}
        }
        if let Some(index) = word.strip_prefix('v').and_then(|d| d.parse().ok()) {
            return Ok(Node::Symbol(index));
        }
        let f = Function::named(&word).ok_or_else(|| self.error(&format!("unknown word '{word}'")))?;
        self.eat(b'(')?;
        let argument = self.expression()?;
        self.eat(b')')?;
        Ok(Node::Call(f, Box::new(argument)))
    }
}

#[cfg(test)]
mod tests {
    use crate::file_model::expr::Expr;

    /// A spring energy of two coordinates with `springs` terms, each
    /// k (sqrt((x - a)^2 + (y - b)^2 + c^2) - l)^2 / 2: a prism's natural potential's shape.
    fn springs_text(springs: usize) -> String {
        let term = |i: usize| {
            let (a, b, c, l) = (0.3 * i as f64, 1.0 - 0.1 * i as f64, 0.5 + 0.01 * i as f64, 0.9);
            format!("0.5*{k}*(sqrt((x - {a})^2 + (y - {b})^2 + {c}^2) - {l})^2", k = 100.0 + i as f64)
        };
        (0..springs).map(term).collect::<Vec<_>>().join(" + ")
    }

    /// The gradient and Hessian of an 18-spring energy (the symbolic engine had overflowed the
    /// stack on it) by forward differentiation, against central differences of its value
    /// (steps 1e-4: error about 1e-8 of the entries); a third derivative is refused.
    #[test]
    fn an_eighteen_spring_energys_hessian_meets_its_differences() {
        let symbols = ["x", "y"];
        let v = Expr::compile(&springs_text(18), &symbols).expect("compiles");
        assert!(v.size() > 1_000, "{}", v.size());
        let at = [0.37, -0.21];
        let value = |x: f64, y: f64| v.eval(&[x, y]);
        let h = 1e-4;
        for i in 0..2 {
            let g = v.derivative(i).expect("forward");
            let e = |s: f64| if i == 0 { value(at[0] + s, at[1]) } else { value(at[0], at[1] + s) };
            let fd = (e(h) - e(-h)) / (2.0 * h);
            assert!(
                (g.eval(&at) - fd).abs() <= 1e-7 * fd.abs().max(1.0),
                "dV/d{}: {} vs {fd}",
                symbols[i],
                g.eval(&at)
            );
            for j in 0..2 {
                let k = g.derivative(j).expect("second, forward").eval(&at);
                let shifted = |s: f64| {
                    let mut p = at;
                    p[j] += s;
                    g.eval(&p)
                };
                let fd = (shifted(h) - shifted(-h)) / (2.0 * h);
                assert!((k - fd).abs() <= 1e-6 * fd.abs().max(1.0), "d2V/d{}d{}: {k} vs {fd}", symbols[i], symbols[j]);
            }
            assert!(g.derivative(0).unwrap().derivative(0).is_err(), "a third derivative is refused");
        }
    }

    /// A function of two powers and a number: exmex 0.21, which had evaluated the expressions,
    /// gives sin(x^2 + y^2 + 1) = 1.0014 and sqrt(x^2 + y^2 + 1) = 1.1587 at (0.37, -0.21); the
    /// tree gives the values to round-off.
    #[test]
    fn a_function_of_two_powers_and_a_number_has_its_value() {
        let at = [0.37, -0.21];
        let inner: f64 = 0.37 * 0.37 + 0.21 * 0.21 + 1.0;
        for (text, exact) in [("sin(x^2 + y^2 + 1)", inner.sin()), ("sqrt(x^2 + y^2 + 1)", inner.sqrt())] {
            let value = Expr::compile(text, &["x", "y"]).unwrap().eval(&at);
            assert!((value - exact).abs() <= 1e-15, "{text}: {value} vs {exact}");
        }
    }

    /// Every function and operator against its closed-form derivatives at one point.
    #[test]
    fn each_function_has_its_closed_form_derivatives() {
        let symbols = ["x", "y"];
        let at = [0.4, 1.7];
        let cases: [(&str, f64, f64); 6] = [
            // (expression, d/dx, d2/dx dy) at (0.4, 1.7)
            ("sin(x)*y^3", 0.4f64.cos() * 1.7f64.powi(3), 0.4f64.cos() * 3.0 * 1.7f64.powi(2)),
            ("exp(x*y)", 1.7 * (0.68f64).exp(), (1.0 + 0.68) * (0.68f64).exp()),
            ("ln(x)*y", 1.7 / 0.4, 1.0 / 0.4),
            (
                "atan2(y, x)",
                -1.7 / (0.4 * 0.4 + 1.7 * 1.7),
                (1.7 * 1.7 - 0.4 * 0.4) / (0.4f64 * 0.4 + 1.7 * 1.7).powi(2),
            ),
            ("x^y", 1.7 * 0.4f64.powf(0.7), 0.4f64.powf(0.7) * (1.0 + 1.7 * 0.4f64.ln())),
            (
                "sqrt(x)/y + tan(x) - acos(x/2)",
                0.5 / (0.4f64.sqrt() * 1.7) + 1.0 / 0.4f64.cos().powi(2) + 0.5 / (1.0 - 0.04f64).sqrt(),
                -0.5 / (0.4f64.sqrt() * 1.7 * 1.7),
            ),
        ];
        for (text, dx, dxdy) in cases {
            let e = Expr::compile(text, &symbols).unwrap();
            let tree = super::parse(e.source()).unwrap();
            let d = tree.eval(&at, Some(0), Some(1));
            assert!((d.a - dx).abs() <= 1e-12 * dx.abs(), "{text}: d/dx {} vs {dx}", d.a);
            assert!((d.ab - dxdy).abs() <= 1e-12 * dxdy.abs(), "{text}: d2/dxdy {} vs {dxdy}", d.ab);
        }
    }
}
