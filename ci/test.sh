#!/usr/bin/env bash
# Set up (installs Ipopt, libclang and pkg-config when missing) and run the whole test
# suite. This is exactly what CI runs (.ci/run).
set -euo pipefail
cd "$(dirname "$0")/.."
bash ci/install-deps.sh
cargo test --no-fail-fast "$@"
