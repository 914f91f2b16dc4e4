#!/usr/bin/env bash
# Set up (installs Ipopt, libclang and pkg-config when missing) and run the whole test
# suite. This is exactly what CI runs (.ci/run).
set -euo pipefail
cd "$(dirname "$0")/.."
bash ci/install-deps.sh
# A toolchain installed by install-deps.sh lives in ~/.cargo.
if ! command -v cargo >/dev/null 2>&1 && [[ -f "$HOME/.cargo/env" ]]; then
    # shellcheck disable=SC1091
    source "$HOME/.cargo/env"
fi
cargo test --no-fail-fast "$@"
