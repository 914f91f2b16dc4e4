//! Compiled tapes: the same values as the graph's evaluation, common subexpressions
//! shared across outputs, edge cases, too few variables refused, and their speed.

use super::*;

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
