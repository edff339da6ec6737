"""Every labelled SmartBody corpus file loads and reports the joints its label names."""
from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import infuse
from infuse.cli.builtin import asset_summary
from corpus_data import REPO, corpus_file, labels, require_corpus

SMARTBODY = [d for d in labels() if d["meta"]["format"].startswith("SmartBody")]
INFUSE = Path(sys.executable).with_name("infuse")


def _label_id(doc):
    return doc["file"].removeprefix("smartbody/")


def _wanted(doc) -> set[str]:
    return {v for v in doc["mapping"].values() if v}


def test_corpus_has_smartbody_labels():
    require_corpus()
    kinds = {d["meta"]["format"].split()[1] for d in SMARTBODY}
    assert kinds == {".sk", ".skm"}
    assert len(SMARTBODY) >= 100


@pytest.mark.parametrize("doc", SMARTBODY, ids=_label_id)
def test_labelled_file_loads_with_its_joints(doc):
    asset = infuse.load(corpus_file(doc["file"]))
    summary = asset_summary(asset)
    missing = _wanted(doc) - set(summary["joints"])
    assert not missing, f"joints named by the label but not reported: {sorted(missing)}"
    assert len(summary["parents"]) == len(summary["joints"])
    if doc["meta"].get("units"):  # "cm", "m" or "cm (not stated)": the reader must find the same unit
        assert summary["units"] == doc["meta"]["units"].split()[0]
        assert summary["units_detected_by"] == ("guess" if "not stated" in doc["meta"]["units"] else "file")
    if doc["file"].endswith(".skm"):
        motion = next(iter(asset.motions.values()))
        assert motion.num_frames == doc["meta"]["frames"]
        if doc["meta"].get("fps"):
            assert motion.fps == pytest.approx(doc["meta"]["fps"], rel=1e-3)
        assert asset.meta["skeleton_file"], "every corpus motion has a skeleton beside it"
        # The skeleton is a superset of the motion's channel joints, and its units were resolved.
        animated = [n for n, a in zip(asset.skeleton.names, motion.animated_mask) if a]
        assert animated and set(animated) <= set(summary["joints"])
        assert np.all(np.isfinite(motion.local_rotations))


def _skeleton_expected(skm: str) -> str:
    """Where SmartBody keeps the character of each corpus motion folder."""
    if "/behaviorsets/" in skm:
        folder = Path(skm).parent.parent / "skeletons"
        return str(next(folder.glob("*.sk")))
    return str(Path(skm).parent.parent / f"{Path(skm).parent.parent.name}.sk")


@pytest.mark.parametrize("rel", [
    "smartbody/behaviorsets/MaleLocomotion/motions/ChrUtah_Walk001.skm",
    "smartbody/behaviorsets/FemaleLocomotion/motions/ChrHarmony@Walk01.skm",
    "smartbody/behaviorsets/reaching/motions/HandsAtSide_RArm_GestureYou.skm",
    "smartbody/ChrBrad/face/ChrBrad@112_happy.skm",
])
def test_motion_finds_its_skeleton(rel):
    path = corpus_file(rel)
    asset = infuse.load(path)
    assert Path(asset.meta["skeleton_file"]).resolve() == Path(_skeleton_expected(str(path))).resolve()


@pytest.mark.parametrize("rel", [
    "smartbody/ChrBrad/ChrBrad.sk",
    "smartbody/behaviorsets/MaleLocomotion/motions/ChrUtah_Jog001.skm",
    "smartbody/ChrBrad/face/ChrBrad@045_blink_rt.skm",
])
def test_cli_info_json(rel):
    doc = next(d for d in SMARTBODY if d["file"] == rel)
    path = corpus_file(rel)
    run = subprocess.run([str(INFUSE), "info", str(path), "--json"], capture_output=True, text=True, cwd=REPO, timeout=120)
    assert run.returncode == 0, run.stderr
    summary = json.loads(run.stdout)
    assert _wanted(doc) <= set(summary["joints"])
    assert summary["up_axis"] == "Y"
    assert 1.4 < summary["height_m"] < 2.1
    if rel.endswith(".skm"):
        assert summary["frames"] == doc["meta"]["frames"]
        assert summary["meta"]["skeleton_file"].endswith(".sk")
