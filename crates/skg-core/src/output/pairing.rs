//! The pairing rule's check: a data file must be the one that the `summary.json` beside
//! it lists ([`verify_pairing`], [`DataFile`]).

use std::path::Path;

use indexmap::IndexMap;
use serde::{Deserialize, Serialize};

use super::{io_err, OutputError, SUMMARY_FILE};
use crate::scene::provenance;

/// What `summary.json` says about one data file of its run.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct DataFile {
    /// Data rows (without comments and the header).
    pub rows: usize,
    /// SHA-256 of the file's bytes, `sha256:<hex>`.
    pub sha256: String,
}

/// The part of `summary.json` a reader needs to check the pairing rule.
#[derive(Deserialize)]
struct ListedFiles {
    #[serde(default)]
    files: Option<IndexMap<String, DataFile>>,
}

/// Check the pairing rule for a data file read as `bytes` from `path`: if a
/// `summary.json` beside it lists the file, the bytes must be the ones it lists. A file
/// that no summary lists (a reference, a copied file, the remains of an interrupted
/// run, a summary written before the rule) passes.
pub fn verify_pairing(path: &Path, bytes: &[u8]) -> Result<(), OutputError> {
    let Some(name) = path.file_name().map(|n| n.to_string_lossy().into_owned()) else { return Ok(()) };
    let summary = path.with_file_name(SUMMARY_FILE);
    let text = match std::fs::read_to_string(&summary) {
        Ok(text) => text,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(()),
        Err(e) => return Err(io_err(&summary)(e)),
    };
    let unpaired = |message: String| OutputError::Unpaired { file: path.to_path_buf(), message };
    let listed = serde_json::from_str::<ListedFiles>(&text)
        .map_err(|e| unpaired(format!("the {} beside it cannot be read ({e}): run the solve again", summary.display())))?;
    let Some(expected) = listed.files.and_then(|mut f| f.swap_remove(&name)) else { return Ok(()) };
    let actual = provenance::content_hash(bytes);
    if actual == expected.sha256 {
        return Ok(());
    }
    Err(unpaired(format!(
        "is not the file that {} describes ({} rows, {}; this file is {actual}): the two come from different runs \
         (a write was interrupted or a file was replaced); run the solve again",
        summary.display(),
        expected.rows,
        expected.sha256
    )))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::output::{write_csv, TRAJECTORY_FILE};

    #[test]
    fn readers_accept_only_the_file_a_summary_lists() {
        let dir = tempfile::tempdir().unwrap();
        let csv = dir.path().join(TRAJECTORY_FILE);
        let listed = write_csv(&csv, None, &["t".into()], &[vec![0.0], vec![1.0]]).unwrap();
        let bytes = std::fs::read(&csv).unwrap();
        assert_eq!(listed, DataFile { rows: 2, sha256: provenance::content_hash(b"t\n0.0\n1.0\n") });
        // No summary, or one that does not list the file (a summary of an older schema): unchecked.
        verify_pairing(&csv, b"anything").unwrap();
        std::fs::write(dir.path().join(SUMMARY_FILE), r#"{"converged": true}"#).unwrap();
        verify_pairing(&csv, b"anything").unwrap();
        let summary = serde_json::json!({ "files": { TRAJECTORY_FILE: listed } });
        std::fs::write(dir.path().join(SUMMARY_FILE), summary.to_string()).unwrap();
        verify_pairing(&csv, &bytes).unwrap();
        let e = verify_pairing(&csv, b"t\n0.0\n2.0\n").unwrap_err().to_string();
        assert!(e.contains("is not the file that") && e.contains("2 rows"), "{e}");
        verify_pairing(&dir.path().join("reference.csv"), b"other").unwrap();
    }
}
