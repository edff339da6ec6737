"""A joint with thousands of branches: the heuristic mapper compares only its longest branches as limbs,
so a file cannot make the limb search grow with the square of its joints; a hand with many digit-like
chains matches only a handful of them to the fingers."""
from __future__ import annotations

import time

import numpy as np
import pytest

import infuse
from infuse.canonical import BODY_NAMES, canonical_skeleton
from infuse.errors import NotHumanoidError
from infuse.mapping import map_skeleton
from infuse_heuristic_mapper.body import MAX_LIMB_BRANCHES, limb_pairs
from infuse_heuristic_mapper.view import SkeletonView

import skeleton_variants


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


def test_a_hand_with_many_digit_chains_is_matched_quickly():
    """Twenty two-joint chains under each hand (straps, claws, hair) beside the fingers: the finger
    matching looks at a handful of chains only, the body is mapped and no digit gets two names."""
    sk = canonical_skeleton(extras=False)
    names = list(sk.names)
    parents = [int(p) for p in sk.parents]
    pos = list(sk.rest_global_positions)
    rng = np.random.default_rng(1)
    for side in "lr":
        wrist = sk.index[f"{side}_wrist"]
        for k in range(20):
            d = rng.normal(size=3) * 0.02
            for step in (1, 2):
                names.append(f"strap_{side}_{k}_{step}")
                parents.append(wrist if step == 1 else len(names) - 2)
                pos.append(pos[wrist] + step * d)
    skeleton = skeleton_variants._from_positions(names, parents, np.array(pos))
    t0 = time.process_time()
    mapping = map_skeleton(skeleton)
    assert time.process_time() - t0 < 1.0
    assert all(mapping[n] == n for n in BODY_NAMES)
    mapped = [j for j in mapping.joints.values() if j is not None]
    assert len(mapped) == len(set(mapped))
