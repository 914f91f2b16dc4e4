//! The order study of the dissipative operators on conservative scenes: the table of
//! docs/validation.md ("The dissipative operators on conservative scenes").
//!
//! For each scene and centred operator of the study (the rolling disk, the knife edge and
//! the pendulum; SBP121 … SBP484) and its dissipative sibling `…-AD`, one global solve
//! per grid of its ladder (strong initial velocity, Newton backend), the largest error
//! of the coordinates against the truth (a closed form, or a Runge–Kutta integration of
//! the equation derived by hand; last two nodes excluded) and the least-squares order
//! over the ladder. It prints a Markdown table; a grid whose solve does not converge is
//! reported as a row of its own and left out of the fit. `tests/dissipative.rs` asserts
//! the same study (every dissipative order at least the centred one's, within 0.1).
//!
//! Run it with `cargo run --release -p skg-core --example dissipative_order_study`
//! (a few seconds).

#[path = "../tests/common/mod.rs"]
mod common;
#[path = "../tests/studies/order_study.rs"]
mod order_study;

use order_study::{study, ORDER_STUDY};

fn main() {
    println!("| scene | N | operator | max error (last two nodes excluded) | order | dissipative | max error | order |");
    println!("|---|---|---|---|---:|---|---|---:|");
    for &(scene, centred, ladder) in ORDER_STUDY {
        let dissipative = format!("{centred}-AD");
        let (ec, oc) = study(scene, centred, ladder, true);
        let (ed, od) = study(scene, &dissipative, ladder, true);
        let list = |e: &[f64]| e.iter().map(|e| format!("{e:.2e}")).collect::<Vec<_>>().join(", ");
        let order = |o: Option<f64>| o.map_or("—".to_string(), |o| format!("{o:.2}"));
        let ns = ladder.iter().map(|n| n.to_string()).collect::<Vec<_>>().join(", ");
        println!("| {scene} | {ns} | {centred} | {} | {} | {dissipative} | {} | {} |", list(&ec), order(oc), list(&ed), order(od));
    }
}
