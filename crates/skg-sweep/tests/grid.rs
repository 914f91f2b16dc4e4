//! Expansion of a sweep file into points: grids, explicit points, duplicates, the peer
//! rows, indices and ids.

mod common;

use std::collections::HashSet;

use skg_sweep::{Method, SweepFile};

#[test]
fn grid_expansion_products_points_and_peer() {
    let dir = tempfile::tempdir().unwrap();
    let p = common::sweep_file(
        dir.path(),
        &common::scenario("tumbler"),
        r#"
[[grid]]
nodes = [64, 128]
operator = ["SBP121", "SBP242", "SBP363"]
sigma = "1/80"

[[grid]]
sigma = ["1/110", 0.005]

[[points]]
nodes = 256
sigma = "1/200"

[[points]]     # the same point as the first of the first grid: dropped
sigma = "1/80"
operator = "SBP121"
nodes = 64

[peer]
tolerances = [1e-6, 1e-9]
"#,
    );
    let f = SweepFile::load(&p).unwrap();
    let e = f.expand().unwrap();
    assert_eq!(e.points.len(), 6 + 2 + 1 + 2);
    assert_eq!(e.duplicates, 1);
    assert_eq!(e.axes, vec!["nodes", "operator", "sigma"]);
    // The first axis varies slowest.
    let first: Vec<(&str, &str)> = e.points[..3].iter().map(|p| (p.value("nodes").unwrap(), p.value("operator").unwrap())).collect();
    assert_eq!(first, vec![("64", "SBP121"), ("64", "SBP242"), ("64", "SBP363")]);
    assert_eq!(e.points[3].value("nodes"), Some("128"));
    assert_eq!(e.points[7].value("sigma"), Some("0.005"));
    assert_eq!(e.points[8].value("sigma"), Some("1/200"));
    assert_eq!(e.points[9].method, Method::Ode { rtol: 1e-6 });
    // Indices are positions; ids are unique and stable.
    for (k, p) in e.points.iter().enumerate() {
        assert_eq!(p.index, k);
    }
    let ids: HashSet<String> = e.points.iter().map(|p| p.id()).collect();
    assert_eq!(ids.len(), e.points.len());
    assert_eq!(f.expand().unwrap().points[4].id(), e.points[4].id());
}
