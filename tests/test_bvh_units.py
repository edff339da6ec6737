"""The BVH unit guess on every labelled humanoid corpus BVH: each figure comes out adult-sized.

The table (file, guessed unit, standing height, leg length) is printed with ``pytest -s`` and in
any failure message. Standing height is :func:`infuse.conventions.figure_height` measured in metres
on the loaded asset, from the labelled pelvis; leg length (thigh + shin, from the labelled hip, knee
and ankle) does not depend on the pose or on how the height is measured.
"""
from __future__ import annotations

import numpy as np
import pytest

import infuse
from infuse.conventions import HUMAN_HEIGHT_RANGE_M, figure_height
from infuse.kinematics import forward_kinematics

from corpus_data import corpus_file, labels, require_corpus

HUMANOID_BVH = [doc for doc in labels() if doc["meta"]["format"].startswith("BVH") and doc["humanoid"]]
#: Thigh + shin of adults 1.4 to 2.0 m tall (about 0.47 to 0.5 of the standing height), metres.
LEG_RANGE_M = (0.65, 1.0)
#: Units established from the files themselves, by family.
KNOWN_UNITS = {
    # CMU conversions keep the ASF's bone lengths (a 7.3-unit thigh): 1/0.45 inch per unit.
    "bvh11/resources/131_01.bvh": "cmu",
    "deep-motion-editing/blender_rendering/example.bvh": "cmu",
    "deep-motion-editing/style_transfer/data/xia_test/neutral_01_000.bvh": "cmu",
    # The same skeleton as the Xia clips converted to metres (0.0564 m per CMU unit).
    "fairmotion/fairmotion/tasks/pfnn/data/motion/pfnn_hierarchy.bvh": "m",
    # Hand and thumb end sites of exactly 3.9370 units: 10 cm written in inches.
    "pymo/demos/data/AV_8Walk_Meredith_HVHA_Rep1.bvh": "inch",
    "rgbdacquisition/Motions/makehuman.bvh": "dm",
    "bandai/Bandai-Namco-Research-Motiondataset-1/data/dataset-1_walk_normal_001.bvh": "cm",
}
SAMPLE_FRAMES = 16


def _subtree(parents: np.ndarray, root: int) -> np.ndarray:
    inside = np.zeros(len(parents), dtype=bool)
    inside[root] = True
    for j in range(root + 1, len(parents)):  # parents precede children
        inside[j] = parents[j] >= 0 and inside[parents[j]]
    return np.flatnonzero(inside)


def _row(doc: dict) -> dict:
    asset = infuse.load(corpus_file(doc["file"]))
    sk, mapping = asset.skeleton, doc["mapping"]
    body = _subtree(sk.parents, sk.index[mapping["base"]])  # leaves out ground roots above the pelvis
    rest = np.concatenate((sk.rest_global_positions[body],
                           sk.rest_end_site_positions[np.isin(sk.end_site_parents, body)]))
    poses = None
    motion = next(iter(asset.motions.values()), None)
    if motion is not None:
        every = slice(None, None, max(1, motion.num_frames // SAMPLE_FRAMES))
        translations = None if motion.joint_translations is None else motion.joint_translations[every]
        poses = forward_kinematics(sk, motion.local_rotations[every], motion.root_translations[every],
                                   translations)[1][:, body]
    pos = sk.rest_global_positions
    legs = [np.linalg.norm(pos[sk.index[mapping[f"{s}_knee"]]] - pos[sk.index[mapping[f"{s}_hip"]]])
            + np.linalg.norm(pos[sk.index[mapping[f"{s}_ankle"]]] - pos[sk.index[mapping[f"{s}_knee"]]])
            for s in "lr"]
    return {"file": doc["file"], "unit": asset.source_units, "by": asset.units_detected_by,
            "height_m": figure_height(rest, 0, poses), "leg_m": float(np.mean(legs))}


@pytest.fixture(scope="module")
def table() -> list[dict]:
    require_corpus()
    return [_row(doc) for doc in HUMANOID_BVH]


def _format(rows: list[dict]) -> str:
    width = max(len(r["file"]) for r in rows)
    lines = [f"{'file':{width}} {'unit':5} {'height m':>8} {'leg m':>6}"]
    lines += [f"{r['file']:{width}} {r['unit']:5} {r['height_m']:8.2f} {r['leg_m']:6.2f}" for r in rows]
    return "\n".join(lines)


def test_every_humanoid_bvh_is_adult_sized(table):
    print("\n" + _format(table))
    assert len(table) >= 45
    lo, hi = HUMAN_HEIGHT_RANGE_M
    wrong = [r for r in table if not (lo <= r["height_m"] <= hi and LEG_RANGE_M[0] <= r["leg_m"] <= LEG_RANGE_M[1])]
    assert not wrong, "figures outside an adult's size:\n" + _format(wrong)
    assert {r["by"] for r in table} == {"guess"}


def test_units_found_in_the_files_are_guessed(table):
    guessed = {r["file"]: r["unit"] for r in table}
    assert {f: guessed[f] for f in KNOWN_UNITS} == KNOWN_UNITS


def test_override_still_wins():
    require_corpus()
    asset = infuse.load(corpus_file("bvh11/resources/131_01.bvh"), units="dm")
    assert (asset.source_units, asset.units_detected_by) == ("dm", "override")
    assert "units_guess" not in asset.meta
