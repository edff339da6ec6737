"""Validate glTF files with the Khronos glTF validator (npm ``gltf-validator``) run by Node.js.

``make setup`` installs the validator into ``.venv/tools/node_modules``; another location can be
given with the environment variable ``INFUSE_GLTF_VALIDATOR`` (the package folder). The report is the
validator's JSON: ``report["issues"]["numErrors"]``, ``["messages"]`` (code, message, severity,
pointer)...
"""
from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

from infuse.errors import MissingFeatureError

# Reads each file given on the command line and prints one JSON report per line.
_SCRIPT = r"""
const fs = require('fs');
const path = require('path');
const validator = require(process.env.INFUSE_GLTF_VALIDATOR_MODULE);
(async () => {
  for (const file of process.argv.slice(1)) {
    const data = new Uint8Array(fs.readFileSync(file));
    const report = await validator.validateBytes(data, {
      uri: path.basename(file),
      maxIssues: 200,
      externalResourceFunction: (uri) => new Promise((resolve, reject) => {
        fs.readFile(path.resolve(path.dirname(file), decodeURIComponent(uri)),
                    (err, buf) => err ? reject(err.toString()) : resolve(new Uint8Array(buf)));
      }),
    });
    process.stdout.write(JSON.stringify(report) + '\n');
  }
})().catch((err) => { process.stderr.write(String(err) + '\n'); process.exit(1); });
"""


def validator_location() -> Path | None:
    """The ``gltf-validator`` package folder, or ``None`` when it is not installed."""
    candidates = [os.environ.get("INFUSE_GLTF_VALIDATOR"), Path(sys.prefix) / "tools" / "node_modules" / "gltf-validator"]
    for c in candidates:
        if c and (Path(c) / "package.json").is_file():
            return Path(c)
    return None


def available() -> bool:
    """True when Node.js and the validator package are both present."""
    return shutil.which("node") is not None and validator_location() is not None


def validate_files(paths: list[str | Path], timeout: float = 300.0) -> list[dict]:
    """Validator reports for ``paths`` (one Node.js process for all of them)."""
    location = validator_location()
    node = shutil.which("node")
    if location is None or node is None:
        raise MissingFeatureError(None, "the Khronos glTF validator needs Node.js and the npm package gltf-validator: "
                                        "run `make setup` (or npm install --prefix .venv/tools gltf-validator)")
    env = dict(os.environ, INFUSE_GLTF_VALIDATOR_MODULE=str(location))
    done = subprocess.run([node, "-e", _SCRIPT, *map(str, paths)], capture_output=True, text=True, env=env, timeout=timeout)
    if done.returncode != 0:
        raise RuntimeError(f"gltf-validator failed: {done.stderr.strip()[:500]}")
    return [json.loads(line) for line in done.stdout.splitlines() if line.strip()]


def validate(path: str | Path) -> dict:
    """The validator report for one file."""
    return validate_files([path])[0]


def errors(report: dict) -> list[str]:
    """``"CODE pointer: message"`` for every error (severity 0) in a report."""
    return [f"{m.get('code')} {m.get('pointer', '')}: {m.get('message')}"
            for m in report.get("issues", {}).get("messages", []) if m.get("severity") == 0]
