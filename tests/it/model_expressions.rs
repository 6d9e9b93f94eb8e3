//! The expression engine of a scenario file's model (`model::expr`): values, symbolic
//! derivatives and errors located at a byte offset inside the expression.

use std::f64::consts::{E, PI};
use tensegrity_testbed::file_model::expr::Expr;

/// Round-off allowed on a value computed by the engine against the same formula in Rust.
const EVAL_TOL: f64 = 1e-14;

fn eval(text: &str, symbols: &[&str], values: &[f64]) -> f64 {
    Expr::compile(text, symbols).unwrap_or_else(|e| panic!("{text}: {e}")).eval(values)
}

/// A call of two arguments inside the second argument of another (the engine's own call form
/// failed on `atan2(a, min(b, c))` with "parentheses mismatch"; the expansion of `min(c in
/// cables, ...)` nests that way).
#[test]
fn two_argument_calls_nest_in_either_argument() {
    let (a, b, c): (f64, f64, f64) = (1.0, 2.0, 3.0);
    let s = ["a", "b", "c"];
    let cases: &[(&str, f64)] = &[
        ("atan2(a, atan2(b, c))", a.atan2(b.atan2(c))),
        ("min(a, min(b, c))", a.min(b.min(c))),
        ("max(min(a, b), max(b, hypot(a, c)))", a.min(b).max(b.max(a.hypot(c)))),
        ("pow(a + 1, min(b, c)) * 2", (a + 1.0).powf(b.min(c)) * 2.0),
    ];
    for (text, expected) in cases {
        let got = eval(text, &s, &[a, b, c]);
        assert!((got - expected).abs() <= EVAL_TOL, "{text}: {got} against {expected}");
    }
}

/// Every function and constant of the grammar evaluates as its Rust counterpart, with the
/// usual precedence (`-x^2` is `-(x^2)`, `^` groups to the right, `-` and `/` to the left).
#[test]
fn functions_and_constants_evaluate_as_in_rust() {
    let (x, y): (f64, f64) = (0.3, -1.7);
    let s = ["x", "y"];
    let cases: &[(&str, f64)] = &[
        ("sin(x) + cos(y) * tan(x)", x.sin() + y.cos() * x.tan()),
        ("asin(x) - acos(x) + atan(y)", x.asin() - x.acos() + y.atan()),
        ("atan2(y, x)", y.atan2(x)),
        ("sqrt(x) * hypot(x, y)", x.sqrt() * x.hypot(y)),
        ("abs(y) + min(x, y) - max(x, y)", y.abs() + x.min(y) - x.max(y)),
        ("pow(x, 2.5) + x^3", x.powf(2.5) + x.powi(3)),
        ("exp(y) + ln(x)", y.exp() + x.ln()),
        ("pi/2 + pi/3", PI / 2.0 + PI / 3.0),
        ("e^2", E * E),
        ("-x^2", -(x * x)),
        ("2^3^2", 512.0),
        ("2^-x", 2f64.powf(-x)),
        ("8/4/2 - 1 - 2 - 3", 1.0 - 6.0),
        ("2*-y", 2.0 * -y),
        ("1e-3 * x + 2.5E2", 1e-3 * x + 2.5e2),
        ("(x + y) * (x - y) / 4", (x + y) * (x - y) / 4.0),
    ];
    for (text, want) in cases {
        let got = eval(text, &s, &[x, y]);
        assert!((got - want).abs() <= EVAL_TOL * want.abs().max(1.0), "{text}: {got} != {want}");
    }
}

/// Dotted names (`B1.x`, `side1.force`) and names between braces are symbols; the values come
/// in the order of the symbol list, whatever order the expression names them in.
#[test]
fn symbols_are_read_in_the_order_of_the_list() {
    let s = ["side1.force", "B1.x", "spring AD.force", "k"];
    let got = eval("B1.x - side1.force / k + {spring AD.force}", &s, &[10.0, 3.0, 0.5, 4.0]);
    assert!((got - (3.0 - 10.0 / 4.0 + 0.5)).abs() <= EVAL_TOL, "{got}");
    let e = Expr::compile("k * B1.x", &s).unwrap();
    assert_eq!(e.uses(), &[1, 3]);
}

/// Eleven and more symbols keep their order (the engine sorts its variables by name).
#[test]
fn many_symbols_keep_their_order() {
    let names: Vec<String> = (0..25).map(|i| format!("s{i}")).collect();
    let s: Vec<&str> = names.iter().map(String::as_str).collect();
    let values: Vec<f64> = (0..25).map(|i| i as f64).collect();
    let text = "s2 + 10*s10 + 100*s24 + 1000*s9";
    assert_eq!(eval(text, &s, &values), 2.0 + 100.0 + 2400.0 + 9000.0);
}

/// The symbolic derivative of a smooth expression agrees with the hand-derived one within
/// 1e-12; a symbol the expression does not use has derivative zero.
#[test]
fn symbolic_derivatives_agree_with_hand_derived_ones() {
    let s = ["q", "k", "L"];
    // Energy of a pendulum spring: V = k/2 (L sin q - 1)^2 + cos(q).
    let v = Expr::compile("k/2*(L*sin(q) - 1)^2 + cos(q)", &s).unwrap();
    let (q, k, l): (f64, f64, f64) = (0.7, 3.0, 1.3);
    let x = [q, k, l];
    let dv = v.derivative(0).unwrap();
    let want = k * (l * q.sin() - 1.0) * l * q.cos() - q.sin();
    assert!((dv.eval(&x) - want).abs() <= 1e-12, "{} != {want}", dv.eval(&x));
    let d2v = dv.derivative(0).unwrap();
    let want2 = k * l * l * q.cos().powi(2) - k * (l * q.sin() - 1.0) * l * q.sin() - q.cos();
    assert!((d2v.eval(&x) - want2).abs() <= 1e-12, "{} != {want2}", d2v.eval(&x));
    let dk = v.derivative(1).unwrap();
    assert!((dk.eval(&x) - 0.5 * (l * q.sin() - 1.0).powi(2)).abs() <= 1e-12);
    let none = Expr::compile("k*q", &s).unwrap().derivative(2).unwrap();
    assert_eq!(none.eval(&x), 0.0);
    // hypot and pow are rewritten into differentiable forms.
    let h = Expr::compile("hypot(q, L) + pow(q, 3)", &s).unwrap().derivative(0).unwrap();
    let want_h = q / q.hypot(l) + 3.0 * q * q;
    assert!((h.eval(&x) - want_h).abs() <= 1e-12, "{} != {want_h}", h.eval(&x));
}

/// atan2, which the symbolic engine could not differentiate, has its closed-form derivatives
/// (taken forward): d/dx atan2(y, x) = -y / (x^2 + y^2) and d2/dx dy = (y^2 - x^2) / (x^2 + y^2)^2,
/// within 1e-15, on either side of the line where atan(y / x) would divide by zero; a third
/// derivative is refused.
#[test]
fn a_derivative_through_atan2_is_its_closed_form() {
    let e = Expr::compile("atan2(y, x)", &["x", "y"]).unwrap();
    let (dx, dxdy) = (e.derivative(0).unwrap(), e.derivative(0).unwrap().derivative(1).unwrap());
    for (x, y) in [(0.4, 1.7), (1.7, -0.4), (0.0, 2.0)] {
        let r2: f64 = x * x + y * y;
        assert!((dx.eval(&[x, y]) + y / r2).abs() <= 1e-15, "({x}, {y})");
        assert!((dxdy.eval(&[x, y]) - (y * y - x * x) / (r2 * r2)).abs() <= 1e-15, "({x}, {y})");
    }
    assert!(dxdy.derivative(0).unwrap_err().message.contains("third order"));
}

/// Each error names the byte offset where it lies and what exists there.
#[test]
fn errors_carry_their_byte_offset() {
    let s = ["r", "B1.x"];
    let cases: &[(&str, usize, &str)] = &[
        ("2*r + q", 6, "unknown symbol 'q' (symbols here: r, B1.x; constants: pi, e; functions: sin"),
        ("r + sinh(r)", 4, "unknown function 'sinh'"),
        ("atan2(r)", 0, "atan2 takes 2 argument(s), got 1"),
        ("(r + 1", 0, "'(' without a closing ')'"),
        ("r + 1)", 5, "')' without an opening '('"),
        ("r # 2", 2, "unexpected character '#'"),
        ("sqrt + 1", 0, "function 'sqrt' needs its arguments in parentheses"),
        ("max(r, )", 7, "missing argument"),
        ("r, 1", 1, "',' outside a function's arguments"),
        ("  ", 0, "empty expression"),
        ("B1.y", 0, "unknown symbol 'B1.y'"),
    ];
    for (text, offset, msg) in cases {
        let e = Expr::compile(text, &s).expect_err(text);
        assert_eq!(e.offset, *offset, "{text}: {e}");
        assert!(e.message.contains(msg), "{text}: {}", e.message);
    }
}

/// A hidden symbol (an empty name in the list) cannot be named, and is not listed.
#[test]
fn hidden_symbols_are_unknown() {
    let e = Expr::compile("a + b", &["a", ""]).unwrap_err();
    assert_eq!(e.offset, 4);
    assert!(e.message.contains("symbols here: a;"), "{}", e.message);
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(2000))]
    /// Any text from the grammar's characters compiles or fails with an offset inside it
    /// (never a panic); what compiles evaluates, and its derivative compiles or fails cleanly.
    #[test]
    fn arbitrary_text_never_panics(text in "[xy0-9.eE+*/^(),{} -]{0,12}|[a-z0-9 .(),+*/^-]{0,16}") {
        match Expr::compile(&text, &["x", "y", "pi2"]) {
            Ok(e) => {
                let _ = e.eval(&[0.5, -1.5, 2.0]);
                if let Ok(d) = e.derivative(0) {
                    let _ = d.eval(&[0.5, -1.5, 2.0]);
                }
            }
            Err(err) => proptest::prop_assert!(err.offset <= text.len(), "{err} for {text:?}"),
        }
    }
}
