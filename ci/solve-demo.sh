#!/usr/bin/env bash
# Set up (installs Ipopt, libclang and pkg-config when missing), build, and solve the
# rolling disk of the paper. Extra arguments go to skg-solve.
set -euo pipefail
cd "$(dirname "$0")/.."
bash ci/install-deps.sh
cargo build --release --quiet
./target/release/skg-solve scenarios/rolling_disk.toml "$@"
