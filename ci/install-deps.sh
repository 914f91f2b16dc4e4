#!/usr/bin/env bash
# Installs the system packages skg-solve needs to build (Debian/Ubuntu):
#   coinor-libipopt-dev  Ipopt (linked by build.rs through pkg-config)
#   libclang-dev         libclang, used by bindgen in build.rs
#   pkg-config           finds Ipopt
#   gcc, libc6-dev       the linker Rust uses
#   python3-venv, python3-dev, python3-pip
#                        the Python package's tests (ci/python-env.sh makes .venv)
#   libopenblas0-serial  an optimized BLAS for MUMPS's dense fronts (Debian's alternatives
#                        make it the system's libblas.so.3): Ipopt's factorizations of
#                        many-body scenes are 2–3× faster than with the reference BLAS
#                        (docs/benchmarks.md#many-body-scenes)
# and, when no cargo is found, installs a Rust toolchain with rustup (minimal profile)
# into ~/.cargo (callers then `source ~/.cargo/env`). When `cargo fmt` or `cargo clippy`
# is missing (rustup's minimal profile has neither) and rustup is present, adds the
# rustfmt and clippy components.
#
# Idempotent and quiet when everything is already installed: apt-get runs (once
# `apt-get update`, then one `apt-get install`) only for missing packages. Uses sudo
# only when not root.
set -euo pipefail

packages=(coinor-libipopt-dev libclang-dev pkg-config gcc libc6-dev python3-venv python3-dev python3-pip libopenblas0-serial)
need_rust=false
if ! command -v cargo >/dev/null 2>&1 && [[ ! -x "$HOME/.cargo/bin/cargo" ]]; then
    need_rust=true
    packages+=(curl ca-certificates)
fi

missing=()
for pkg in "${packages[@]}"; do
    # dpkg -s also succeeds for removed-but-not-purged packages: check the status line.
    if ! dpkg -s "$pkg" 2>/dev/null | grep -q '^Status: install ok installed'; then
        missing+=("$pkg")
    fi
done

if ((${#missing[@]} > 0)); then
    if ! command -v apt-get >/dev/null 2>&1; then
        echo "install-deps: missing packages ${missing[*]}, and apt-get is not available;" >&2
        echo "install Ipopt (with pkg-config file), libclang and pkg-config by other means." >&2
        exit 1
    fi
    sudo_cmd=()
    if [[ "$(id -u)" -ne 0 ]]; then
        if ! command -v sudo >/dev/null 2>&1; then
            echo "install-deps: need root or sudo to install: ${missing[*]}" >&2
            exit 1
        fi
        sudo_cmd=(sudo)
    fi
    echo "install-deps: installing ${missing[*]}"
    "${sudo_cmd[@]}" env DEBIAN_FRONTEND=noninteractive apt-get update -qq
    "${sudo_cmd[@]}" env DEBIAN_FRONTEND=noninteractive \
        apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

if ! pkg-config --exists ipopt; then
    echo "install-deps: pkg-config cannot find ipopt (ipopt.pc) even though coinor-libipopt-dev is installed;" >&2
    echo "check PKG_CONFIG_PATH." >&2
    exit 1
fi

if $need_rust; then
    echo "install-deps: no cargo found; installing Rust with rustup into ~/.cargo"
    curl --proto '=https' --tlsv1.2 -sSf https://sh.rustup.rs | sh -s -- -y --profile minimal --no-modify-path >/dev/null
fi

# rustfmt and clippy (ci/test.sh checks formatting and lints).
if ! command -v cargo >/dev/null 2>&1 && [[ -f "$HOME/.cargo/env" ]]; then
    # shellcheck disable=SC1091
    source "$HOME/.cargo/env"
fi
if ! cargo fmt --version >/dev/null 2>&1 || ! cargo clippy --version >/dev/null 2>&1; then
    if command -v rustup >/dev/null 2>&1; then
        echo "install-deps: adding the rustfmt and clippy components with rustup"
        rustup component add rustfmt clippy >/dev/null
    else
        echo "install-deps: cargo fmt or cargo clippy is missing and rustup is not available;" >&2
        echo "install rustfmt and clippy for this toolchain by other means." >&2
        exit 1
    fi
fi
