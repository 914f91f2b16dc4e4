#!/usr/bin/env bash
# Installs the system packages skg-solve needs to build (Debian/Ubuntu):
#   coinor-libipopt-dev  Ipopt (linked by build.rs through pkg-config)
#   libclang-dev         libclang, used by bindgen in build.rs
#   pkg-config           finds Ipopt
# and checks that a Rust toolchain (cargo) is present.
#
# Idempotent and quiet when everything is already installed: apt-get runs (once
# `apt-get update`, then one `apt-get install`) only for missing packages. Uses sudo
# only when not root.
set -euo pipefail

packages=(coinor-libipopt-dev libclang-dev pkg-config)

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

if ! command -v cargo >/dev/null 2>&1; then
    echo "install-deps: cargo (Rust) was not found on PATH." >&2
    echo "Install Rust with rustup (https://rustup.rs):" >&2
    echo "    curl --proto '=https' --tlsv1.2 -sSf https://sh.rustup.rs | sh -s -- -y" >&2
    echo "then run: source \"\$HOME/.cargo/env\"   (or add ~/.cargo/bin to PATH)" >&2
    echo "or, on Debian, install the packaged toolchain: apt-get install cargo rustc (needs Rust >= 1.80)" >&2
    exit 1
fi
