"""``infuse retarget``: BVH and GLB output through the installed mapper, and bad input (exit 2 or 3,
one line, nothing written)."""
from __future__ import annotations

import dataclasses
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import infuse
from infuse.cli import main
from infuse.contacts import feet as contact_feet
from infuse.contacts import lowest_points
from infuse.grounding import foot_height, grounded
from infuse.kinematics import motion_fk
from infuse.mapping import map_skeleton
from infuse_gltf import validate as validator
from infuse_gltf.container import parse_file
from infuse_retarget import RetargetPlan, retarget_clip
from infuse_retarget.command import source_mapping

from corpus_data import corpus_file, labels, require_corpus

WALK = "bandai/Bandai-Namco-Research-Motiondataset-1/data/dataset-1_walk_normal_001.bvh"
XBOT = "runxaway-models/Xbot.glb"
UTAH = "smartbody/behaviorsets/MaleLocomotion/skeletons/test_utah.sk"
FOX = "projectlookingglass-glb/Fox.glb"
BRAD = "smartbody/mesh/brad/Brad.dae"
INFUSE = Path(sys.executable).with_name("infuse")


def answer_lines(stderr: str) -> list[str]:
    return [ln for ln in stderr.splitlines() if ln.strip() and not ln.startswith("infuse: warning:")]


def run(capsys, *argv) -> tuple[int, str, str]:
    code = main(["retarget", *map(str, argv)])
    out, err = capsys.readouterr()
    return code, out, err


@pytest.fixture(scope="module")
def expected():
    """The retargeted walk computed through the API with the mappings the command uses, stood on
    the ground as the command writes it."""
    require_corpus()
    walk = infuse.load(corpus_file(WALK))
    xbot = infuse.load(corpus_file(XBOT))
    clip = next(iter(walk.motions.values()))
    xbot_map = map_skeleton(xbot)
    plan = RetargetPlan(clip.skeleton, source_mapping(walk, "heuristic", None), xbot.skeleton, xbot_map,
                        source_motion=clip, target_motion=next(iter(xbot.motions.values())))
    result = retarget_clip(plan, clip)
    on_ground = {k: grounded(m, foot_height(xbot, xbot_map, m)) for k, m in (("motion", result.motion), ("plain", result.plain))}
    return xbot, dataclasses.replace(result, **on_ground)


def test_characters_stand_on_the_ground_unless_asked_not_to(tmp_path, capsys):
    """SmartBody's Brad puts his hips at the origin, his feet a metre down: written, every clip
    stands on y = 0 (its lowest sole point; his own rest clip lifted by a metre), or keeps its
    height with --no-ground."""
    brad = corpus_file(BRAD)
    out, kept = tmp_path / "brad.glb", tmp_path / "brad_kept.glb"
    assert run(capsys, corpus_file(WALK), "--to", brad, "-o", out, "--keep-clips")[0] == 0
    assert run(capsys, corpus_file(WALK), "--to", brad, "-o", kept, "--keep-clips", "--no-ground")[0] == 0
    written, unchanged = infuse.load(out), infuse.load(kept)
    mapping = map_skeleton(written)
    assert list(written.motions) == ["dataset-1_walk_normal_001", "Brad"]
    assert foot_height(written, mapping) < -0.9  # the file's rest pose is Brad's own
    for name in written.motions:
        assert abs(foot_height(written, mapping, written.motions[name])) < 1e-5, name
    assert foot_height(unchanged, mapping, unchanged.motions["Brad"]) < -0.9
    pair = contact_feet(written.skeleton, mapping)
    walk = lowest_points(written.skeleton, pair, *motion_fk(written.motions["dataset-1_walk_normal_001"]))
    assert 0.0 < np.median(walk) < 0.02  # the toe joints a little above the soles while planted


def test_bvh_output_has_the_characters_names_and_rest(tmp_path, capsys, expected):
    xbot, result = expected
    out = tmp_path / "walk_xbot.bvh"
    code, stdout, err = run(capsys, corpus_file(WALK), "--to", corpus_file(XBOT), "-o", out)
    assert code == 0, err
    assert "leg scale" in stdout and str(out) in stdout
    back = infuse.load(out)
    assert back.skeleton.names == xbot.skeleton.names
    assert np.abs(back.skeleton.rest_global_positions - xbot.skeleton.rest_global_positions).max() < 1e-6
    motion = next(iter(back.motions.values()))
    assert motion.num_frames == result.motion.num_frames
    assert np.abs(motion_fk(motion)[1] - motion_fk(result.motion)[1]).max() < 1e-5


def test_glb_output_keeps_the_mesh_and_plays_the_new_clip_first(tmp_path, capsys, expected):
    """The new clip is the glb's first animation (Blender's active action, three.js's animations[0]);
    the character's own clips follow with --keep-clips only."""
    xbot, result = expected
    out = tmp_path / "walk_xbot.glb"
    code, _, err = run(capsys, corpus_file(WALK), "--to", corpus_file(XBOT), "-o", out, "--name", "walk")
    assert code == 0, err
    before, after = parse_file(corpus_file(XBOT)).json, parse_file(out).json
    for key in ("meshes", "skins", "materials"):
        assert json.dumps(after.get(key), sort_keys=True) == json.dumps(before.get(key), sort_keys=True), key
    assert [a["name"] for a in after["animations"]] == ["walk"]
    back = infuse.load(out)
    assert list(back.motions) == ["walk"]
    assert np.abs(motion_fk(back.motions["walk"])[1] - motion_fk(result.motion)[1]).max() < 1e-4
    kept = tmp_path / "walk_xbot_kept.glb"
    code, _, err = run(capsys, corpus_file(WALK), "--to", corpus_file(XBOT), "-o", kept, "--name", "walk", "--keep-clips")
    assert code == 0, err
    assert [a["name"] for a in parse_file(kept).json["animations"]] == ["walk", *xbot.motions]
    if not validator.available():
        pytest.fail("the Khronos glTF validator is missing: run `make setup`")
    assert validator.validate(out)["issues"]["numErrors"] == 0


def test_no_ik_gives_the_plain_transfer(tmp_path, capsys, expected):
    _, result = expected
    out = tmp_path / "plain.bvh"
    code, stdout, err = run(capsys, corpus_file(WALK), "--to", corpus_file(XBOT), "-o", out, "--no-ik")
    assert code == 0 and "feet: none" in stdout, err
    motion = next(iter(infuse.load(out).motions.values()))
    assert np.abs(motion_fk(motion)[1] - motion_fk(result.plain)[1]).max() < 1e-5


def _label_map_file(tmp_path: Path, rel: str, **changes) -> Path:
    doc = next(d for d in labels() if d["file"] == rel)
    mapping = dict(doc["mapping"], **changes)
    path = tmp_path / f"{Path(rel).stem}.map.json"
    path.write_text(json.dumps({"mapping": mapping}))
    return path


def _zero_leg_bvh(tmp_path: Path) -> Path:
    text = corpus_file(WALK).read_text().splitlines()
    out, inside = [], None
    for line in text:
        stripped = line.strip()
        if stripped.startswith("JOINT"):
            inside = stripped.split()[1]
        if stripped.startswith("OFFSET") and inside in ("LowerLeg_L", "Foot_L", "LowerLeg_R", "Foot_R"):
            line = line[: line.index("OFFSET")] + "OFFSET 0 0 0"
        out.append(line)
    path = tmp_path / "zero_legs.bvh"
    path.write_text("\n".join(out) + "\n")
    return path


def _nan_bvh(tmp_path: Path) -> Path:
    lines = corpus_file(WALK).read_text().splitlines()
    k = next(i for i, ln in enumerate(lines) if ln.startswith("Frame Time")) + 3
    values = lines[k].split()
    values[7] = "nan"
    lines[k] = " ".join(values)
    path = tmp_path / "nan.bvh"
    path.write_text("\n".join(lines) + "\n")
    return path


@pytest.mark.parametrize("case,code,phrase", [
    ("non-humanoid motion", 3, "not a humanoid"),
    ("non-humanoid character", 3, "not a humanoid"),
    ("map naming a missing joint", 2, "not in the skeleton"),
    ("target map without knees", 3, "lacks l_knee"),
    ("zero-length legs", 3, "zero-length"),
    ("NaN in the motion", 2, "not a finite number"),
    ("no clip in the motion file", 3, "no motion clip"),
    ("unknown output type", 2, "no installed writer"),
])
def test_bad_input_exits_with_one_line_and_writes_nothing(tmp_path, capsys, case, code, phrase):
    require_corpus()
    motion, character, extra = corpus_file(WALK), corpus_file(XBOT), []
    out = tmp_path / "out" / "result.bvh"
    if case == "non-humanoid motion":
        motion = corpus_file(FOX)
    elif case == "non-humanoid character":
        character = corpus_file(FOX)
    elif case == "map naming a missing joint":
        extra = ["--map", _label_map_file(tmp_path, WALK, base="NoSuchJoint")]
    elif case == "target map without knees":
        extra = ["--target-map", _label_map_file(tmp_path, XBOT, l_knee=None)]
    elif case == "zero-length legs":
        motion = _zero_leg_bvh(tmp_path)
        extra = ["--map", _label_map_file(tmp_path, WALK)]
    elif case == "NaN in the motion":
        motion = _nan_bvh(tmp_path)
    elif case == "no clip in the motion file":
        motion = corpus_file(UTAH)
    else:
        out = tmp_path / "out" / "result.xyz"
    got, stdout, err = run(capsys, motion, "--to", character, "-o", out, *extra)
    lines = answer_lines(err)
    assert got == code and len(lines) == 1 and phrase in lines[0], err
    assert "Traceback" not in err and stdout == ""
    assert not out.exists() and not (out.parent.exists() and any(out.parent.iterdir()))


def test_installed_command_answers_in_one_line(tmp_path):
    require_corpus()
    out = tmp_path / "fox.bvh"
    result = subprocess.run([str(INFUSE), "retarget", str(corpus_file(FOX)), "--to", str(corpus_file(XBOT)), "-o", str(out)],
                            capture_output=True, text=True, timeout=300)
    lines = answer_lines(result.stderr)
    assert result.returncode == 3 and len(lines) == 1 and "Traceback" not in result.stderr, result.stderr
    assert not out.exists()
