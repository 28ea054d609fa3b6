#!/usr/bin/env bash
# Create (or reuse) the project's virtual environment in .venv: the pinned packages of
# requirements.txt, then the project itself in editable mode (`pip install --no-deps -e .`:
# the packages common, geometry, solver and benchmarks of this checkout). Needs a Python
# >= 3.12 interpreter.
#
# Each part is redone when needed: the pinned packages when requirements.txt is newer than
# their stamp, the project when pyproject.toml is newer than its stamp or when its packages
# do not resolve to this checkout (a new or moved checkout, an environment made elsewhere).
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$(pwd)
VENV=.venv
STAMP=$VENV/.installed            # pinned packages of requirements.txt
PROJECT_STAMP=$VENV/.installed-project  # this checkout, editable

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

# Whether the project's packages resolve to this checkout from outside it (found, not imported).
project_installed() {
    [[ -f $PROJECT_STAMP && ! pyproject.toml -nt $PROJECT_STAMP ]] || return 1
    (cd / && "$ROOT/$VENV/bin/python" - "$ROOT" <<'EOF'
import importlib.util
import pathlib
import sys

root = pathlib.Path(sys.argv[1]).resolve()
for name in ("common", "geometry", "solver", "benchmarks"):
    spec = importlib.util.find_spec(name)
    if spec is None or spec.origin is None or pathlib.Path(spec.origin).resolve().parent != root / name:
        sys.exit(1)
EOF
    )
}

if [[ ! -x $VENV/bin/python ]]; then
    if ! PY=$(find_python); then
        echo "error: no Python >= 3.12 found (looked for python3.14/3.13/3.12 on PATH and under ${PYENV_ROOT:-$HOME/.pyenv}/versions)." >&2
        echo "       Install Python 3.12 or newer (with venv), e.g. 'apt-get install python3 python3-venv' or 'pyenv install 3.12'." >&2
        exit 1
    fi
    echo "setup: creating $VENV with $PY"
    "$PY" -m venv "$VENV"
fi
if [[ ! -f $STAMP || requirements.txt -nt $STAMP ]]; then
    echo "setup: installing pinned packages into $VENV"
    "$VENV/bin/python" -m pip install --quiet --disable-pip-version-check -r requirements.txt
    touch "$STAMP"
fi
if ! project_installed; then
    echo "setup: installing the project into $VENV (editable)"
    "$VENV/bin/python" -m pip install --quiet --disable-pip-version-check --no-deps -e .
    touch "$PROJECT_STAMP"
    project_installed || { echo "error: the project's packages do not resolve to $ROOT after installing it" >&2; exit 1; }
fi
