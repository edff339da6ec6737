"""A joint with thousands of branches: the heuristic mapper compares only its longest branches as limbs,
so a file cannot make the limb search grow with the square of its joints."""
from __future__ import annotations

import numpy as np
import pytest

import infuse
from infuse.errors import NotHumanoidError
from infuse.mapping import map_skeleton
from infuse_heuristic_mapper.body import MAX_LIMB_BRANCHES, limb_pairs
from infuse_heuristic_mapper.view import SkeletonView


def _fan(path, lengths_cm):
    """A BVH: a root with one leaf branch of each length in ``lengths_cm``, spread in every direction."""
    rng = np.random.default_rng(0)
    lines = ["HIERARCHY", "ROOT Hips", "{", "OFFSET 0 100 0",
             "CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation"]
    for k, length in enumerate(lengths_cm):
        d = rng.normal(size=3)
        d = 0.5 * length * d / np.linalg.norm(d)
        lines += [f"JOINT j{k}", "{", "OFFSET {:.4f} {:.4f} {:.4f}".format(*d), "CHANNELS 3 Zrotation Xrotation Yrotation",
                  "End Site", "{", "OFFSET {:.4f} {:.4f} {:.4f}".format(*d), "}", "}"]
    lines += ["}", "MOTION", "Frames: 1", "Frame Time: 0.033333", " ".join(["0"] * (6 + 3 * len(lengths_cm)))]
    path.write_text("\n".join(lines) + "\n")
    return path


def test_only_the_longest_branches_of_a_joint_are_paired(tmp_path):
    lengths = np.r_[np.full(2000, 30.0), np.full(MAX_LIMB_BRANCHES, 80.0)]
    skeleton = infuse.load(_fan(tmp_path / "fan.bvh", lengths)).skeleton
    pairs = limb_pairs(SkeletonView(skeleton, skeleton.rest_global_positions))
    longest = {skeleton.index[f"j{k}"] for k in range(2000, 2000 + MAX_LIMB_BRANCHES)}
    assert pairs and all(p.a in longest and p.b in longest for p in pairs)
    assert len(pairs) <= MAX_LIMB_BRANCHES * (MAX_LIMB_BRANCHES - 1) // 2


def test_a_fan_of_thousands_of_branches_is_refused_as_not_humanoid(tmp_path):
    path = _fan(tmp_path / "fan.bvh", np.full(3000, 40.0))
    with pytest.raises(NotHumanoidError, match="not a humanoid"):
        map_skeleton(infuse.load(path))
