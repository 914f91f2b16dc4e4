#!/usr/bin/env bash
# The README's first set-up command. Installs what is missing (Ipopt, libclang,
# pkg-config, a C linker; Rust with rustup when there is no cargo), builds skg-solve,
# installs it with `cargo install` into cargo's bin directory ($CARGO_HOME/bin, i.e.
# ~/.cargo/bin, or $CARGO_INSTALL_ROOT/bin when that is set), and solves the rolling disk
# of the paper. Extra arguments go to that solve.
#
# When that bin directory is not on the caller's PATH (typically: this script had to
# install Rust itself), the last line says what to run so that `skg-solve` is found.
set -euo pipefail
cd "$(dirname "$0")/.."
caller_path="$PATH"
bash ci/install-deps.sh
# A toolchain installed by install-deps.sh lives in ~/.cargo.
if ! command -v cargo >/dev/null 2>&1 && [[ -f "$HOME/.cargo/env" ]]; then
    # shellcheck disable=SC1091
    source "$HOME/.cargo/env"
fi
cargo build --release --quiet -p skg-cli
# Reuses the release build above (for --path, cargo install builds in this workspace's target/).
cargo install --path crates/skg-cli --locked --quiet
./target/release/skg-solve scenarios/rolling_disk.toml "$@"

bin_dir="${CARGO_INSTALL_ROOT:-${CARGO_HOME:-$HOME/.cargo}}/bin"
case ":$caller_path:" in
    *":$bin_dir:"*) echo "skg-solve is installed in $bin_dir (on your PATH)." ;;
    *)
        if [[ -f "$HOME/.cargo/env" && "$bin_dir" == "$HOME/.cargo/bin" ]]; then
            echo "skg-solve is installed in $bin_dir, which is not on your PATH: run  source ~/.cargo/env  (once per shell) before using skg-solve."
        else
            echo "skg-solve is installed in $bin_dir, which is not on your PATH: run  export PATH=\"$bin_dir:\$PATH\"  before using skg-solve."
        fi
        ;;
esac
