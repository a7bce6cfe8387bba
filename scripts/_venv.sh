# Shared by scripts/run and scripts/test: make sure .venv exists and holds the
# project (editable) with the requested extras. Re-installs only when
# pyproject.toml changed since the last install.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
VENV="$ROOT/.venv"
EXTRAS="${1:-}"
PY="${PYTHON:-python3}"
if [ ! -x "$VENV/bin/python" ]; then
    "$PY" -m venv "$VENV"
    "$VENV/bin/python" -m pip install -q --upgrade pip
fi
STAMP="$VENV/.installed${EXTRAS:+-$EXTRAS}"
if [ ! -f "$STAMP" ] || [ "$ROOT/pyproject.toml" -nt "$STAMP" ]; then
    SPEC="$ROOT"
    [ -n "$EXTRAS" ] && SPEC="$ROOT[$EXTRAS]"
    "$VENV/bin/python" -m pip install -q -e "$SPEC"
    if [ "$EXTRAS" = "test" ]; then
        # the schemas the suite checks our files against (not committed: fetched)
        "$VENV/bin/python" "$ROOT/scripts/test_schemas.py" || true
    fi
    touch "$STAMP"
fi
