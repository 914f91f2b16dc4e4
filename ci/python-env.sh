#!/usr/bin/env bash
# The Python environment of the tests of the `skg` package (crates/skg-python): a
# virtual environment in .venv (gitignored; Debian's system Python refuses `pip
# install`, PEP 668) with maturin (builds the extension), numpy, pytest, pandas and
# sympy (optional for users; the tests of `to_pandas()` and of SymPy expressions in
# scenes use them).
#
# Idempotent and quiet when .venv already has them: pip runs only for a new or
# incomplete environment. The system packages (python3-venv, python3-dev) come from
# ci/install-deps.sh.
set -euo pipefail
cd "$(dirname "$0")/.."

packages=("maturin>=1.9.4,<2" "numpy" "pytest" "pandas" "sympy")
if [[ -x .venv/bin/python ]] && .venv/bin/python -c "import numpy, pytest, pandas, sympy" 2>/dev/null \
    && [[ -x .venv/bin/maturin ]]; then
    exit 0
fi
if [[ ! -x .venv/bin/python ]]; then
    if ! python3 -m venv .venv; then
        echo "python-env: \`python3 -m venv .venv\` failed; on Debian install python3-venv (ci/install-deps.sh does)." >&2
        rm -rf .venv
        exit 1
    fi
fi
echo "python-env: installing ${packages[*]} into .venv"
.venv/bin/python -m pip install --quiet --disable-pip-version-check "${packages[@]}"
