#!/usr/bin/env bash
# Runs the test suite (the Rust tests and the Python tests, as ci/test.sh runs them) once
# per BLAS configuration, to find tests that assert where rounding lands: MUMPS (under
# Ipopt) does its dense work in BLAS, and OpenBLAS picks its kernels by processor, so the
# last bits of every Ipopt iterate differ between machines. Not part of CI's default run
# (it takes one whole test run per configuration); see CONTRIBUTING.md.
#
#   bash ci/test-blas-kernels.sh                    # the default set (below)
#   bash ci/test-blas-kernels.sh Haswell reference  # chosen configurations
#   bash ci/test-blas-kernels.sh -- --test backends # extra arguments after -- go to cargo test
#
# A configuration is an OpenBLAS kernel name (OPENBLAS_CORETYPE: Zen, Haswell,
# Sandybridge, Nehalem, Prescott, SkylakeX, Cooperlake, ...) or `reference`: the
# reference BLAS and LAPACK of Debian's libblas3 and liblapack3. The default set is the
# kernels this processor can run among Zen, Haswell, SkylakeX and Sandybridge, then
# `reference`. A kernel whose instructions the processor lacks (SkylakeX without
# AVX-512) is skipped with a note: it would die of an illegal instruction.
#
# The reference BLAS is loaded through LD_LIBRARY_PATH for the test processes only,
# which is what `update-alternatives --set libblas.so.3-x86_64-linux-gnu ...` would do
# for every program of the machine: the machine's own choice is left alone, and an
# interrupted run leaves nothing to undo. The script checks (with ldd) that the binary
# then loads the reference libraries and no OpenBLAS. It installs libblas3 and
# liblapack3 (apt, as root or through sudo) when they are missing.
#
# Exits 0 when every configuration passed, 1 otherwise; the last lines are a table of
# configurations and results, and each configuration's output is kept in
# target/blas-kernels/<configuration>.log.
set -uo pipefail
cd "$(dirname "$0")/.."

configs=()
cargo_args=()
while (($# > 0)); do
    if [[ "$1" == "--" ]]; then
        shift
        cargo_args=("$@")
        break
    fi
    configs+=("$1")
    shift
done

flags=$(grep -m1 '^flags' /proc/cpuinfo || true)
has() { [[ " $flags " == *" $1 "* ]]; }
# The instructions an OpenBLAS kernel needs (a subset that tells the kernels apart).
runnable() {
    case "$1" in
        SkylakeX | Cooperlake | SapphireRapids) has avx512f ;;
        Haswell | Zen) has avx2 && has fma ;;
        Sandybridge) has avx ;;
        *) return 0 ;;
    esac
}

if ((${#configs[@]} == 0)); then
    for k in Zen Haswell SkylakeX Sandybridge; do
        if runnable "$k"; then configs+=("$k"); else echo "test-blas-kernels: skipping $k: this processor lacks its instructions" >&2; fi
    done
    configs+=(reference)
fi

blas_dir=/usr/lib/x86_64-linux-gnu/blas
lapack_dir=/usr/lib/x86_64-linux-gnu/lapack
if [[ " ${configs[*]} " == *" reference "* ]] && [[ ! -e $blas_dir/libblas.so.3 || ! -e $lapack_dir/liblapack.so.3 ]]; then
    sudo_cmd=()
    [[ "$(id -u)" -ne 0 ]] && sudo_cmd=(sudo)
    echo "test-blas-kernels: installing libblas3 liblapack3 (the reference BLAS)" >&2
    "${sudo_cmd[@]}" env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends libblas3 liblapack3 >/dev/null || exit 1
fi

# One build for every configuration (the kernels are chosen when the library loads).
bash ci/install-deps.sh || exit 1
if ! command -v cargo >/dev/null 2>&1 && [[ -f "$HOME/.cargo/env" ]]; then
    # shellcheck disable=SC1091
    source "$HOME/.cargo/env"
fi
bash ci/python-env.sh || exit 1
cargo test --workspace --no-run "${cargo_args[@]}" || exit 1
cargo build -p skg-cli || exit 1
env VIRTUAL_ENV="$PWD/.venv" PYO3_CONFIG_FILE="$PWD/crates/skg-python/pyo3-config.txt" \
    .venv/bin/maturin develop -m crates/skg-python/Cargo.toml >target/maturin-develop.log 2>&1 || {
    cat target/maturin-develop.log >&2
    exit 1
}

logs=target/blas-kernels
mkdir -p "$logs"
results=()
failed=0
for config in "${configs[@]}"; do
    env_args=(OPENBLAS_VERBOSE=2)
    if [[ "$config" == reference ]]; then
        env_args+=("LD_LIBRARY_PATH=$blas_dir:$lapack_dir${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}")
        loaded=$(env "${env_args[@]}" ldd target/debug/skg-solve)
        if grep -q libopenblas <<<"$loaded" || ! grep -q "$blas_dir/libblas.so.3" <<<"$loaded"; then
            echo "test-blas-kernels: the reference BLAS would not be loaded:" >&2
            grep -E 'blas|lapack' <<<"$loaded" >&2
            exit 1
        fi
        label="reference BLAS ($blas_dir)"
    else
        if ! runnable "$config"; then
            echo "test-blas-kernels: $config: this processor lacks its instructions" >&2
            results+=("$config|skipped (instructions missing)")
            continue
        fi
        env_args+=("OPENBLAS_CORETYPE=$config")
        # OpenBLAS names the kernel it loaded (it falls back to its own pick for an unknown name).
        core=$(env "${env_args[@]}" target/debug/skg-solve --version 2>&1 | sed -n 's/^Core: //p' | head -1)
        if [[ "$core" != "$config" ]]; then
            echo "test-blas-kernels: OpenBLAS does not accept the kernel $config (it loaded '${core:-?}')" >&2
            results+=("$config|not accepted by OpenBLAS (loaded ${core:-?})")
            failed=1
            continue
        fi
        label="OpenBLAS $config kernels"
    fi
    log="$logs/$config.log"
    echo "== $label (log: $log)" >&2
    start=$SECONDS
    env "${env_args[@]}" cargo test --workspace --no-fail-fast "${cargo_args[@]}" >"$log" 2>&1
    rust_rc=$?
    env "${env_args[@]}" SKG_SOLVE="$PWD/target/debug/skg-solve" .venv/bin/python -m pytest -q crates/skg-python/tests >>"$log" 2>&1
    py_rc=$?
    passed=$(grep -o '^test result: [a-zA-Z]*\. [0-9]* passed' "$log" | awk '{s += $4} END {print s + 0}')
    failures=$(grep -E '^test .* FAILED$|^FAILED ' "$log" | sed 's/^test //; s/ \.\.\. FAILED$//; s/^FAILED //' | tr '\n' ' ')
    summary="cargo: $passed passed$([[ $rust_rc -ne 0 ]] && echo ", FAILED")"
    summary+="; pytest: $(grep -E '^[0-9]+ (passed|failed)|^=+ .*(passed|failed)' "$log" | tail -1 | tr -d '=' | xargs)"
    [[ -n "$failures" ]] && summary+="; failed: $failures"
    summary+="; $((SECONDS - start)) s"
    results+=("$config|$summary")
    if ((rust_rc != 0 || py_rc != 0)); then failed=1; fi
done

echo
echo "configuration | result"
for r in "${results[@]}"; do
    echo "${r%%|*} | ${r#*|}"
done
exit $failed
