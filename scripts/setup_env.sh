#!/usr/bin/env bash
# Create (or reuse) the project's virtual environment in .venv with the pinned
# packages of requirements.txt. Needs a Python >= 3.12 interpreter.
set -euo pipefail
cd "$(dirname "$0")/.."
VENV=.venv
STAMP=$VENV/.installed

find_python() {
    local candidates=(python3.14 python3.13 python3.12)
    for c in "${candidates[@]}"; do
        if command -v "$c" >/dev/null 2>&1 && "$c" -c 'import sys; assert sys.version_info >= (3, 12)' >/dev/null 2>&1; then
            command -v "$c"; return 0
        fi
    done
    local root="${PYENV_ROOT:-$HOME/.pyenv}"
    for p in $(ls -d "$root"/versions/3.1[2-9]*/bin/python3 2>/dev/null | sort -V -r); do
        if "$p" -c 'import sys; assert sys.version_info >= (3, 12)' >/dev/null 2>&1; then
            echo "$p"; return 0
        fi
    done
    return 1
}

if [[ -f $STAMP && $STAMP -nt requirements.txt ]]; then
    exit 0
fi
if [[ ! -x $VENV/bin/python ]]; then
    if ! PY=$(find_python); then
        echo "error: no Python >= 3.12 found (looked for python3.14/3.13/3.12 on PATH and under ${PYENV_ROOT:-$HOME/.pyenv}/versions)." >&2
        echo "       Install Python 3.12 or newer (with venv), e.g. 'apt-get install python3 python3-venv' or 'pyenv install 3.12'." >&2
        exit 1
    fi
    echo "setup: creating $VENV with $PY"
    "$PY" -m venv "$VENV"
fi
echo "setup: installing pinned packages into $VENV (first time only)"
"$VENV/bin/python" -m pip install --quiet --disable-pip-version-check -r requirements.txt
touch "$STAMP"
