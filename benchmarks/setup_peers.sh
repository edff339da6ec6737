#!/usr/bin/env bash
# Creates benchmarks/.venv with the peer libraries io_fk.py compares against (bvhio, upc-pymotion).
# They are benchmark-only: never dependencies of infuse. Idempotent.
set -euo pipefail
cd "$(dirname "$0")"
PY=${PYTHON:-python3}
if [ ! -x .venv/bin/python ]; then
  "$PY" -m venv .venv
fi
if ! .venv/bin/python -c "import bvhio, pymotion" 2>/dev/null; then
  .venv/bin/python -m pip install -q --upgrade pip
  .venv/bin/python -m pip install -q numpy bvhio upc-pymotion
fi
echo "peers ready: $(.venv/bin/python -m pip list 2>/dev/null | grep -i -E '^(bvhio|upc-pymotion|numpy) ' | tr -s ' ' | tr '\n' ';')"
