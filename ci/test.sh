#!/usr/bin/env bash
# Set up (installs Ipopt, libclang and pkg-config when missing, and rustfmt and clippy
# when rustup can add them) and check the workspace. This is exactly what CI runs
# (.ci/run), in this order, stopping at the first failure, except that the Python tests
# run even when a Rust test failed (the script then exits non-zero after them, so that
# every failure is seen at once):
#   cargo fmt --all --check                                formatting
#   bash ci/check-links.sh                                 the docs' links, anchors and quoted paths
#   cargo clippy --workspace --all-targets -- -D warnings  lints, tests included
#   cargo clippy -p skg-core --no-default-features …       skg-core builds without Ipopt
#   RUSTDOCFLAGS="-D warnings" cargo doc --workspace --no-deps  the API docs, links checked
#   cargo build --workspace --examples                     the examples compile
#   cargo run -p skg-core --example oscillator             a scene solved from code
#   cargo test --workspace --no-fail-fast                  the test suite, with SKG_REQUIRE_SLURM=1: the
#                                                          tests of sweeps on Slurm (crates/skg-cli/tests/slurm.rs)
#                                                          start a cluster with ci/slurm-local.sh (root; it
#                                                          installs Debian's slurmctld, slurmd and munge if
#                                                          missing) and fail instead of skipping without one
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
step bash ci/check-links.sh
step cargo clippy --workspace --all-targets -- -D warnings
step cargo clippy -p skg-core --no-default-features --all-targets -- -D warnings
step env RUSTDOCFLAGS="-D warnings" cargo doc --workspace --no-deps
step cargo build --workspace --examples
step cargo run --quiet -p skg-core --example oscillator
rust_tests=0
step env SKG_REQUIRE_SLURM=1 cargo test --workspace --no-fail-fast "$@" || rust_tests=$?

# The Python package: .venv with maturin, numpy, pytest and pandas (ci/python-env.sh),
# the extension built by maturin in the dev profile, and its tests, which compare with
# the skg-solve just built. maturin builds crates/skg-python alone; with the same PyO3
# configuration file as cargo (.cargo/config.toml) and the features that
# crates/skg-python/Cargo.toml aligns, it reuses skg-core and everything below it from
# `cargo build --workspace --examples` above and compiles only what that build does not
# need (PyO3, numpy, skg-sweep, the extension). If a dependency change breaks the
# alignment, skg-core is compiled again: then it says so.
step bash ci/python-env.sh
maturin_log=target/maturin-develop.log
echo "== maturin develop -m crates/skg-python/Cargo.toml (output in $maturin_log)" >&2
env VIRTUAL_ENV="$PWD/.venv" PYO3_CONFIG_FILE="$PWD/crates/skg-python/pyo3-config.txt" \
    .venv/bin/maturin develop -m crates/skg-python/Cargo.toml >"$maturin_log" 2>&1 || { cat "$maturin_log" >&2; exit 1; }
if grep -q '^ *Compiling skg-core ' "$maturin_log"; then
    echo "warning: maturin compiled skg-core again instead of reusing the workspace's build (see crates/skg-python/Cargo.toml):" \
        "$(sed -n 's/^ *Compiling \([^ ]*\) .*/\1/p' "$maturin_log" | tr '\n' ' ')" >&2
fi
python_tests=0
step env SKG_SOLVE="$PWD/target/debug/skg-solve" .venv/bin/python -m pytest -q crates/skg-python/tests || python_tests=$?
failed=()
((rust_tests == 0)) || failed+=("the Rust tests (cargo test, whose output is above the Python tests')")
((python_tests == 0)) || failed+=("the Python tests (pytest)")
if ((${#failed[@]} > 0)); then
    printf 'test.sh: failed: %s\n' "${failed[@]}" >&2
    exit 1
fi
