use super::*;

/// Deterministic xorshift64* generator, so the tests need no dependency.
struct Rng(u64);
impl Rng {
    fn next_u64(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    /// Uniform in [lo, hi).
    fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * ((self.next_u64() >> 11) as f64 / (1u64 << 53) as f64)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n as u64) as usize
    }
}

const NAMES: [&str; 4] = ["x", "y", "z", "w"];

/// Resolver: x, y, z, w are variables 0..4; k = 3 and half = 0.5 are constants.
fn resolver(name: &str) -> Option<Symbol> {
    match name {
        "k" => Some(Symbol::Const(3.0)),
        "half" => Some(Symbol::Const(0.5)),
        _ => NAMES.iter().position(|&n| n == name).map(Symbol::Var),
    }
}

fn parse(g: &mut Graph, src: &str) -> ExprId {
    match g.parse(src, &mut resolver) {
        Ok(e) => e,
        Err(err) => panic!("{err}\n{}", err.caret_line()),
    }
}

fn value(src: &str, vars: &[f64]) -> f64 {
    let mut g = Graph::new();
    let e = parse(&mut g, src);
    g.eval(e, vars)
}

fn parse_err(src: &str) -> ParseError {
    let mut g = Graph::new();
    match g.parse(src, &mut resolver) {
        Ok(e) => panic!("`{src}` parsed to {} but should have failed", g.to_string(e)),
        Err(err) => err,
    }
}

fn close(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * a.abs().max(b.abs()).max(1.0)
}

// ------------------------------------------------------------------ parser

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

// ------------------------------------------------------------------ simplification

#[test]
fn simplification() {
    let mut g = Graph::new();
    let c = parse(&mut g, "3*k + sin(2)");
    assert!(g.as_constant(c).is_some());
    let dc = g.diff(c, 0);
    assert!(g.is_zero(dc));
    let xy = parse(&mut g, "x*y");
    let dz = g.diff(xy, 2);
    assert!(g.is_zero(dz));
    let dx = g.diff(xy, 0);
    assert_eq!(dx, g.var(1), "d(x*y)/dx should be exactly y");
    let x2 = parse(&mut g, "x^2");
    let d = g.diff(x2, 0);
    assert_eq!(g.eval(d, &[1.5]), 3.0);
    assert_eq!(g.to_string(d), "2*v0");
    let x = g.var(0);
    let zero = g.constant(0.0);
    let one = g.constant(1.0);
    assert_eq!(g.add(x, zero), x);
    assert_eq!(g.mul(one, x), x);
    let zx = g.mul(zero, x);
    assert!(g.is_zero(zx));
    assert_eq!(g.powi(x, 1), x);
    let x0 = g.powi(x, 0);
    assert!(g.is_one(x0));
    let nx = g.neg(x);
    assert_eq!(g.neg(nx), x);
    let xmx = g.sub(x, x);
    assert!(g.is_zero(xmx));
    for (src, simple) in
        [("x + 0", "x"), ("x*1", "x"), ("x^1", "x"), ("--x", "x"), ("x/1", "x"), ("0*exp(x) + x", "x"), ("x - y + y - x + x", "x")]
    {
        let (a, b) = (parse(&mut g, src), parse(&mut g, simple));
        if src != "x - y + y - x + x" {
            assert_eq!(a, b, "{src}");
        }
    }
    let e = parse(&mut g, "2*(3*x)");
    let f = parse(&mut g, "6*x");
    assert_eq!(e, f);
    let e = parse(&mut g, "x^2.0");
    assert_eq!(g.to_string(e), "v0^2"); // integer powers become Powi
    let e = parse(&mut g, "sin(w)*x + 0*y");
    assert_eq!(g.variables(e), vec![0, 3]);
}

// ------------------------------------------------------------------ derivatives

/// Expressions covering every function and operator, with the points where they are
/// tested (each variable drawn from [0.5, 1.5]).
const DIFF_EXPRS: [&str; 16] = [
    "x*y + y/z - x*z^3",
    "sin(x*y) + cos(y - z)^2 + tan(x/2)",
    "exp(-x^2*y) / (1 + z^2)",
    "log(1 + x^2*y) - sqrt(x + y*z)",
    "abs(x - 3)*y + abs(y*z + 2)",
    "sinh(x*y) - cosh(z)/tanh(x + 1) + atan(x*z - y)",
    "atan2(y - x, z + 1) * atan2(x, -y)",
    "x^y + (1 + y^2)^(x*z)",
    "x^2.5 - z^-1.3 + y^-3 + (x*y)^0.5",
    "2^(x*y) - pi^z",
    "-(x*y - z)^3 / -(x + y)",
    "((x + y)^2 - (x - y)^2) / (4*x*y + z)",
    "1/2*M*(x_dot^2 + y_dot^2) + 1/2*IS*theta_dot^2 + 1/2*ID*phi_dot^2 + M*g*x*sin(alpha)",
    "x_dot*sin(phi) - y_dot*cos(phi)",
    "V0/sqrt(2*pi*sigma^2)*exp(-(x^2 + y^2 - R^2)^2/(2*sigma^2))",
    "w*exp(-w*x)*cos(y*w)^3 + sqrt(z^2 + w^2)",
];

/// Variables of the test expressions (the rolling disk's and the wall's included) and
/// their constants.
const DIFF_VARS: [&str; 10] = ["x", "y", "z", "w", "x_dot", "y_dot", "theta_dot", "phi_dot", "phi", "theta"];

fn diff_resolver(name: &str) -> Option<Symbol> {
    let consts = [("M", 1.3), ("IS", 0.4), ("ID", 0.2), ("g", 9.81), ("alpha", 0.3), ("V0", 2.0), ("sigma", 0.7), ("R", 1.1)];
    if let Some(&(_, c)) = consts.iter().find(|(n, _)| *n == name) {
        return Some(Symbol::Const(c));
    }
    DIFF_VARS.iter().position(|&n| n == name).map(Symbol::Var)
}

/// Central finite difference of `e` along variable `v` at `p`.
fn fd(g: &Graph, e: ExprId, v: usize, p: &[f64]) -> f64 {
    let h = 1e-6 * p[v].abs().max(1.0);
    let (mut lo, mut hi) = (p.to_vec(), p.to_vec());
    lo[v] -= h;
    hi[v] += h;
    (g.eval(e, &hi) - g.eval(e, &lo)) / (hi[v] - lo[v])
}

fn check_derivative(g: &Graph, f: ExprId, df: ExprId, v: usize, p: &[f64], what: &str) {
    let sym = g.eval(df, p);
    let num = fd(g, f, v, p);
    let scale = g.eval(f, p).abs().max(sym.abs()).max(1.0);
    assert!(sym.is_finite(), "{what}: not finite at {p:?}");
    assert!((sym - num).abs() <= 1e-7 * scale, "{what} wrt var {v} at {p:?}: symbolic {sym}, finite difference {num}");
}

#[test]
fn derivatives_match_finite_differences() {
    let mut g = Graph::new();
    let mut rng = Rng(42);
    let mut checked = 0;
    for src in DIFF_EXPRS {
        let e = g.parse(src, &mut diff_resolver).unwrap_or_else(|err| panic!("{err}"));
        let vars = g.variables(e);
        assert!(!vars.is_empty(), "{src}");
        for _ in 0..5 {
            let p: Vec<f64> = (0..DIFF_VARS.len()).map(|_| rng.uniform(0.5, 1.5)).collect();
            for &i in &vars {
                let di = g.diff(e, i);
                check_derivative(&g, e, di, i, &p, &format!("d/d{} {src}", DIFF_VARS[i]));
                for &j in &vars {
                    let dij = g.diff(di, j);
                    check_derivative(&g, di, dij, j, &p, &format!("d²/d{}d{} {src}", DIFF_VARS[i], DIFF_VARS[j]));
                    // symmetry of the Hessian
                    let dj = g.diff(e, j);
                    let dji = g.diff(dj, i);
                    assert!(close(g.eval(dij, &p), g.eval(dji, &p), 1e-12), "Hessian asymmetry in {src}");
                    for &k in vars.iter().take(3) {
                        let dijk = g.diff(dij, k);
                        check_derivative(&g, dij, dijk, k, &p, &format!("third derivative {i}{j}{k} of {src}"));
                        checked += 1;
                    }
                }
            }
        }
    }
    assert!(checked > 1000, "{checked}");
}

#[test]
fn derivatives_of_paper_expressions_are_exact() {
    let mut g = Graph::new();
    let l = g.parse(DIFF_EXPRS[12], &mut diff_resolver).unwrap_or_else(|err| panic!("{err}"));
    let (x, xd, phi, phid) = (0, 4, 8, 7);
    // dL/dx = M g sin(alpha), a constant; d²L/dx_dot² = M; d²L/dphi_dot² = ID
    let dx = g.diff(l, x);
    assert!(close(g.as_constant(dx).unwrap(), 1.3 * 9.81 * 0.3f64.sin(), 1e-15));
    let dxd = g.diff(l, xd);
    let dxdxd = g.diff(dxd, xd);
    assert_eq!(g.as_constant(dxdxd), Some(1.3));
    let dpd = g.diff(l, phid);
    let dpdpd = g.diff(dpd, phid);
    assert_eq!(g.as_constant(dpdpd), Some(0.2));
    let dphi = g.diff(l, phi);
    assert!(g.is_zero(dphi));
    // the constraint x_dot sin(phi) - y_dot cos(phi)
    let c = g.parse(DIFF_EXPRS[13], &mut diff_resolver).unwrap();
    let dc = g.diff(c, phi);
    let want = g.parse("x_dot*cos(phi) + y_dot*sin(phi)", &mut diff_resolver).unwrap();
    let p = [0.0, 0.0, 0.0, 0.0, 0.7, -0.4, 0.0, 0.0, 1.1, 0.0];
    assert_eq!(g.eval(dc, &p), g.eval(want, &p));
}

// ------------------------------------------------------------------ tapes

/// All outputs of the derivative tests: every expression, its gradient, Hessian and some
/// third derivatives.
fn many_outputs(g: &mut Graph) -> Vec<ExprId> {
    let mut outs = Vec::new();
    for src in DIFF_EXPRS {
        let e = g.parse(src, &mut diff_resolver).unwrap();
        outs.push(e);
        let vars = g.variables(e);
        for &i in &vars {
            let di = g.diff(e, i);
            outs.push(di);
            for &j in &vars {
                let dij = g.diff(di, j);
                outs.push(dij);
                let dijj = g.diff(dij, j);
                outs.push(dijj);
            }
        }
    }
    outs
}

#[test]
fn tape_matches_graph_eval() {
    let mut g = Graph::new();
    let mut outs = many_outputs(&mut g);
    // constant and plain-variable outputs, and repeats
    outs.push(g.constant(2.5));
    outs.push(g.var(3));
    outs.push(outs[0]);
    let n_vars = DIFF_VARS.len();
    let tape = Tape::compile(&g, &outs, n_vars);
    assert_eq!(tape.n_outputs(), outs.len());
    assert_eq!(tape.n_vars(), n_vars);
    let mut scratch = vec![f64::NAN; tape.scratch_len()];
    let mut out = vec![0.0; outs.len()];
    let mut rng = Rng(7);
    for _ in 0..50 {
        let p: Vec<f64> = (0..n_vars).map(|_| rng.uniform(0.5, 1.5)).collect();
        tape.eval(&p, &mut scratch, &mut out);
        let want = g.eval_many(&outs, &p);
        for (k, (a, b)) in out.iter().zip(&want).enumerate() {
            assert!(a.is_finite(), "output {k}");
            assert!((a - b).abs() <= 1e-15 * b.abs(), "output {k}: tape {a}, graph {b}");
        }
        assert_eq!(out[outs.len() - 3], 2.5);
        assert_eq!(out[outs.len() - 2], p[3]);
        assert_eq!(out[outs.len() - 1], out[0]);
    }
    // registers are reused: far fewer than instructions
    assert!(tape.scratch_len() < tape.len() / 2, "{} registers for {} instructions", tape.scratch_len(), tape.len());
}

#[test]
fn tape_cse_across_outputs() {
    let mut g = Graph::new();
    let e = g.parse(DIFF_EXPRS[14], &mut diff_resolver).unwrap();
    let d = g.diff(e, 0);
    let single = |outs: &[ExprId]| Tape::compile(&g, outs, DIFF_VARS.len()).len();
    let separate = single(&[e]) + single(&[e]) + single(&[d]);
    let joint = single(&[e, e, d]);
    assert!(joint < separate, "joint {joint} vs separate {separate}");
    assert!(joint <= single(&[d]) + 2, "e should be almost free given its derivative: {joint} vs {}", single(&[d]));
    // every node is computed at most once
    let outs = many_outputs(&mut g);
    let nodes: usize = g.reachable(&outs).iter().filter(|&&n| g.as_constant(n).is_none()).count();
    assert!(Tape::compile(&g, &outs, DIFF_VARS.len()).len() <= nodes);
}

#[test]
fn tape_edge_cases() {
    let mut g = Graph::new();
    let c = g.constant(-1.5);
    let x = g.var(1);
    let t = Tape::compile(&g, &[c, x], 2);
    assert_eq!(t.len(), 1); // the load of x
    assert_eq!(t.eval_vec(&[10.0, 20.0]), vec![-1.5, 20.0]);
    let t = Tape::compile(&g, &[], 0);
    assert!(t.is_empty());
    assert_eq!(t.eval_vec(&[]), Vec::<f64>::new());
    // operations whose constant operands need registers
    let e = g.parse("atan2(2, x) + atan2(y, 3) + 2^y + 1.5^x + 2/x - (1 - x) + x/4", &mut resolver).unwrap();
    let t = Tape::compile(&g, &[e], 2);
    let p = [0.8, 1.7];
    assert!((t.eval_vec(&p)[0] - g.eval(e, &p)).abs() <= 1e-15 * g.eval(e, &p).abs());
    // scratch longer than needed and reused without clearing
    let mut scratch = vec![123.0; t.scratch_len() + 5];
    let mut out = [0.0];
    t.eval(&p, &mut scratch, &mut out);
    t.eval(&p, &mut scratch, &mut out);
    assert_eq!(out[0], t.eval_vec(&p)[0]);
}

#[test]
#[should_panic(expected = "n_vars")]
fn tape_rejects_too_few_variables() {
    let mut g = Graph::new();
    let e = g.parse("x*z", &mut resolver).unwrap();
    let _ = Tape::compile(&g, &[e], 2);
}

/// Timing of the tapes a solver would build (run with `--ignored --nocapture`).
#[test]
#[ignore]
fn tape_performance() {
    use std::time::Instant;
    let mut g = Graph::new();
    let n_vars = DIFF_VARS.len();
    let report = |name: &str, outs: Vec<ExprId>, g: &Graph| {
        let tape = Tape::compile(g, &outs, n_vars);
        if std::env::var("SHOW_TAPE").is_ok() {
            println!("{tape:#?}");
        }
        let mut scratch = vec![0.0; tape.scratch_len()];
        let mut out = vec![0.0; outs.len()];
        let mut p: Vec<f64> = (0..n_vars).map(|i| 0.5 + 0.1 * i as f64).collect();
        let iters = 100_000;
        let mut acc = 0.0;
        let mut ns = f64::INFINITY;
        for _rep in 0..7 {
            let t0 = Instant::now();
            for it in 0..iters {
                p[0] = 0.5 + 1e-7 * it as f64;
                tape.eval(&p, &mut scratch, &mut out);
                acc += out[out.len() - 1];
            }
            ns = ns.min(t0.elapsed().as_nanos() as f64 / iters as f64);
        }
        println!(
            "{name}: {} outputs, {} instructions in {} runs, {} registers: {ns:.1} ns/eval ({:.2} ns/instruction) [{acc:.3}]",
            outs.len(),
            tape.len(),
            tape.n_runs(),
            tape.scratch_len(),
            ns / tape.len().max(1) as f64
        );
    };
    let all: Vec<usize> = (0..n_vars).collect();
    for (name, src) in [("disk Lagrangian", 12), ("constraint", 13), ("Gaussian wall", 14), ("mixed", 5)] {
        let e = g.parse(DIFF_EXPRS[src], &mut diff_resolver).unwrap();
        let vars = g.variables(e);
        let mut outs = vec![e];
        outs.extend(g.gradient(e, &vars));
        outs.extend(g.hessian(e, &vars));
        report(&format!("{name} value+gradient+Hessian"), outs.clone(), &g);
        for &i in &vars {
            for &j in &vars {
                let h = g.hessian(e, &all)[i * n_vars + j];
                for &k in &vars {
                    outs.push(g.diff(h, k));
                }
            }
        }
        report(&format!("{name} + third derivatives"), outs, &g);
    }
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

/// Substitution agrees with evaluating the outer expression at the inner ones' values,
/// for every kind of node, and folds what becomes constant.
#[test]
fn substitution_is_composition() {
    let mut g = Graph::new();
    let outer = parse(&mut g, "sin(x)*y^3 - exp(x/y) + atan2(y, x)^z + abs(x) + -tanh(w) - x^(1/3)");
    let (a, b) = (parse(&mut g, "z*w + 1"), parse(&mut g, "cos(z) + 2"));
    let composed = g.substitute(outer, &[(0, a), (1, b)]);
    let mut rng = Rng(7);
    for _ in 0..20 {
        let (z, w) = (rng.uniform(0.1, 1.0), rng.uniform(0.1, 1.0));
        let inner = [g.eval(a, &[0.0, 0.0, z, w]), g.eval(b, &[0.0, 0.0, z, w])];
        let direct = g.eval(outer, &[inner[0], inner[1], z, w]);
        let got = g.eval(composed, &[0.0, 0.0, z, w]);
        assert!((got - direct).abs() <= 1e-14 * direct.abs().max(1.0), "{got} vs {direct}");
    }
    assert!(!g.variables(composed).iter().any(|&v| v < 2), "x and y are gone");
    // Substituting constants folds the expression to a constant.
    let two = g.constant(2.0);
    let square = parse(&mut g, "x*x + 1");
    let folded = g.substitute(square, &[(0, two)]);
    assert_eq!(g.as_constant(folded), Some(5.0));
    // No substitution, no change.
    assert_eq!(g.substitute(outer, &[]), outer);
}
