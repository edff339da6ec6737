"""Reading glTF/GLB/VRM files: infuse's json + numpy reader beside pygltflib, per corpus file.

Columns (milliseconds, best of ``--passes``):
- ``parse``: infuse's container + JSON + buffer views (``infuse_gltf.parse_file``);
- ``read``: infuse's whole reader: skeleton, every clip resampled, morph targets, VRM facts;
- ``pygltflib``: ``GLTF2().load`` (JSON into dataclasses, binary blob), the accessors of the skins and
  animations then decoded with numpy, which is what the skeleton and clips need;
- ratios: pygltflib's time over infuse's ``read``, and ``GLTF2().load`` alone over ``parse``.

pygltflib is never a dependency of infuse: its rows appear when it is importable here or in the
interpreter given by ``--peer-python`` (e.g. a throwaway venv with ``pip install pygltflib``).

    .venv/bin/python benchmarks/gltf_read.py [--passes 5] [--peer-python /path/to/python]
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

from infuse_gltf import parse_file, read

HERE = Path(__file__).resolve().parent
CORPUS = Path(os.environ.get("INFUSE_CORPUS", HERE.parent.parent / "shared" / "corpus")).resolve()
SUFFIXES = (".glb", ".gltf", ".vrm", ".vrma")

# Runs in the peer interpreter: prints {file: [load_ms, load_and_decode_ms]}.
PEER_SCRIPT = r"""
import json, sys, time
import numpy as np
import pygltflib

DTYPES = {5120: "i1", 5121: "u1", 5122: "<i2", 5123: "<u2", 5125: "<u4", 5126: "<f4"}
WIDTH = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT2": 4, "MAT3": 9, "MAT4": 16}

def decode(gltf, blob, index):
    acc = gltf.accessors[index]
    view = gltf.bufferViews[acc.bufferView]
    if view.extensions:
        return None  # compressed: pygltflib does not decode it either
    dtype = np.dtype(DTYPES[acc.componentType])
    width = WIDTH[acc.type]
    start = (view.byteOffset or 0) + (acc.byteOffset or 0)
    stride = view.byteStride or dtype.itemsize * width
    raw = np.frombuffer(blob, np.uint8, stride * (acc.count - 1) + dtype.itemsize * width, start)
    return np.lib.stride_tricks.as_strided(raw, (acc.count, width * dtype.itemsize), (stride, 1)).copy().view(dtype)

def load(path):
    # pygltflib picks JSON or binary by extension (.vrm/.vrma would be taken for JSON): ask for binary.
    with open(path, "rb") as handle:
        binary = handle.read(4) == b"glTF"
    return pygltflib.GLTF2().load_binary(path) if binary else pygltflib.GLTF2().load_json(path)

def load_and_decode(path):
    gltf = load(path)
    blob = gltf.binary_blob()
    wanted = [s.inverseBindMatrices for s in gltf.skins if s.inverseBindMatrices is not None]
    for anim in gltf.animations:
        wanted += [x for s in anim.samplers for x in (s.input, s.output)]
    return [decode(gltf, blob, i) for i in wanted]

files, passes = json.loads(sys.argv[1]), int(sys.argv[2])
out = {}
for f in files:
    best_load = best_all = float("inf")
    for _ in range(passes):
        t = time.perf_counter(); load(f); best_load = min(best_load, time.perf_counter() - t)
        t = time.perf_counter(); load_and_decode(f); best_all = min(best_all, time.perf_counter() - t)
    out[f] = [best_load * 1e3, best_all * 1e3]
print(json.dumps(out))
"""


def best_ms(fn, passes: int) -> float:
    best = float("inf")
    for _ in range(passes):
        t = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t)
    return best * 1e3


def peer_timings(files: list[Path], passes: int, peer_python: str | None) -> dict | None:
    """pygltflib timings per file, or None when pygltflib is not importable anywhere given."""
    candidates = [sys.executable] + ([peer_python] if peer_python else [])
    for python in candidates:
        check = subprocess.run([python, "-c", "import pygltflib, numpy"], capture_output=True)
        if check.returncode == 0:
            done = subprocess.run([python, "-c", PEER_SCRIPT, json.dumps([str(f) for f in files]), str(passes)],
                                  capture_output=True, text=True, check=True)
            return {Path(k): v for k, v in json.loads(done.stdout).items()}
    return None


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n", 1)[0])
    parser.add_argument("--passes", type=int, default=3)
    parser.add_argument("--peer-python", help="an interpreter with pygltflib installed")
    args = parser.parse_args()
    files = sorted(p for p in CORPUS.rglob("*") if p.suffix.lower() in SUFFIXES)
    if not files:
        print(f"no glTF files under {CORPUS} (set INFUSE_CORPUS)", file=sys.stderr)
        return 2
    peers = peer_timings(files, args.passes, args.peer_python)
    header = f"{'file':<44} {'KB':>6} {'parse':>8} {'read':>8}"
    if peers:
        header += f" {'pygltflib':>10} {'+decode':>9} {'read x':>8} {'parse x':>8}"
    print(header)
    totals = [0.0, 0.0, 0.0, 0.0]
    for f in files:
        parse = best_ms(lambda: parse_file(f), args.passes)
        full = best_ms(lambda: read(f), args.passes)
        row = f"{f.name[:44]:<44} {f.stat().st_size / 1024:>6.0f} {parse:>8.2f} {full:>8.2f}"
        totals[0] += parse
        totals[1] += full
        if peers:
            load, decoded = peers[f]
            totals[2] += load
            totals[3] += decoded
            row += f" {load:>10.1f} {decoded:>9.1f} {decoded / full:>7.0f}x {load / parse:>7.0f}x"
        print(row)
    total = f"{'all files':<44} {'':>6} {totals[0]:>8.2f} {totals[1]:>8.2f}"
    if peers:
        total += f" {totals[2]:>10.1f} {totals[3]:>9.1f} {totals[3] / totals[1]:>7.0f}x {totals[2] / totals[0]:>7.0f}x"
    else:
        total += "   (pygltflib not importable: no peer columns; see --peer-python)"
    print(total)
    return 0


if __name__ == "__main__":
    sys.exit(main())
