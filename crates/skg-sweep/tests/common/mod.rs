//! Helpers shared by the integration tests of skg-sweep (and, through this file, of
//! skg-cli): skg-core's scene helpers, included by path, and sweep files and results.
#![allow(dead_code)]

use std::path::{Path, PathBuf};

#[path = "../../../skg-core/tests/common/mod.rs"]
mod scenes;

pub use scenes::*;

/// Write `dir/sweep.toml` whose base scene is `scene`, followed by `body`.
pub fn sweep_file(dir: &Path, scene: &Path, body: &str) -> PathBuf {
    let p = dir.join("sweep.toml");
    let text = format!("[sweep]\nscene = \"{}\"\n{body}", scene.display());
    std::fs::write(&p, text).unwrap();
    p
}

/// Rows of a results directory's `results.csv` by id (each line must have the header's
/// field count and the file must end with a complete line).
pub fn rows_by_id(dir: &Path) -> (skg_sweep::Results, std::collections::HashMap<String, usize>) {
    let text = std::fs::read_to_string(dir.join("results.csv")).unwrap();
    assert!(text.ends_with('\n'), "results.csv ends with a complete line");
    let r = skg_sweep::Results::read(dir).unwrap();
    let id = r.column_index("id").unwrap();
    let mut count = std::collections::HashMap::new();
    for row in &r.rows {
        assert_eq!(row.len(), r.header.len());
        *count.entry(row[id].clone()).or_insert(0) += 1;
    }
    (r, count)
}
