//! The parser: precedence, functions, numbers, error kinds and positions, deep nesting
//! and random input without a panic; hash consing; the round trip through text; names
//! bound to expressions.

use super::*;

#[test]
fn precedence_and_associativity() {
    let v = [3.0, 2.0, 5.0, 7.0];
    assert_eq!(value("2^3^2", &v), 512.0);
    assert_eq!(value("-2^2", &v), -4.0);
    assert_eq!(value("(-2)^2", &v), 4.0);
    assert_eq!(value("1-2-3", &v), -4.0);
    assert_eq!(value("8/4/2", &v), 1.0);
    assert_eq!(value("2*pi", &v), 2.0 * std::f64::consts::PI);
    assert_eq!(value("1+2*3", &v), 7.0);
    assert_eq!(value("(1+2)*3", &v), 9.0);
    assert_eq!(value("2*3^2", &v), 18.0);
    assert_eq!(value("-x^2", &v), -9.0);
    assert_eq!(value("x^-1", &v), 1.0 / 3.0);
    assert_eq!(value("2^-1^2", &v), 0.5); // 2^(-(1^2))
    assert_eq!(value("--x", &v), 3.0);
    assert_eq!(value("+x - -y", &v), 5.0);
    assert_eq!(value("x*-y", &v), -6.0);
    assert_eq!(value("x / y * z", &v), 7.5);
    assert_eq!(value("x - y + z", &v), 6.0);
    assert_eq!(value("k*half", &v), 1.5);
    assert_eq!(value("  x\t+\ny ", &v), 5.0);
}

#[test]
fn double_star_is_a_power_with_the_precedence_of_python() {
    // Each case's value as Python (and so SymPy's printed form) means it.
    let v = [3.0, 2.0, 5.0, 7.0];
    assert_eq!(value("2**3**2", &v), 512.0);
    assert_eq!(value("-x**2", &v), -9.0);
    assert_eq!(value("2*x**2", &v), 18.0);
    assert_eq!(value("x**(-2)", &v), 1.0 / 9.0);
    assert_eq!(value("x**-1", &v), 1.0 / 3.0);
    assert_eq!(value("x**(3/2)", &v), 3f64.powf(1.5));
    assert_eq!(value("x ** 2 + y^2", &v), 13.0);
    assert_eq!(value("-x**y/2", &v), -4.5);
    // `* *` with a space is not a power
    assert_eq!(parse_err("x* *2").position, 3);
}

#[test]
fn functions_parse_and_evaluate() {
    let v: [f64; 4] = [0.3, 0.7, 1.9, 2.0];
    let (x, y) = (v[0], v[1]);
    let cases: [(&str, f64); 13] = [
        ("sin(x)", x.sin()),
        ("cos(x)", x.cos()),
        ("tan(x)", x.tan()),
        ("exp(x)", x.exp()),
        ("log(x)", x.ln()),
        ("sqrt(x)", x.sqrt()),
        ("abs(-x)", x.abs()),
        ("sinh(x)", x.sinh()),
        ("cosh(x)", x.cosh()),
        ("tanh(x)", x.tanh()),
        ("atan(x)", x.atan()),
        ("atan2(y, -x)", y.atan2(-x)),
        ("sin(cos(x)*y)^2", ((x.cos() * y).sin()).powi(2)),
    ];
    for (src, want) in cases {
        let got = value(src, &v);
        assert!(close(got, want, 1e-15), "{src}: {got} vs {want}");
    }
}

#[test]
fn numbers_in_all_formats() {
    for (src, want) in [
        ("1", 1.0),
        ("2.5", 2.5),
        ("1e-3", 1e-3),
        ("1E3", 1e3),
        ("1e+3", 1e3),
        (".5", 0.5),
        ("5.", 5.0),
        ("1.5e2", 150.0),
        (".5e1", 5.0),
        ("007", 7.0),
        ("0.1", 0.1),
    ] {
        assert_eq!(value(src, &[]), want, "{src}");
    }
}

#[test]
fn error_kinds_and_positions() {
    use ParseErrorKind::*;
    let cases: [(&str, ParseErrorKind, usize); 22] = [
        ("x + * y", UnexpectedToken, 4),
        ("sin(x", MissingCloseParen, 5),
        ("(x + y", MissingCloseParen, 6),
        ("(x y)", MissingCloseParen, 3),
        ("foo(x)", UnknownFunction, 0),
        ("x + q", UnknownSymbol, 4),
        ("x + sin", UnknownSymbol, 4),
        ("", EmptyExpression, 0),
        ("   ", EmptyExpression, 0),
        ("x y", TrailingInput, 2),
        ("2x", TrailingInput, 1),
        ("x + ", UnexpectedEnd, 4),
        ("x + $", UnexpectedCharacter, 4),
        ("x + é + y", UnexpectedCharacter, 4),
        ("é + q", UnexpectedCharacter, 0),
        ("x)", UnmatchedCloseParen, 1),
        ("sin(x, y)", WrongArgumentCount, 0),
        ("1 + atan2(x)", WrongArgumentCount, 4),
        ("cos()", WrongArgumentCount, 0),
        ("x + 1e", InvalidNumber, 4),
        ("x + .", InvalidNumber, 4),
        ("1e999", InvalidNumber, 0),
    ];
    for (src, kind, pos) in cases {
        let err = parse_err(src);
        assert_eq!((err.kind, err.position), (kind, pos), "`{src}`: {err}");
        assert_eq!(err.source_text, src);
    }
    // positions count characters, not bytes
    let err = parse_err("é*é + q");
    assert_eq!(err.kind, UnexpectedCharacter);
    assert_eq!(err.position, 0);
    let err = parse_err("x*x + ψ");
    assert_eq!(err.position, 6);
    // `**` is a power like `^`: an error after it points at it as at `^`
    let err = parse_err("x** * 2");
    assert_eq!((err.kind, err.position), (UnexpectedToken, 4), "{err}");
}

#[test]
fn error_display_caret_and_hint() {
    let err = parse_err("x + q");
    assert_eq!(err.message, "unknown symbol `q`");
    assert_eq!(err.to_string(), "unknown symbol `q` at position 4 in `x + q`");
    assert_eq!(err.caret_line(), "x + q\n    ^");
    let err = err.with_hint("valid names: x, y, z, w");
    assert_eq!(err.to_string(), "unknown symbol `q` at position 4 in `x + q`; valid names: x, y, z, w");
    let err = parse_err("sin(x");
    assert_eq!(err.caret_line(), "sin(x\n     ^");
    assert!(err.message.contains("position 3"), "{}", err.message);
    let err = parse_err("foo(x)");
    assert!(err.message.contains("unknown function `foo`"), "{}", err.message);
    // A long expression is cut around the position, in the message and the caret line.
    let long = format!("{}q{}", "x + ".repeat(10_000), " + x".repeat(10_000));
    let err = parse_err(&long);
    assert_eq!(err.position, 40_000);
    // 60 characters before the position, and 60 from it (the `q` and 59 after).
    let window = format!("…{}q{}…", &"x + ".repeat(15), &" + x".repeat(15)[..59]);
    assert_eq!(err.to_string(), format!("unknown symbol `q` at position 40000 in `{window}`"));
    assert_eq!(err.caret_line(), format!("{window}\n{}^", " ".repeat(61)));
}

#[test]
fn deep_nesting_is_an_error_not_a_crash() {
    let src = format!("{}x{}", "(".repeat(100_000), ")".repeat(100_000));
    assert_eq!(parse_err(&src).kind, ParseErrorKind::TooDeep);
    let src = format!("{}x", "-".repeat(100_000));
    assert_eq!(parse_err(&src).kind, ParseErrorKind::TooDeep);
    let src = vec!["x"; 100_000].join("^");
    assert_eq!(parse_err(&src).kind, ParseErrorKind::TooDeep);
    // moderately deep is fine
    let src = format!("{}x{}", "(".repeat(150), ")".repeat(150));
    assert_eq!(value(&src, &[2.0]), 2.0);
    // long flat chains are fine, and evaluation, differentiation and rendering of the
    // resulting 100000-deep tree do not recurse
    let src = vec!["x*y"; 100_000].join(" + ");
    let mut g = Graph::new();
    let e = parse(&mut g, &src);
    assert!(close(g.eval(e, &[2.0, 3.0]), 600_000.0, 1e-12));
    let d = g.diff(e, 0);
    assert!(close(g.eval(d, &[2.0, 3.0]), 300_000.0, 1e-12));
    assert!(g.to_string(d).len() > 100_000);
    let t = Tape::compile(&g, &[e, d], 2);
    assert!(close(t.eval_vec(&[2.0, 3.0])[1], 300_000.0, 1e-12));
}

/// A random well-formed expression over x, y, z, k and pi.
fn random_expr(rng: &mut Rng, depth: usize) -> String {
    if depth == 0 || rng.below(4) == 0 {
        return ["x", "y", "z", "k", "pi", "2", "0.5", "1e-3", "0", "1"][rng.below(10)].to_string();
    }
    let a = random_expr(rng, depth - 1);
    let b = random_expr(rng, depth - 1);
    match rng.below(9) {
        0 => format!("{a} + {b}"),
        1 => format!("{a} - ({b})"),
        2 => format!("({a})*({b})"),
        3 => format!("({a})/({b})"),
        4 => format!("({a})^{}", ["2", "3", "-1", "0.5", "1.5", "y", "0", "1"][rng.below(8)]),
        5 => format!("-({a})"),
        6 => format!("atan2({a}, {b})"),
        7 => format!("({a})^({b})"),
        _ => format!("{}({a})", Func::ALL[rng.below(Func::ALL.len())].name()),
    }
}

#[test]
fn fuzz_parse_never_panics() {
    let mut rng = Rng(0x1234_5678_9abc_def1);
    let pieces = [
        "x", "y", "z", "q", "k", "pi", "1", "2.5", ".5", "1e-3", "1e", ".", "+", "-", "*", "/", "^", "(", ")", ",", " ", "sin", "atan2",
        "foo", "sqrt(", "abs(", "log", "0", "é", "$", "**",
    ];
    let mut ok = 0;
    for round in 0..20_000 {
        let src: String = if round % 3 == 2 {
            random_expr(&mut rng, 4)
        } else if round % 3 == 0 {
            let n = rng.below(40);
            let bytes: Vec<u8> = (0..n)
                .map(|_| match rng.below(3) {
                    0 => rng.next_u64() as u8,
                    _ => b"xyz+-*/^()., 0123456789esin"[rng.below(27)],
                })
                .collect();
            String::from_utf8_lossy(&bytes).into_owned()
        } else {
            (0..rng.below(16)).map(|_| pieces[rng.below(pieces.len())]).collect()
        };
        let mut g = Graph::new();
        match g.parse(&src, &mut resolver) {
            Ok(e) => {
                ok += 1;
                // everything downstream of a successful parse must work too
                let d = g.diff(e, 0);
                let d2 = g.diff(d, 1);
                let vals = g.eval_many(&[e, d, d2], &[0.3, -1.2, 2.0, 0.0]);
                let t = Tape::compile(&g, &[e, d, d2], 4);
                let tv = t.eval_vec(&[0.3, -1.2, 2.0, 0.0]);
                for (a, b) in vals.iter().zip(&tv) {
                    assert!(a == b || (a.is_nan() && b.is_nan()), "`{src}`: {a} vs {b}");
                }
                let s = g.to_string_with(e, &|i| NAMES[i].to_string());
                let again = g.parse(&s, &mut resolver).unwrap_or_else(|err| panic!("`{src}` → `{s}`: {err}"));
                let (a, b) = (g.eval(e, &[0.3, -1.2, 2.0, 0.0]), g.eval(again, &[0.3, -1.2, 2.0, 0.0]));
                assert!(a == b || (a.is_nan() && b.is_nan()) || close(a, b, 1e-12), "`{src}` → `{s}`: {a} vs {b}");
            }
            Err(err) => {
                assert!(err.position <= src.chars().count(), "`{src}`: {err}");
                let _ = err.caret_line();
            }
        }
    }
    assert!(ok > 6000, "only {ok} random inputs parsed: the fuzz test is too weak");
}

#[test]
fn hash_consing() {
    let mut g = Graph::new();
    let a = parse(&mut g, "sin(x)*y + exp(z/2)");
    let n = g.len();
    let b = parse(&mut g, "sin(x)*y + exp(z/2)");
    assert_eq!(a, b);
    assert_eq!(g.len(), n, "reparsing created nodes");
    let c = parse(&mut g, "exp(z/2) + y*sin(x)"); // commutative operands are ordered
    assert_eq!(a, c);
    let d = parse(&mut g, "sin(x)*y + exp(z/3)");
    assert_ne!(a, d);
}

#[test]
fn round_trip_through_to_string() {
    let mut g = Graph::new();
    let name = |i: usize| NAMES[i].to_string();
    for src in [
        "x - (y - z)",
        "x/(y*z)",
        "(x/y)/z",
        "x*(y*z)",
        "x + (y + z)",
        "-x^2",
        "(-x)^3",
        "x^-2",
        "x^2^y",
        "(x^2)^y",
        "-(x*y)",
        "2^x",
        "atan2(x - 1, y)*0.1 + 1e-20*z",
        "sin(-x)/cos(x)^-2.5",
        "-2*x",
        "x*-2",
        "abs(x)^0.3",
    ] {
        let e = parse(&mut g, src);
        let s = g.to_string_with(e, &name);
        let again = parse(&mut g, &s);
        assert_eq!(e, again, "`{src}` rendered as `{s}`");
    }
    let e = parse(&mut g, "x^2");
    assert_eq!(g.to_string(e), "v0^2");
}

/// A name bound to an expression of the graph stands for that expression: `r2 = x^2 + y^2`
/// used in `sqrt(r2)*z` is `sqrt(x^2 + y^2)*z`, one node with the direct parse, so its
/// derivatives are those of the expanded expression.
#[test]
fn a_name_bound_to_an_expression_parses_as_that_expression() {
    let mut g = Graph::new();
    let r2 = parse(&mut g, "x^2 + y^2");
    let mut named = |name: &str| if name == "r2" { Some(Symbol::Expr(r2)) } else { resolver(name) };
    let e = g.parse("sqrt(r2)*z", &mut named).unwrap();
    assert_eq!(e, parse(&mut g, "sqrt(x^2 + y^2)*z"));
    let dx = g.diff(e, 0);
    // d/dx sqrt(x² + y²) z = x z / sqrt(x² + y²) at (3, 4, 2): 6/5.
    assert!((g.eval(dx, &[3.0, 4.0, 2.0, 0.0]) - 1.2).abs() < 1e-15);
    // An id beyond the graph is an unknown symbol at the name's position, not a panic.
    let mut stale = |name: &str| if name == "r2" { Some(Symbol::Expr(ExprId(u32::MAX))) } else { resolver(name) };
    let err = g.parse("x + r2", &mut stale).unwrap_err();
    assert_eq!((err.kind, err.position), (ParseErrorKind::UnknownSymbol, 4));
}
