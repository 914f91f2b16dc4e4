#!/usr/bin/env bash
# Set up (installs Ipopt, libclang and pkg-config when missing, and rustfmt and clippy
# when rustup can add them) and check the workspace. This is exactly what CI runs
# (.ci/run), in this order, stopping at the first failure:
#   cargo fmt --all --check                                formatting
#   cargo clippy --workspace --all-targets -- -D warnings  lints, tests included
#   cargo build --workspace --examples                     the examples compile
#   cargo run -p skg-core --example oscillator             a scene solved from code
#   cargo test --workspace --no-fail-fast                  the test suite
# Extra arguments go to `cargo test`.
set -euo pipefail
cd "$(dirname "$0")/.."
bash ci/install-deps.sh
# A toolchain installed by install-deps.sh lives in ~/.cargo.
if ! command -v cargo >/dev/null 2>&1 && [[ -f "$HOME/.cargo/env" ]]; then
    # shellcheck disable=SC1091
    source "$HOME/.cargo/env"
fi

step() {
    echo "== $*" >&2
    "$@"
}

step cargo fmt --all --check
step cargo clippy --workspace --all-targets -- -D warnings
step cargo build --workspace --examples
step cargo run --quiet -p skg-core --example oscillator
step cargo test --workspace --no-fail-fast "$@"
