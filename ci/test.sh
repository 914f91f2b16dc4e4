#!/usr/bin/env bash
# Set up (installs Ipopt, libclang and pkg-config when missing, and rustfmt and clippy
# when rustup can add them) and check the workspace. This is exactly what CI runs
# (.ci/run), in this order, stopping at the first failure:
#   cargo fmt --all --check                                formatting
#   cargo clippy --workspace --all-targets -- -D warnings  lints, tests included
#   cargo build --workspace --examples                     the examples compile
#   cargo run -p skg-core --example oscillator             a scene solved from code
#   cargo test --workspace --no-fail-fast                  the test suite
#   maturin develop, then pytest crates/skg-python/tests   the Python package (skg), in .venv
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

# The Python package: .venv with maturin, numpy, pytest and pandas (ci/python-env.sh),
# the extension built by maturin in the dev profile (the crates it shares with the
# workspace are built already), and its tests, which compare with the skg-solve just built.
step bash ci/python-env.sh
step env VIRTUAL_ENV="$PWD/.venv" .venv/bin/maturin develop --quiet -m crates/skg-python/Cargo.toml
step env SKG_SOLVE="$PWD/target/debug/skg-solve" .venv/bin/python -m pytest -q crates/skg-python/tests
