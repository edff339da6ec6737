"""The canonical skeleton, Mapping files (save, load, complete), mapper lookup and the ``infuse map`` CLI."""
from __future__ import annotations

import json
from itertools import permutations

import numpy as np
import pytest

from infuse import InputError, NotHumanoidError, UsageError
from infuse import quaternions as quat
from infuse.cli import main as cli_main
from infuse.canonical import (ALL_NAMES, BODY_NAMES, CANONICAL_NAMES, EXTRA_NAMES, canonical_joint, canonical_joints,
                              canonical_skeleton, mirror_name)
from infuse.mapping import Mapping, map_skeleton, read_map, restrict_to_animated
from infuse.skeleton import Skeleton

from corpus_data import labels
from infuse_heuristic_mapper.matching import best_matching

LABELLED_ORDER = ("base", "spine1", "spine2", "spine3", "spine4", "spine5", "skullbase", "eyeball_left",
                  "eyeball_right")


# -- the canonical skeleton ------------------------------------------------------------------------------
def test_canonical_names_are_the_69_of_the_labelling_rules():
    assert len(CANONICAL_NAMES) == 69
    assert CANONICAL_NAMES[:9] == LABELLED_ORDER
    for side in ("l", "r"):
        for part in ("acromioclavicular", "shoulder", "elbow", "forearm", "wrist", "hip", "knee", "ankle",
                     "forefoot", "toe"):
            assert f"{side}_{part}" in CANONICAL_NAMES
        for finger in ("thumb", "index", "middle", "ring", "pinky"):
            assert all(f"{side}_{finger}{k}" in CANONICAL_NAMES for k in range(1, 5))
    assert {"l_sternoclavicular", "r_sternoclavicular"} <= set(EXTRA_NAMES)
    assert not set(EXTRA_NAMES) & set(CANONICAL_NAMES)
    assert set(BODY_NAMES) <= set(CANONICAL_NAMES)


def test_canonical_names_match_every_label_file():
    docs = labels()
    if not docs:
        pytest.skip("corpus not available")
    assert all(list(d["mapping"]) == list(CANONICAL_NAMES) for d in docs)


def test_canonical_t_pose_is_in_the_core_frame():
    sk = canonical_skeleton()
    pos = dict(zip(sk.names, sk.rest_global_positions))
    assert np.allclose(sk.rest_rotations, quat.identity((sk.num_joints,)))
    # +X is the character's left, +Y up, +Z forward; feet on the ground; about 1.75 m tall
    assert pos["l_wrist"][0] > 0.6 and pos["r_wrist"][0] < -0.6
    assert pos["skullbase"][1] > pos["spine3"][1] > pos["base"][1] > pos["l_knee"][1] > pos["l_ankle"][1]
    assert pos["l_toe"][2] > pos["l_ankle"][2] and pos["eyeball_left"][2] > pos["skullbase"][2]
    assert abs(min(p[1] for p in pos.values())) < 0.05
    assert 1.6 < pos["eyeball_left"][1] + 0.1 < 1.9
    # T-pose: the arm is straight along +X at shoulder height
    arm = np.array([pos[n] for n in ("l_shoulder", "l_elbow", "l_forearm", "l_wrist")])
    assert np.ptp(arm[:, 1]) < 0.01 and np.all(np.diff(arm[:, 0]) > 0)
    # mirror symmetry
    for name in sk.names:
        m = mirror_name(name)
        assert np.allclose(pos[m] * np.array([-1, 1, 1]), pos[name])


def test_canonical_table_rows():
    rows = canonical_joints()
    assert [r.name for r in rows] == list(ALL_NAMES)
    assert canonical_joint("l_wrist").group == "arm" and canonical_joint("l_index1").group == "hand"
    assert canonical_joint("l_wrist").side == "left" and canonical_joint("base").side == "center"
    assert canonical_joint("l_acromioclavicular").parent == "l_sternoclavicular"
    required = canonical_skeleton(extras=False)
    assert required.names == CANONICAL_NAMES
    assert required.names[required.parents[required.index["l_acromioclavicular"]]] == "spine3"
    # both skeletons put shared joints at the same place
    full = canonical_skeleton()
    for n in CANONICAL_NAMES:
        assert np.allclose(full.rest_global_positions[full.index[n]], required.rest_global_positions[required.index[n]])


# -- Mapping files ------------------------------------------------------------------------------------------
def _canonical_mapping():
    sk = canonical_skeleton()
    return sk, map_skeleton(sk)


def test_heuristic_maps_the_canonical_skeleton_onto_itself():
    sk, mapping = _canonical_mapping()
    assert mapping.mapper == "heuristic"
    for n in CANONICAL_NAMES:
        assert mapping[n] == n, n
    assert 0.5 < mapping.overall_confidence <= 1.0


def test_save_load_round_trip(tmp_path):
    sk, mapping = _canonical_mapping()
    path = mapping.save(tmp_path / "map.json")
    doc = json.loads(path.read_text())
    assert set(doc) >= {"mapping", "confidence", "unmapped"}
    assert list(doc["mapping"])[:69] == list(CANONICAL_NAMES)
    assert all(0.0 <= v <= 1.0 for v in doc["confidence"].values())
    loaded = Mapping.load(path, sk)
    assert loaded.joints == mapping.joints
    assert loaded.unmapped == mapping.unmapped
    again = map_skeleton(sk, saved_map=path)  # a complete file is used as it is
    assert again.joints == mapping.joints and again.mapper == "heuristic"


def test_partial_map_is_completed_and_hand_entries_win(tmp_path):
    sk, mapping = _canonical_mapping()
    doc = {"mapping": {"l_wrist": "l_forearm", "r_forearm": None, "spine2": None}}
    path = tmp_path / "partial.json"
    path.write_text(json.dumps(doc))
    done = map_skeleton(sk, saved_map=path)
    assert done["l_wrist"] == "l_forearm" and done.confidence["l_wrist"] == 1.0
    assert done["r_forearm"] is None and done["spine2"] is None  # null: no counterpart, kept
    assert done["l_forearm"] is None  # the joint given by hand to l_wrist is not used twice
    assert done["base"] == "base" and done["r_wrist"] == "r_wrist"  # missing keys filled in
    assert "by hand" in done.reasons["l_wrist"]


def test_map_file_errors_name_the_file_and_key(tmp_path):
    sk = canonical_skeleton()
    bad_joint = tmp_path / "bad.json"
    bad_joint.write_text(json.dumps({"mapping": {"l_wrist": "NoSuchJoint"}}))
    with pytest.raises(InputError) as err:
        map_skeleton(sk, saved_map=bad_joint)
    assert "bad.json" in str(err.value) and "mapping.l_wrist" in str(err.value) and "NoSuchJoint" in str(err.value)
    bad_key = tmp_path / "key.json"
    bad_key.write_text(json.dumps({"mapping": {"left_hand": "l_wrist"}}))
    with pytest.raises(InputError, match="mapping.left_hand"):
        read_map(bad_key)
    not_json = tmp_path / "broken.json"
    not_json.write_text("{")
    with pytest.raises(InputError, match="broken.json"):
        read_map(not_json)
    with pytest.raises(InputError, match="confidence.base"):
        map_skeleton(sk, saved_map={"mapping": {"base": "base"}, "confidence": {"base": 7}})


def test_unknown_mapper_is_a_usage_error():
    with pytest.raises(UsageError, match="no mapper named 'nope'.*heuristic"):
        map_skeleton(canonical_skeleton(), mapper="nope")


def test_motion_files_map_only_animated_joints():
    sk, mapping = _canonical_mapping()
    face = restrict_to_animated(mapping, sk, ["eyeball_left", "eyeball_right", "skullbase"])
    assert set(face.mapped()) == {"eyeball_left", "eyeball_right", "skullbase"}
    assert "not animated" in face.reasons["base"]


def test_non_humanoid_is_refused_with_a_reason():
    chain = Skeleton(("a", "b", "c", "d"), np.array([-1, 0, 1, 2]), np.array([[0, 1, 0], [0, .3, 0], [0, .3, 0], [0, .3, 0]]),
                     quat.identity((4,)))
    with pytest.raises(NotHumanoidError) as err:
        map_skeleton(chain)
    assert err.value.reason and "chain" in err.value.reason


# -- the CLI --------------------------------------------------------------------------------------------------
BVH_CHAIN = """HIERARCHY
ROOT base
{
  OFFSET 0 0 0
  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
  JOINT child1
  {
    OFFSET 0 10 0
    CHANNELS 3 Zrotation Xrotation Yrotation
    End Site
    {
      OFFSET 0 10 0
    }
  }
}
MOTION
Frames: 1
Frame Time: 0.033333
0 0 0 0 0 0 0 0 0
"""


def _bvh_of(skeleton: Skeleton, path, scale: float = 100.0) -> None:
    """A one-frame BVH of ``skeleton``'s rest pose (identity rest rotations), lengths in centimetres."""
    lines = ["HIERARCHY"]
    kids = skeleton.children

    def write(j, depth):
        pad = "  " * depth
        lines.append(f"{pad}{'ROOT' if skeleton.parents[j] < 0 else 'JOINT'} {skeleton.names[j]}")
        lines.append(pad + "{")
        off = skeleton.rest_translations[j] * scale
        lines.append(f"{pad}  OFFSET {off[0]:.5f} {off[1]:.5f} {off[2]:.5f}")
        lines.append(f"{pad}  CHANNELS {6 if depth == 0 else 3} " + ("Xposition Yposition Zposition " if depth == 0 else "")
                     + "Zrotation Xrotation Yrotation")
        for c in kids[j]:
            write(c, depth + 1)
        if not kids[j]:
            lines.extend([pad + "  End Site", pad + "  {", pad + "    OFFSET 0 1 0", pad + "  }"])
        lines.append(pad + "}")

    write(0, 0)
    channels = 6 + 3 * (skeleton.num_joints - 1)
    root = skeleton.rest_translations[0] * scale
    lines += ["MOTION", "Frames: 1", "Frame Time: 0.033333",
              " ".join([f"{root[0]:.5f}", f"{root[1]:.5f}", f"{root[2]:.5f}"] + ["0"] * (channels - 3))]
    path.write_text("\n".join(lines) + "\n")


@pytest.fixture
def cli(capsys):
    """Run the ``infuse`` CLI in this process: returns (exit code, stdout, stderr)."""
    def run(*args):
        code = cli_main([str(a) for a in args])
        out = capsys.readouterr()
        return code, out.out, out.err
    return run


@pytest.fixture(scope="module")
def canonical_bvh(tmp_path_factory):
    path = tmp_path_factory.mktemp("cli") / "canonical.bvh"
    _bvh_of(canonical_skeleton(extras=False), path)
    return path


def test_cli_map_json_and_save(cli, canonical_bvh, tmp_path):
    saved = tmp_path / "saved.json"
    code, out, err = cli("map", canonical_bvh, "--json", "--save", saved)
    assert code == 0, err
    doc = json.loads(out)
    assert doc["mapping"]["l_wrist"] == "l_wrist" and doc["mapping"]["base"] == "base"
    assert set(doc["confidence"]) == set(doc["mapping"]) and isinstance(doc["unmapped"], list)
    assert json.loads(saved.read_text())["mapping"] == doc["mapping"]
    code, out, err = cli("map", canonical_bvh)
    assert code == 0 and "l_wrist" in out and "heuristic" in out


def test_cli_map_with_partial_map_and_mapper(cli, canonical_bvh, tmp_path):
    partial = tmp_path / "partial.json"
    partial.write_text(json.dumps({"mapping": {"spine2": None, "l_forearm": None}}))
    code, out, err = cli("map", canonical_bvh, "--json", "--map", partial, "--mapper", "names")
    assert code == 0, err
    doc = json.loads(out)
    assert doc["mapping"]["spine2"] is None and doc["mapping"]["l_elbow"] == "l_elbow"


@pytest.mark.parametrize("args, code, words", [
    (("--mapper", "nope"), 2, "no mapper named 'nope'"),
    (("--map", "missing.json"), 2, "mapping file not found"),
])
def test_cli_map_usage_errors(cli, canonical_bvh, args, code, words):
    got, out, err = cli("map", canonical_bvh, *args)
    assert got == code
    assert words in err and "Traceback" not in err
    assert len(err.strip().splitlines()) == 1


def test_cli_map_non_humanoid_exits_3_with_one_line(cli, tmp_path):
    path = tmp_path / "chain.bvh"
    path.write_text(BVH_CHAIN)
    code, out, err = cli("map", path)
    assert code == 3
    assert "not a humanoid" in err and "Traceback" not in err
    assert len(err.strip().splitlines()) == 1


def test_cli_map_bad_joint_in_map_names_file_and_key(cli, canonical_bvh, tmp_path):
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps({"mapping": {"l_wrist": "Nope"}}))
    code, out, err = cli("map", canonical_bvh, "--map", bad)
    assert code == 2
    assert "bad.json" in err and "mapping.l_wrist" in err


def test_best_matching_is_the_least_cost_one_to_one_matching():
    """The mapper's small matchings (finger chains to digits) are exact: the least total of every
    one-to-one choice, with the margin to the second best."""
    rng = np.random.default_rng(3)
    for rows, cols in ((1, 1), (2, 4), (4, 4), (3, 5)):
        cost = rng.normal(size=(rows, cols))
        totals = sorted(sum(cost[i, c] for i, c in enumerate(p)) for p in permutations(range(cols), rows))
        columns, margin = best_matching(cost)
        assert len(set(columns.tolist())) == rows
        assert cost[np.arange(rows), columns].sum() == pytest.approx(totals[0])
        assert margin == (pytest.approx(totals[1] - totals[0]) if len(totals) > 1 else np.inf)
    with pytest.raises(ValueError):
        best_matching(np.zeros((3, 2)))
