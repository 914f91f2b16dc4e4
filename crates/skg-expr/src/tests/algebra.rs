//! The graph's algebra: simplification, derivatives (against finite differences, and
//! exact on the paper's expressions), substitution as composition.

use super::*;

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
