"""The heuristic mapper on rigs of families it was not developed on (``INFUSE_WILD``): game characters,
mocap exports, robots and cartoon bodies, and non-humanoids that must be refused.

Targets: at least 98% of labelled joints right, every body joint right on every humanoid, every
non-humanoid refused (exit code 3 with the reason on the command line), and confidences that mean
something: of the entries given at least 0.9, at least 99% right.
"""
from __future__ import annotations

import pytest

import infuse
from infuse.canonical import BODY_NAMES, CANONICAL_NAMES
from infuse.cli import main as cli_main
from infuse.mapping import map_skeleton

import skeleton_variants
from wild_data import require_wild, wild_file, wild_labels


def _wrong(joints: dict, label: dict, names=CANONICAL_NAMES) -> list:
    alts = label.get("alternatives") or {}
    return [(k, joints.get(k), label["mapping"][k]) for k in names
            if joints.get(k) != label["mapping"][k] and joints.get(k) not in alts.get(k, [])]


@pytest.fixture(scope="module")
def wild_assets():
    """(label, asset) for every labelled wild rig, read once."""
    require_wild()
    return [(label, infuse.load(wild_file(label["file"]))) for label in wild_labels()]


@pytest.fixture(scope="module")
def wild(wild_assets):
    """(label, mapping or None, refusal or None) for every labelled wild rig."""
    out = []
    for label, asset in wild_assets:
        try:
            out.append((label, map_skeleton(asset), None))
        except infuse.NotHumanoidError as exc:
            out.append((label, None, exc))
    return out


def test_wild_rigs_are_there(wild):
    assert sum(label["humanoid"] for label, *_ in wild) >= 24
    assert sum(not label["humanoid"] for label, *_ in wild) >= 7


def test_labelled_joints(wild):
    right = total = 0
    for label, mapping, refused in wild:
        if label["humanoid"]:
            right += len(CANONICAL_NAMES) - len(_wrong(mapping.joints if mapping else {}, label))
            total += len(CANONICAL_NAMES)
    assert right / total >= 0.98, f"{right}/{total}"


def test_every_body_joint_on_every_humanoid(wild):
    failures = {}
    for label, mapping, refused in wild:
        if label["humanoid"]:
            assert refused is None, f"{label['file']} refused: {refused}"
            wrong = _wrong(mapping.joints, label, BODY_NAMES)
            if wrong:
                failures[label["file"]] = wrong
    assert not failures


def test_every_non_humanoid_is_refused_with_a_reason(wild):
    for label, mapping, refused in wild:
        if not label["humanoid"]:
            assert refused is not None, f"{label['file']} was mapped"
            assert len(refused.reason) > 20


def test_confident_entries_are_right(wild):
    """Calibration: of the entries given a confidence of at least 0.9, at least 99% are right."""
    right = total = 0
    for label, mapping, refused in wild:
        if mapping is None:
            continue
        wrong = {k for k, *_ in _wrong(mapping.joints, label)}
        sure = [k for k in CANONICAL_NAMES if mapping.confidence[k] >= 0.9]
        right += sum(k not in wrong for k in sure)
        total += len(sure)
    assert total >= 100 and right / total >= 0.99, f"{right}/{total}"


def test_mirrored_side_names_are_reported(wild):
    """A rig whose side names are the viewer's: geometry decides, and the reasons say so."""
    mirrored = [(label, m) for label, m, _ in wild if m is not None and label["mapping"]["l_hip"]
                and label["mapping"]["l_hip"].lower().startswith(("r-", "r_", "right"))]
    assert mirrored
    for label, mapping in mirrored:
        assert "opposite" in mapping.reasons["l_hip"] and "geometry decides" in mapping.reasons["l_hip"]


@pytest.mark.parametrize("kind", ["snake", "flying head", "insect", "arachnid", "quadruped"])
def test_cli_refuses_non_humanoids_with_exit_3(kind, capsys):
    require_wild()
    files = [label["file"] for label in wild_labels() if not label["humanoid"] and kind in label["convention"]]
    assert files, kind
    code = cli_main(["map", str(wild_file(files[0]))])
    err = capsys.readouterr().err
    assert code == 3
    assert "not a humanoid" in err and "Traceback" not in err and len(err.strip().splitlines()) == 1


@pytest.mark.parametrize("mapper", ["heuristic", "names"])
def test_wild_bodies_without_legs_or_arms_are_refused(mapper, wild_assets):
    """Each wild humanoid without its legs, or without its arms from the upper arm down (what is left
    of a shoulder girdle, breast, skirt, hair, control and landmark chains stay), is refused by both
    mappers with a reason; the names mapper also maps the wild humanoids whose limbs its dictionaries
    do not know when the hierarchy shows them."""
    mapped = []
    for label, asset in wild_assets:
        if not label["humanoid"]:
            continue
        variants = skeleton_variants.non_humanoid_variants(asset.skeleton, None, label)
        assert variants, label["file"]
        for v in variants:
            with pytest.raises(infuse.NotHumanoidError) as err:
                map_skeleton(v.skeleton, mapper=mapper)
            assert err.value.reason, (label["file"], v.name)
        try:
            map_skeleton(asset, mapper=mapper)
            mapped.append(label["file"])
        except infuse.NotHumanoidError:
            pass
    assert len(mapped) >= 22, mapped
