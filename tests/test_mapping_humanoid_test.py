"""The humanoid test of both built-in mappers: any biped is accepted (cartoon proportions, arms hanging
below the feet, any facing), bodies without two legs and two arms on a trunk are refused with the
reason, by the ``heuristic`` and by the ``names`` mapper alike."""
from __future__ import annotations

import numpy as np
import pytest

import infuse
from infuse import quaternions as quat
from infuse.canonical import BODY_NAMES, CANONICAL_NAMES, canonical_skeleton
from infuse.cli import main as cli_main
from infuse.mapping import map_skeleton

import skeleton_variants
from wild_data import require_wild, wild_file, wild_labels

LEGS = tuple(f"{s}_{j}" for s in "lr" for j in ("hip", "knee", "ankle", "forefoot", "toe"))


def _canonical() -> tuple[infuse.Skeleton, dict]:
    """The canonical skeleton (required joints) and its label (every name is its own joint)."""
    sk = canonical_skeleton(extras=False)
    return sk, {"mapping": {n: n for n in CANONICAL_NAMES}, "alternatives": {}}


def _wrong(joints: dict, variant, names=BODY_NAMES) -> list:
    return [(k, joints.get(k), variant.mapping[k]) for k in names
            if joints.get(k) != variant.mapping[k] and joints.get(k) not in variant.alternatives.get(k, [])]


@pytest.mark.parametrize("factors", [skeleton_variants.CARTOON, {"arms": 1.8, "legs": 0.5, "head": 2.2}],
                         ids=["cartoon", "frog"])
@pytest.mark.parametrize("arms_deg", [0.0, -45.0, -85.0], ids=["t_pose", "a_pose", "arms_down"])
def test_cartoon_bipeds_are_accepted(factors, arms_deg):
    """Long arms, short legs and a big head, arms level, at 45 degrees or hanging below the feet,
    lying as if Z were up: every body joint right."""
    sk, label = _canonical()
    v = skeleton_variants.proportioned(sk, None, label, factors, "cartoon")
    v = skeleton_variants.arms_posed(v.skeleton, None, label, arms_deg, "posed")
    v = skeleton_variants.transformed(v.skeleton, None, label, rotation="z_up")
    hands = v.skeleton.rest_global_positions[[v.skeleton.index["l_wrist"], v.skeleton.index["r_wrist"]]]
    feet = v.skeleton.rest_global_positions[[v.skeleton.index["l_ankle"], v.skeleton.index["r_ankle"]]]
    if arms_deg == -85.0 and factors["arms"] > 1.5:
        assert hands[:, 2].max() < feet[:, 2].min()  # the hands hang below the feet
    assert _wrong(map_skeleton(v.skeleton).joints, v) == []


@pytest.mark.parametrize("mapper", ["heuristic", "names"])
def test_generated_non_humanoids_are_refused(mapper):
    """The canonical body without its legs (a trunk with arms) or without its arms: refused by both
    mappers with the reason."""
    sk, label = _canonical()
    variants = skeleton_variants.non_humanoid_variants(sk, None, label)
    assert [v.name for v in variants] == ["no_legs", "no_arms"]
    for v in variants:
        assert not v.humanoid
        with pytest.raises(infuse.NotHumanoidError) as err:
            map_skeleton(v.skeleton, mapper=mapper)
        assert "two legs and two arms" in err.value.reason


def _legs_turned(sk: infuse.Skeleton, degrees: float) -> np.ndarray:
    """Rest positions with each leg turned forward about its hip by ``degrees`` (90: sitting)."""
    pos = sk.rest_global_positions.copy()
    q = quat.from_axis_angle(np.array([1.0, 0.0, 0.0]), np.radians(-degrees))  # +X is the left: -X turns forward
    for side in "lr":
        hip = sk.index[f"{side}_hip"]
        moved = [sk.index[f"{side}_{j}"] for j in ("knee", "ankle", "forefoot", "toe")]
        pos[moved] = pos[hip] + quat.rotate(q, pos[moved] - pos[hip])
    return pos


def test_names_mapper_checks_the_body():
    """Names alone do not make a humanoid: the names mapper maps the standing canonical body and
    refuses it with its legs turned to point along the spine's line, with the reason."""
    sk, _ = _canonical()
    assert map_skeleton(sk, mapper="names")["l_hip"] == "l_hip"
    assert sk.rest_global_positions[sk.index["l_toe"], 2] > sk.rest_global_positions[sk.index["l_ankle"], 2]
    lying = skeleton_variants._from_positions(sk.names, sk.parents, _legs_turned(sk, 150.0))
    with pytest.raises(infuse.NotHumanoidError) as err:
        map_skeleton(lying, mapper="names")
    assert "four-legged or lying" in err.value.reason


def test_names_mapper_refuses_the_flying_head_with_exit_3(capsys):
    """A flying head whose arms carry humanoid names: the names mapper refuses it on the command line
    with one line and the reason."""
    require_wild()
    files = [label["file"] for label in wild_labels() if "flying head" in label["convention"]]
    assert files
    code = cli_main(["map", str(wild_file(files[0])), "--mapper", "names"])
    err = capsys.readouterr().err
    assert code == 3
    assert "not a humanoid" in err and "two legs and two arms" in err and len(err.strip().splitlines()) == 1


def test_wild_cartoon_frog_with_its_arms_down():
    """The wild cartoon frog (arms longer than its legs, feet driven by IK) with its arms hanging
    85 degrees down: its fingertips reach below its feet, and it is still mapped as a biped with
    every body joint right."""
    require_wild()
    labels = [label for label in wild_labels() if "Frog" in label["file"]]
    assert labels
    label = labels[0]
    asset = infuse.load(wild_file(label["file"]))
    v = skeleton_variants.arms_posed(asset.skeleton, None, label, -85.0, "arms_down")
    pos = v.skeleton.rest_global_positions
    fingertips = [v.skeleton.index[n] for n in v.skeleton.names if n.startswith(("Middle3", "Pinky3"))]
    feet = [v.skeleton.index[label["mapping"][k]] for k in ("l_ankle", "r_ankle")]
    assert pos[fingertips, 1].min() < pos[feet, 1].max()
    assert _wrong(map_skeleton(v.skeleton).joints, v) == []


def _armless_with_girdle() -> skeleton_variants.Variant:
    """The canonical body with both clavicle joints per side (the sternal end well off the chest joint,
    as in rigs whose chest joint sits at the back) and its arms removed from the upper arm down: what
    is left of each shoulder girdle is a two-joint chain as long as a short cartoon arm."""
    sk = canonical_skeleton(extras=True)
    pos = sk.rest_global_positions.copy()
    chest = pos[sk.index["spine3"]]
    for side, sign in (("l", 1.0), ("r", -1.0)):
        pos[sk.index[f"{side}_sternoclavicular"]] = chest + [0.1 * sign, 0.06, 0.12]
        pos[sk.index[f"{side}_acromioclavicular"]] = chest + [0.17 * sign, 0.1, 0.06]
    sk = skeleton_variants._from_positions(sk.names, sk.parents, pos)
    label = {"mapping": {n: n for n in CANONICAL_NAMES}, "alternatives": {}}
    return skeleton_variants.removed(sk, None, label, "arms")


@pytest.mark.parametrize("names", ["own", "meaningless", "landmark_leaves"])
def test_a_shoulder_girdle_without_arms_is_no_pair_of_arms(names):
    """Two clavicle joints per side left without arms are refused as arms by their short reach
    (geometry alone, with meaningless names; also when each carries four landmark leaves, which are
    no digits) and the reason says so."""
    v = _armless_with_girdle()
    sk = v.skeleton
    if names == "landmark_leaves":
        for side, sign in (("l", 1.0), ("r", -1.0)):
            end = sk.rest_global_positions[sk.index[f"{side}_acromioclavicular"]]
            sk = _with_chains(sk, f"{side}_acromioclavicular",
                              {f"{side}_mark{k}": (end + [0.02 * sign, 0.01 * k - 0.015, 0.0])[None] for k in range(4)})
        sk = skeleton_variants.meaningless(sk, None, {"mapping": {}, "alternatives": {}}).skeleton
    if names == "meaningless":
        sk = skeleton_variants.meaningless(sk, None, {"mapping": {}, "alternatives": {}}).skeleton
    stubs = [n for n in v.skeleton.names if n.endswith("clavicular")]
    assert len(stubs) == 4
    with pytest.raises(infuse.NotHumanoidError) as err:
        map_skeleton(sk)
    assert "shoulder girdle without arms" in err.value.reason


def _with_chains(sk: infuse.Skeleton, parent: str, chains: dict[str, np.ndarray]) -> infuse.Skeleton:
    """``sk`` with extra chains hanging from ``parent``: name -> (K, 3) joint positions."""
    names, parents = list(sk.names), list(sk.parents)
    pos = [p for p in sk.rest_global_positions]
    for name, points in chains.items():
        prev = sk.index[parent]
        for k, point in enumerate(points):
            names.append(f"{name}_{k:02d}")
            parents.append(prev)
            prev = len(names) - 1
            pos.append(point)
    return skeleton_variants._from_positions(names, parents, np.array(pos))


@pytest.mark.parametrize("words", [("J_L_Mune", "J_R_Mune"), ("Ctrl_Arm_FK_L", "Ctrl_Arm_FK_R"),
                                   ("L_Skirt", "R_Skirt")], ids=["breasts", "controls", "cloth"])
def test_chains_named_as_no_arm_are_no_arms(words):
    """An armless body whose chest carries a mirror-image pair of three-joint chains as long as short
    arms, named as breasts (in Japanese written in Latin letters), arm controls or cloth: refused,
    because the names never say upper arm, forearm or hand."""
    sk, label = _canonical()
    armless = skeleton_variants.removed(sk, None, label, "arms").skeleton
    chest = armless.rest_global_positions[armless.index["spine3"]]
    chains = {}
    for word, side in zip(words, (1.0, -1.0)):
        start = chest + np.array([0.09 * side, -0.05, 0.08])
        chains[word] = start + np.outer(np.arange(3), [0.03 * side, -0.08, 0.1])
    body = _with_chains(armless, "spine3", chains)
    with pytest.raises(infuse.NotHumanoidError) as err:
        map_skeleton(body)
    assert "two legs and two arms" in err.value.reason


def test_stubby_robot_arms_without_hands_are_arms():
    """Short arms of an upper arm alone (no forearm or hand joint), 0.25 of the leg length: still a
    biped, with its shoulders and elbows mapped."""
    sk, label = _canonical()
    v = skeleton_variants.removed(sk, None, label, "fingers")
    keep = [n for n in v.skeleton.names if not n.endswith(("_wrist", "_forearm"))]
    idx = v.skeleton.index
    parents = []
    for n in keep:
        p = int(v.skeleton.parents[idx[n]])
        while p >= 0 and v.skeleton.names[p] not in keep:
            p = int(v.skeleton.parents[p])
        parents.append(keep.index(v.skeleton.names[p]) if p >= 0 else -1)
    pos = v.skeleton.rest_global_positions[[idx[n] for n in keep]]
    robot = skeleton_variants._from_positions(keep, parents, pos)
    legs = np.linalg.norm(pos[keep.index("l_hip")] - pos[keep.index("l_ankle")])
    upper = np.linalg.norm(pos[keep.index("l_elbow")] - pos[keep.index("l_shoulder")])
    assert upper / legs < 0.4
    joints = map_skeleton(robot).joints
    assert [joints.get(f"{s}_{j}") for s in "lr" for j in ("shoulder", "elbow")] == [
        f"{s}_{j}" for s in "lr" for j in ("shoulder", "elbow")]


def _mixamo_body(unknown: str) -> skeleton_variants.Variant:
    """The canonical body in Mixamo names, its ``unknown`` limbs ("arms" or "legs") renamed into words
    no dictionary knows (``Brachium7``, ``Crus3``...)."""
    sk, label = _canonical()
    v = skeleton_variants.convention(sk, None, label, "mixamo")
    parts = skeleton_variants.LIMB_PARTS[unknown]
    rename = {n: n for n in v.skeleton.names}
    for i, (k, joint) in enumerate(sorted(v.mapping.items())):
        if k[:2] in ("l_", "r_") and skeleton_variants._part(k) in parts and joint is not None:
            rename[joint] = f"Zq{k[0].upper()}{i}"
    return skeleton_variants._renamed(v.skeleton, None, {"mapping": v.mapping, "alternatives": {}}, rename, "unknown")


@pytest.mark.parametrize("unknown", ["arms", "legs"])
def test_names_mapper_maps_what_it_reads_when_a_limb_is_named_in_an_unknown_convention(unknown):
    """Mixamo names with the arms (or legs) named in words no dictionary knows: the hierarchy shows
    the missing pair, so the body is accepted; the named joints are mapped, the unknown limbs are left
    unmapped with a low confidence and a reason that points at the limbs."""
    v = _mixamo_body(unknown)
    mapping = map_skeleton(v.skeleton, mapper="names")
    known = "legs" if unknown == "arms" else "arms"
    first = "hip" if known == "legs" else "shoulder"
    for k in (f"l_{first}", f"r_{first}", "base", "skullbase"):
        assert mapping[k] == v.mapping[k]
    gone = "shoulder" if unknown == "arms" else "hip"
    assert mapping[f"l_{gone}"] is None and mapping.confidence[f"l_{gone}"] < 0.5
    assert f"the hierarchy shows {unknown}" in mapping.reasons[f"l_{gone}"]


def test_names_mapper_reads_names_behind_a_shared_prefix():
    """Mixamo names behind a character prefix (``Character1_LeftUpLeg``) are read."""
    sk, label = _canonical()
    v = skeleton_variants.convention(sk, None, label, "mixamo")
    rename = {n: f"Character1_{n}" for n in v.skeleton.names}
    v = skeleton_variants._renamed(v.skeleton, None, {"mapping": v.mapping, "alternatives": {}}, rename, "prefixed")
    joints = map_skeleton(v.skeleton, mapper="names").joints
    assert _wrong(joints, v) == []


def test_stubby_legs_behind_forward_pelvis_helpers_stand():
    """A blob-like cartoon body: each leg starts at a pelvis helper in front of and above the pelvis
    joint, and the legs are a tenth of a person's and start above the pelvis joint, so that the feet
    end barely below it; the legs still point away from the head (accepted) and its legs and arms are
    found."""
    sk, label = _canonical()
    v = skeleton_variants.proportioned(sk, None, label, {"legs": 0.1}, "stubby")
    names, parents = list(v.skeleton.names), list(v.skeleton.parents)
    pos = list(v.skeleton.rest_global_positions)
    base = pos[v.skeleton.index["base"]]
    for side, sign in (("l", 1.0), ("r", -1.0)):
        hip = v.skeleton.index[f"{side}_hip"]
        for j in skeleton_variants._subtree(v.skeleton, hip):
            pos[j] = pos[j] + np.array([0.0, 0.12, 0.0])
        helper = skeleton_variants._insert(names, parents, pos, None, hip, 0.5, f"pelvis_helper_{side}")
        pos[helper] = base + np.array([0.03 * sign, 0.04, 0.08])
    names, parents, pos, _ = skeleton_variants._topological(names, parents, pos, None)
    body = skeleton_variants._from_positions(names, parents, pos)
    feet = pos[names.index("l_toe")][1]
    assert base[1] - 0.06 < feet < base[1]
    limbs = LEGS + tuple(f"{s}_{j}" for s in "lr" for j in ("shoulder", "elbow", "wrist"))
    assert _wrong(map_skeleton(body).joints, v, limbs) == []


@pytest.mark.parametrize("convention", ["own", "mixamo"])
def test_names_mapper_follows_the_body_when_side_names_are_mirrored(convention):
    """Side names written from the viewer's side (left and right swapped): the names mapper gives
    left and right by the body (its toes and knees show its front) and says so in the reasons."""
    sk, label = _canonical()
    if convention == "mixamo":
        v = skeleton_variants.convention(sk, None, label, "mixamo")
        sk, label = v.skeleton, {"mapping": v.mapping, "alternatives": v.alternatives}
    v = skeleton_variants.mirrored_names(sk, None, label)
    mapping = map_skeleton(v.skeleton, mapper="names")
    assert _wrong(mapping.joints, v) == []
    assert "the body decides" in mapping.reasons["l_hip"]
    plain = map_skeleton(sk, mapper="names")
    assert "the body decides" not in plain.reasons["l_hip"]
