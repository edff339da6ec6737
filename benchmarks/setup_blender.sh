#!/usr/bin/env bash
# Creates benchmarks/.blender-venv with Blender's Python module (bpy, Python 3.11 wheels) for blender_check.py.
# Benchmark-only: never a dependency of infuse. Idempotent. BPY_VERSION picks the wheel (default 4.2.*).
set -euo pipefail
cd "$(dirname "$0")"
PY=${PYTHON:-python3.11}
BPY_VERSION=${BPY_VERSION:-4.2.*}
if [ ! -x .blender-venv/bin/python ]; then
  "$PY" -m venv .blender-venv
fi
if ! .blender-venv/bin/python -c "import bpy" 2>/dev/null; then
  .blender-venv/bin/python -m pip install -q --upgrade pip
  .blender-venv/bin/python -m pip install -q "bpy==$BPY_VERSION"
fi
echo "blender ready: $(.blender-venv/bin/python -c 'import bpy; print(bpy.app.version_string)' 2>/dev/null | tail -n 1)"
