#!/usr/bin/env bash
# Set up (installs Ipopt, libclang and pkg-config when missing), build, and solve the
# rolling disk of the paper. Extra arguments go to skg-solve.
set -euo pipefail
cd "$(dirname "$0")/.."
bash ci/install-deps.sh
# A toolchain installed by install-deps.sh lives in ~/.cargo.
if ! command -v cargo >/dev/null 2>&1 && [[ -f "$HOME/.cargo/env" ]]; then
    # shellcheck disable=SC1091
    source "$HOME/.cargo/env"
fi
cargo build --release --quiet -p skg-cli
./target/release/skg-solve scenarios/rolling_disk.toml "$@"
