//! What every file skg-solve writes says about where it came from: the tool's version,
//! the version of the output's layout (schema) and a hash of the scene's content, so
//! that a reader can tell which program and which scene produced a result and refuse
//! to mix results of different scenes.

use sha2::{Digest, Sha256};

/// The skg-solve version that wrote a file.
pub const VERSION: &str = env!("CARGO_PKG_VERSION");

/// Version of the layout of `summary.json`, `results.csv` and `sweep.json`. Raised
/// whenever a field is renamed, removed or changes meaning (adding one does not).
pub const SCHEMA_VERSION: u32 = 3;

/// The hash of a file's content, written as `sha256:<64 hex digits>`.
pub fn content_hash(bytes: &[u8]) -> String {
    hex_digest(&Sha256::digest(bytes))
}

/// A SHA-256 digest written as `sha256:<64 hex digits>`.
pub fn hex_digest(digest: &[u8]) -> String {
    let mut s = String::with_capacity(7 + 64);
    s.push_str("sha256:");
    for b in digest {
        s.push_str(&format!("{b:02x}"));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hash_of_known_input() {
        // FIPS 180-2, appendix B.1: SHA-256("abc").
        assert_eq!(content_hash(b"abc"), "sha256:ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
        assert_ne!(content_hash(b"abc"), content_hash(b"abd"));
    }
}
