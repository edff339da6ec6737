"""A pack's build and what it drives do not depend on its name, its clips' names or their order: the same
takes imported under another pack name, with file names that sort the other way round, or listed in
another order in the manifest, build the same analysis and walk X Bot to the same output motion (FK,
bit for bit), in this process and in one with another string hash seed.

Sources: the Bandai dataset-1 ``normal`` takes (walks forward, left, right and back, a run, a dash), read
in place and copied under other names to a temporary folder; SmartBody's female behaviour set (cycles,
and the starts, turns on the spot and stop a walk plays whole)."""
from __future__ import annotations

import hashlib
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import infuse
from infuse.kinematics import motion_fk
from infuse.packs import build_pack
from infuse.packs.importers import import_bvh_folder, import_smartbody
from infuse.packs.manifest import manifest_text, read_manifest
from infuse.packs.walk_test import trial_pack

from corpus_data import corpus_file, require_corpus

SOURCE = ("bandai/Bandai-Namco-Research-Motiondataset-1/data", "dataset-1_*_normal_*.bvh")
SMARTBODY = "smartbody/behaviorsets/FemaleLocomotion"
#: Walks to targets 4 m away, to the left and behind (degrees; behind starts with a turn on the spot),
#: besides the trial's straight walks.
TARGET_ANGLES = (90.0, 180.0)


def _takes() -> list[Path]:
    folder, pattern = SOURCE
    files = sorted((require_corpus() / folder).glob(pattern))
    assert len(files) == 7, f"expected the 7 dataset-1 normal takes, found {len(files)}"
    return files


def _renamed(files: list[Path], folder: Path, names: list[str]) -> Path:
    """``folder`` holding a copy of each of ``files`` named ``names[k]``."""
    folder.mkdir(parents=True)
    for f, n in zip(files, names):
        shutil.copyfile(f, folder / n)
    return folder


def _reordered(manifest: Path, order: list[int]) -> Path:
    """Rewrite ``manifest`` with its clips listed in ``order`` (indices into its clips)."""
    m = read_manifest(manifest)
    pack = {"name": m.name, "version": m.version, "kind": m.kind, "skeleton": m.skeleton.relative_to(m.folder).as_posix(),
            "analysis": m.analysis.name, "description": m.description or None}
    clips = [{"name": c.name, "file": c.file.relative_to(m.folder).as_posix(), "role": c.role, "tags": list(c.tags),
              "loop": c.loop} for c in (m.clips[k] for k in order)]
    manifest.write_text(manifest_text(pack, clips), encoding="utf-8")
    return manifest


def _walks(pack, character) -> dict:
    """The trial's figures and its straight walk and walk to a target as (F, J, 3) FK positions."""
    trial = trial_pack(character, pack, distances=(4.0,), angles=TARGET_ANGLES)
    return {"worst": trial.worst(), **{k: motion_fk(trial.motions[k])[1] for k in ("straight", "target")}}


def _same_analysis(a: dict, b: dict) -> None:
    """Equal analyses but for the names: the pack's, its clips' and their files'."""
    def plain(doc):
        keep = {k: v for k, v in doc.items() if k not in ("pack", "fingerprint", "files", "clips", "tessellations", "report")}
        clips = sorted(json.dumps({k: v for k, v in c.items() if k != "name"}, sort_keys=True) for c in doc["clips"])
        spaces = {g: {k: v for k, v in t.items() if k != "labels"} for g, t in doc["tessellations"].items()}
        return keep, clips, spaces
    assert plain(a) == plain(b)


@pytest.fixture(scope="module")
def xbot():
    return infuse.Character("Xbot", infuse.load(corpus_file("runxaway-models/Xbot.glb")))


@pytest.fixture(scope="module")
def bandai(tmp_path_factory):
    """Built packs: "first" as imported, "second" under another name from files whose names sort the other
    way round, "third" as "first" with its manifest listing the clips in another order."""
    work = tmp_path_factory.mktemp("bandai")
    files = _takes()
    source = files[0].parent
    first = import_bvh_folder(source, work / "first", name="first", pattern=SOURCE[1])
    backwards = [f"{len(files) - k:02d}-{f.name}" for k, f in enumerate(files)]
    second = import_bvh_folder(_renamed(files, work / "renamed", backwards), work / "second", name="zz-another-name")
    third = import_bvh_folder(source, work / "third", name="third", pattern=SOURCE[1])
    _reordered(third, [3, 0, 6, 1, 5, 2, 4])
    built = {k: build_pack(m) for k, m in (("first", first), ("second", second), ("third", third))}
    assert [c.name for c in built["first"].manifest.clips] != [c.name for c in built["third"].manifest.clips]
    assert [c.file.name for c in built["second"].manifest.clips] == sorted(backwards)
    return built


@pytest.fixture(scope="module")
def smartbody(tmp_path_factory):
    """Built packs: "first" as imported, "second" under another name with its manifest listing the clips
    in another order."""
    work = tmp_path_factory.mktemp("smartbody")
    source = corpus_file(SMARTBODY)
    first = import_smartbody(source, work / "first", name="first")
    second = import_smartbody(source, work / "second", name="zz-another-name")
    count = len(read_manifest(second).clips)
    _reordered(second, [(7 * k + 3) % count for k in range(count)])  # 7 and the clip count share no factor
    built = {"first": build_pack(first), "second": build_pack(second)}
    assert {c.get("transition") for c in built["first"].require_built()["clips"]} >= {"start", "turn", "stop"}
    return built


@pytest.fixture(params=["bandai", "smartbody"])
def packs(request):
    return request.getfixturevalue(request.param)


def test_build_is_the_same_under_other_names_and_orders(packs):
    for other in set(packs) - {"first"}:
        _same_analysis(packs["first"].require_built(), packs[other].require_built())


def test_walks_are_the_same_under_other_names_and_orders(packs, xbot):
    first = _walks(packs["first"], xbot)
    assert first["worst"]["miss_m"] < 0.05  # the walks reached their targets: the comparison is of real walks
    for other in set(packs) - {"first"}:
        walks = _walks(packs[other], xbot)
        assert walks["worst"] == first["worst"]
        for key in ("straight", "target"):
            np.testing.assert_array_equal(walks[key], first[key])


SUBPROCESS = """
import hashlib, sys
import infuse
from infuse.kinematics import motion_fk
from infuse.packs.walk_test import trial_pack
character = infuse.Character("Xbot", infuse.load(sys.argv[2]))
trial = trial_pack(character, sys.argv[1], distances=(4.0,), angles={angles})
print(hashlib.sha256(b"".join(motion_fk(trial.motions[k])[1].tobytes() for k in ("straight", "target"))).hexdigest())
"""


def test_walks_are_the_same_under_another_hash_seed(smartbody, xbot):
    """The same pack walked in a process whose string hashes differ: the same output, bit for bit."""
    walks = _walks(smartbody["second"], xbot)
    here = hashlib.sha256(b"".join(walks[k].tobytes() for k in ("straight", "target"))).hexdigest()
    seed = "1" if os.environ.get("PYTHONHASHSEED") != "1" else "2"
    done = subprocess.run([sys.executable, "-c", SUBPROCESS.format(angles=TARGET_ANGLES), str(smartbody["second"].manifest.path),
                           str(corpus_file("runxaway-models/Xbot.glb"))], capture_output=True, text=True, timeout=600,
                          env={**os.environ, "PYTHONHASHSEED": seed})
    assert done.returncode == 0, done.stderr
    assert done.stdout.split()[-1] == here


def test_coinciding_examples_share_their_weight_in_any_order():
    """Two examples at one point (a last bit apart, as two takes straightened to the same walk are): Qhull
    keeps one of them, which one turns on those bits; the blend gives each half, in either order."""
    from infuse.packs.tessellation import Tessellation

    walk = np.array([1.2, 0.0, 0.0])
    points = np.array([[0.0, 0.0, 0.0], walk, np.nextafter(walk, 2.0), [0.8, 0.4, 0.0], [0.9, 0.0, 0.6], [0.7, -0.3, -0.5]])
    labels = ["idle", "walk_a", "walk_b", "left", "turn", "right"]
    query = np.array([[1.0, 0.05, 0.05], [1.2, 0.0, 0.0]])
    weights = {}
    for order in ([0, 1, 2, 3, 4, 5], [2, 5, 1, 0, 4, 3]):
        t = Tessellation.build(("vf", "vl", "w"), [labels[k] for k in order], points[order])
        w, inside = t.weights(query)
        assert inside.all()
        weights[tuple(order)] = {label: w[:, k] for k, label in enumerate(t.labels)}
    first, second = weights.values()
    for label in labels:
        np.testing.assert_allclose(first[label], second[label], atol=1e-12)
    np.testing.assert_allclose(first["walk_a"], first["walk_b"], atol=1e-12)
    np.testing.assert_allclose(first["walk_a"][1], 0.5, atol=1e-9)  # at the walk: half each
