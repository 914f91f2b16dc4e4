//! The pairing rule's check: a data file must be the one that the `summary.json` beside
//! it lists ([`verify_pairing`], [`DataFile`]).

use std::path::Path;

use indexmap::IndexMap;
use serde::{Deserialize, Serialize};

use super::{io_err, OutputError, REFERENCE_FILE, SUMMARY_FILE, TRAJECTORY_FILE};
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

/// How a data file stands to the `summary.json` beside it, when the pairing rule allows
/// reading it ([`verify_pairing`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Pairing {
    /// The summary lists the file, with these very bytes, and every other file it lists
    /// is there: the file is the run's.
    Listed,
    /// No summary is beside the file (a CSV from elsewhere, a reference written by
    /// `skg-solve reference`): it is read as it is, but cannot be checked against a run.
    NoSummary,
    /// A summary is beside the file but does not list it, and the file is not one of the
    /// files a solve writes (a reference of another name written into a solve's
    /// directory): it cannot be checked against a run either.
    Unlisted,
}

impl Pairing {
    /// For a file read as a run's solution: the warning that it cannot be checked against
    /// a run, if it cannot.
    pub fn warning(self, path: &Path) -> Option<String> {
        match self {
            Pairing::Listed => None,
            Pairing::NoSummary => Some(format!(
                "{} has no {SUMMARY_FILE} beside it: it is read as it is, and cannot be checked against the run that wrote it",
                path.display()
            )),
            Pairing::Unlisted => Some(format!(
                "the {SUMMARY_FILE} beside {} does not list it: it is read as it is, and cannot be checked against a run",
                path.display()
            )),
        }
    }
}

/// Check the pairing rule for a data file read as `bytes` from `path`. Without a
/// `summary.json` beside it the file is read as it is ([`Pairing::NoSummary`]). With one:
/// * a file it lists must have the bytes it lists, and every other file it lists must be
///   there (a `reference.csv` listed but deleted is refused, naming both files);
/// * a file it does not list is refused if it is one of the files a solve writes
///   (`trajectory.csv`, `reference.csv`: beside a summary that does not list it, it comes
///   from another run, or the summary from a version before the rule), and otherwise
///   read as [`Pairing::Unlisted`].
pub fn verify_pairing(path: &Path, bytes: &[u8]) -> Result<Pairing, OutputError> {
    let Some(name) = path.file_name().map(|n| n.to_string_lossy().into_owned()) else { return Ok(Pairing::NoSummary) };
    let summary = path.with_file_name(SUMMARY_FILE);
    let text = match std::fs::read_to_string(&summary) {
        Ok(text) => text,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Pairing::NoSummary),
        Err(e) => return Err(io_err(&summary)(e)),
    };
    let unpaired = |message: String| OutputError::Unpaired { file: path.to_path_buf(), message };
    let listed = serde_json::from_str::<ListedFiles>(&text)
        .map_err(|e| unpaired(format!("the {} beside it cannot be read ({e}): run the solve again", summary.display())))?;
    let mut files = listed.files.unwrap_or_default();
    let Some(expected) = files.swap_remove(&name) else {
        if [TRAJECTORY_FILE, REFERENCE_FILE].contains(&name.as_str()) {
            return Err(unpaired(format!(
                "the {} beside it does not list {name}, so the two do not come from one run (or the summary was written \
                 by a version before the pairing rule): run the solve again",
                summary.display()
            )));
        }
        return Ok(Pairing::Unlisted);
    };
    let actual = provenance::content_hash(bytes);
    if actual != expected.sha256 {
        return Err(unpaired(format!(
            "is not the file that {} describes ({} rows, {}; this file is {actual}): the two come from different runs \
             (a write was interrupted or a file was replaced); run the solve again",
            summary.display(),
            expected.rows,
            expected.sha256
        )));
    }
    if let Some(missing) = files.keys().map(|other| path.with_file_name(other)).find(|p| !p.is_file()) {
        return Err(unpaired(format!(
            "the {} beside it lists {}, which is missing: the run's files are incomplete (one was deleted or moved); \
             run the solve again",
            summary.display(),
            missing.display()
        )));
    }
    Ok(Pairing::Listed)
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
        // No summary: read as it is.
        assert_eq!(verify_pairing(&csv, b"anything").unwrap(), Pairing::NoSummary);
        // A summary that does not list the trajectory (another run's, or of an older schema): refused.
        std::fs::write(dir.path().join(SUMMARY_FILE), r#"{"converged": true}"#).unwrap();
        let e = verify_pairing(&csv, &bytes).unwrap_err().to_string();
        assert!(e.contains("does not list trajectory.csv") && e.contains("summary.json"), "{e}");
        let summary = serde_json::json!({ "files": { TRAJECTORY_FILE: listed } });
        std::fs::write(dir.path().join(SUMMARY_FILE), summary.to_string()).unwrap();
        assert_eq!(verify_pairing(&csv, &bytes).unwrap(), Pairing::Listed);
        let e = verify_pairing(&csv, b"t\n0.0\n2.0\n").unwrap_err().to_string();
        assert!(e.contains("is not the file that") && e.contains("2 rows"), "{e}");
        // A reference.csv the summary does not list is another run's; a file of another name is unlisted.
        assert!(verify_pairing(&dir.path().join("reference.csv"), b"other").is_err());
        assert_eq!(verify_pairing(&dir.path().join("ref.hard.csv"), b"other").unwrap(), Pairing::Unlisted);
        // A listed file that is missing: refused, naming both files.
        let summary = serde_json::json!({ "files": { TRAJECTORY_FILE: listed, REFERENCE_FILE: listed } });
        std::fs::write(dir.path().join(SUMMARY_FILE), summary.to_string()).unwrap();
        let e = verify_pairing(&csv, &bytes).unwrap_err().to_string();
        assert!(e.contains("lists") && e.contains("reference.csv, which is missing") && e.contains("trajectory.csv"), "{e}");
    }
}
