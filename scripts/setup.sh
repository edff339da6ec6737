#!/usr/bin/env bash
# Idempotent setup: system packages (when root), .venv/ with infuse, every built-in plugin,
# every behaviour pack and the example packages installed editable, and the npm tools used in tests.
set -euo pipefail
cd "$(dirname "$0")/.."
PY=${PYTHON:-python3}
VENV=.venv

# System packages the features need (speech, video renders, browser viewer tests, glTF validation).
SYSTEM_PACKAGES="espeak-ng libespeak-ng1 ffmpeg nodejs npm chromium"
missing=""
for p in $SYSTEM_PACKAGES; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing="$missing $p"
done
# node/npm may come from elsewhere than Debian's packages; only ask apt for them when absent.
command -v node >/dev/null 2>&1 && missing=$(echo "$missing" | sed 's/\bnodejs\b//')
command -v npm >/dev/null 2>&1 && missing=$(echo "$missing" | sed 's/\bnpm\b//')
missing=$(echo $missing)
if [ -n "$missing" ]; then
  if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
    echo "setup: installing system packages: $missing"
    DEBIAN_FRONTEND=noninteractive apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends $missing >/dev/null
  else
    echo "setup: warning: missing system packages ($missing); run: sudo apt-get install $missing" >&2
  fi
fi

# pip's build warnings go to a log, shown only when an install fails.
pip_install() {
  local log="$VENV/setup-pip.log"
  if ! "$VENV/bin/python" -m pip install -q "$@" >"$log" 2>&1; then
    tail -n 30 "$log" >&2
    echo "setup: pip install failed (full log: $log)" >&2
    exit 1
  fi
}

if [ ! -x "$VENV/bin/python" ]; then
  echo "setup: creating $VENV"
  "$PY" -m venv "$VENV"
  pip_install --upgrade pip setuptools wheel
fi

shopt -s nullglob
packages="."
for d in plugins/*/ behaviour_libs/*/ examples/*/; do
  [ -f "$d/pyproject.toml" ] && packages="$packages ${d%/}"
done
stamp=$(cat scripts/setup.sh $(for d in $packages; do echo "$d/pyproject.toml"; done) | sha1sum | cut -d' ' -f1)
if [ "$(cat "$VENV/.setup-stamp" 2>/dev/null)" != "$stamp" ]; then
  echo "setup: installing infuse and its plugins into $VENV"
  # A distribution installed from this checkout under a name no pyproject here has any more (a renamed
  # or removed package) would register its entry points a second time: uninstall it.
  stale=$("$VENV/bin/python" - $packages <<'EOF'
import json, sys, tomllib
from importlib.metadata import distributions
from pathlib import Path
from urllib.parse import unquote, urlparse

def canonical(name):
    return name.lower().replace("_", "-").replace(".", "-")

here = Path.cwd().resolve()
names = {canonical(tomllib.loads((Path(d) / "pyproject.toml").read_text())["project"]["name"]) for d in sys.argv[1:]}
for dist in distributions():
    url = json.loads(dist.read_text("direct_url.json") or "{}").get("url", "")
    if url.startswith("file:") and Path(unquote(urlparse(url).path)).resolve().is_relative_to(here) \
            and canonical(dist.metadata["Name"]) not in names:
        print(dist.metadata["Name"])
EOF
)
  if [ -n "$stale" ]; then
    echo "setup: uninstalling distributions no longer in this checkout:" $stale
    "$VENV/bin/python" -m pip uninstall -q -y $stale
  fi
  args=""
  for d in $packages; do args="$args -e $d"; done
  pip_install --no-build-isolation $args -e ".[test,docs]"
  # The optional extra the tests exercise: infuse batch on a real dask.distributed cluster.
  pip_install --no-build-isolation -e "plugins/batch[dask]"
  echo "$stamp" > "$VENV/.setup-stamp"
fi

# Khronos glTF validator (npm), used by the tests of the glTF writer; three.js for the browser viewer;
# glTF Transform's CLI, which makes the Draco-compressed characters the glTF reader's tests decode.
THREE_VERSION=0.187.0
GLTF_TRANSFORM_VERSION=4.5.1
if command -v npm >/dev/null 2>&1 && { [ ! -f "$VENV/tools/node_modules/gltf-validator/package.json" ] ||
    ! grep -qs "\"version\": \"$THREE_VERSION\"" "$VENV/tools/node_modules/three/package.json" ||
    ! grep -qs "\"version\": \"$GLTF_TRANSFORM_VERSION\"" "$VENV/tools/node_modules/@gltf-transform/cli/package.json"; }; then
  echo "setup: installing gltf-validator, three and @gltf-transform/cli (npm)"
  npm install --silent --no-audit --no-fund --prefix "$VENV/tools" gltf-validator "three@$THREE_VERSION" \
    "@gltf-transform/cli@$GLTF_TRANSFORM_VERSION" >/dev/null
fi
echo "setup: ready ($VENV/bin/infuse)"
