"""Labelled Acclaim corpus files load with their joints; FK matches the standard ASF/AMC matrix chain.

The chain is the one of the CMU ASF/AMC viewers, written here from the raw numbers: for each bone,
``G = G_parent C M C^-1`` (``C`` from ``axis``, ``M`` from the AMC angles, both ``Rz Ry Rx``
matrices) and the bone's end is ``end_parent + length * G direction``.
"""
from __future__ import annotations

import json
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import infuse
from infuse.cli.builtin import asset_summary
from infuse.kinematics import end_site_positions, motion_fk
from corpus_data import REPO, corpus_file, labels, require_corpus

ACCLAIM = [d for d in labels() if d["meta"]["format"].startswith("Acclaim")]
INFUSE = Path(sys.executable).with_name("infuse")
CMU_METRES = 0.0254 / 0.45  # CMU ASF length unit: 1/0.45 inch


def _wanted(doc) -> set[str]:
    return {v for v in doc["mapping"].values() if v}


def test_corpus_has_acclaim_labels():
    require_corpus()
    assert sorted(Path(d["file"]).suffix for d in ACCLAIM) == [".amc", ".asf", ".asf"]


@pytest.mark.parametrize("doc", ACCLAIM, ids=lambda d: Path(d["file"]).name)
def test_labelled_file_loads_with_its_joints(doc):
    asset = infuse.load(corpus_file(doc["file"]))
    summary = asset_summary(asset)
    assert _wanted(doc) <= set(summary["joints"])
    assert summary["units"] == "cmu" and summary["units_detected_by"] == "file"
    assert summary["up_axis"] == "Y"
    assert 1.4 < summary["height_m"] < 2.1


@pytest.mark.parametrize("doc", [d for d in ACCLAIM if not d["file"].endswith("11.asf")], ids=lambda d: Path(d["file"]).name)
def test_cli_info_json(doc):
    run = subprocess.run([str(INFUSE), "info", str(corpus_file(doc["file"])), "--json"],
                         capture_output=True, text=True, cwd=REPO, timeout=120)
    assert run.returncode == 0, run.stderr
    summary = json.loads(run.stdout)
    assert _wanted(doc) <= set(summary["joints"])
    if doc["file"].endswith(".amc"):
        assert Path(summary["meta"]["skeleton_file"]).name == "11.asf"
        assert summary["frames"] == len(re.findall(r"^\d+\s*$", corpus_file(doc["file"]).read_text(), re.M))


# -- independent matrix chain -----------------------------------------------------------------
def rot(axis: str, degrees: np.ndarray) -> np.ndarray:
    a = np.radians(np.asarray(degrees, dtype=np.float64))
    c, s = np.cos(a), np.sin(a)
    m = np.zeros(a.shape + (3, 3))
    i, j = {"x": (1, 2), "y": (2, 0), "z": (0, 1)}[axis]
    k = 3 - i - j
    m[..., k, k] = 1.0
    m[..., i, i], m[..., j, j], m[..., i, j], m[..., j, i] = c, c, -s, s
    return m


def euler_xyz(angles: np.ndarray) -> np.ndarray:
    return rot("z", angles[..., 2]) @ rot("y", angles[..., 1]) @ rot("x", angles[..., 0])


def raw_asf(text: str):
    bones = {}
    for block in re.findall(r"begin(.*?)end", text.split(":bonedata")[1].split(":hierarchy")[0], re.S):
        fields = {line.split()[0]: line.split()[1:] for line in block.strip().splitlines() if line.strip()}
        bones[fields["name"][0]] = dict(direction=np.array(fields["direction"], float), length=float(fields["length"][0]),
                                        axis=np.array(fields["axis"][:3], float), dof=fields.get("dof", []))
    parent = {}
    for line in text.split(":hierarchy")[1].splitlines():
        names = line.split()
        if len(names) > 1:
            for child in names[1:]:
                parent[child] = names[0]
    return bones, parent


def raw_amc(text: str) -> dict[str, np.ndarray]:
    """Bone name -> (F, values) as written."""
    rows: dict[str, list] = {}
    for line in text.splitlines():
        words = line.split()
        if words and not words[0].startswith((":", "#")) and not (words[0].isdigit() and len(words) == 1):
            rows.setdefault(words[0], []).append(words[1:])
    return {name: np.array(r, float) for name, r in rows.items()}


def chain(asf_text: str, amc_text: str | None):
    """Root positions (F,3) and each bone's start and end positions (F,3), metres, for all frames at once."""
    bones, parent = raw_asf(asf_text)
    values = raw_amc(amc_text) if amc_text else {"root": np.zeros((1, 6))}
    frames = len(values["root"])
    g = {"root": euler_xyz(values["root"][:, 3:6])}
    end = {"root": values["root"][:, :3] * CMU_METRES}
    start = {}
    todo = [c for c, p in parent.items() if p == "root"]
    while todo:
        name = todo.pop(0)
        b = bones[name]
        angles = np.zeros((frames, 3))
        for k, d in enumerate(b["dof"] if name in values else []):
            angles[:, "xyz".index(d[1])] = values[name][:, k]
        c = euler_xyz(b["axis"])
        g[name] = g[parent[name]] @ c @ euler_xyz(angles) @ c.T
        start[name] = end[parent[name]]
        end[name] = start[name] + b["length"] * CMU_METRES * (g[name] @ b["direction"])
        todo += [k for k, p in parent.items() if p == name]
    return end["root"], start, end


def test_amc_fk_matches_matrix_chain():
    amc_path = corpus_file("fairmotion/tests/data/11_01.amc")
    asf_text = corpus_file("fairmotion/tests/data/11.asf").read_text()
    motion = next(iter(infuse.load(amc_path).motions.values()))
    g_rot, g_pos = motion_fk(motion)
    ends = end_site_positions(motion.skeleton, g_rot, g_pos)
    names = motion.skeleton.names
    root, bone_start, bone_end = chain(asf_text, amc_path.read_text())
    assert len(root) == motion.num_frames
    start = np.stack([bone_start[n] for n in names[1:]], axis=1)
    tips = np.stack([bone_end[names[j]] for j in motion.skeleton.end_site_parents], axis=1)
    assert np.abs(g_pos[:, 0] - root).max() < 1e-6
    assert np.abs(g_pos[:, 1:] - start).max() < 1e-6
    assert np.abs(ends - tips).max() < 1e-6
    head, feet = names.index("head"), [names.index(n) for n in ("lfoot", "rfoot", "ltoes", "rtoes")]
    assert np.all(g_pos[:, head, 1] > g_pos[:, feet, 1].max(axis=1) + 0.5), "upright in every frame (a kick)"
    assert np.all(np.abs(g_pos[:, feet, 1].min(axis=1)) < 0.2), "a foot near the ground in every frame"


@pytest.mark.parametrize("rel", ["fairmotion/tests/data/01.asf", "fairmotion/tests/data/11.asf"])
def test_asf_rest_pose_matches_matrix_chain(rel):
    path = corpus_file(rel)
    sk = infuse.load(path).skeleton
    root, start, end = chain(path.read_text(), None)
    positions = np.array([root[0]] + [start[n][0] for n in sk.names[1:]])
    assert np.abs(sk.rest_global_positions - positions).max() < 1e-6
    tips = np.array([end[sk.names[j]][0] for j in sk.end_site_parents])
    assert np.abs(sk.rest_end_site_positions - tips).max() < 1e-6
    assert 1.4 < sk.height() < 2.1


def test_amc_skeleton_option_and_fps(tmp_path):
    amc = corpus_file("fairmotion/tests/data/11_01.amc")
    other = corpus_file("fairmotion/tests/data/01.asf")
    asset = infuse.load(amc, skeleton=other, fps=60)
    assert asset.meta["skeleton_file"] == str(other)
    motion = next(iter(asset.motions.values()))
    assert motion.fps == 60 and "fps_rule" not in asset.meta
    default = infuse.load(amc)
    assert next(iter(default.motions.values())).fps == 120 and "fps_rule" in default.meta
    # A different skeleton gives different bone lengths, hence different FK.
    a = motion_fk(motion)[1]
    b = motion_fk(next(iter(default.motions.values())))[1]
    assert np.abs(a - b).max() > 0.01


def test_units_override_and_up_axis(tmp_path):
    path = corpus_file("fairmotion/tests/data/11.asf")
    base = infuse.load(path).skeleton
    inch = infuse.load(path, units="inch")
    assert inch.units_detected_by == "override"
    assert inch.skeleton.height() == pytest.approx(base.height() * 0.45)
    z_up = infuse.load(path, up_axis="Z")
    assert z_up.source_up_axis == "Z"
    # Declaring +Z up turns the file's +Z (toes) into the core's up direction.
    toes = z_up.skeleton.names.index("ltoes")
    foot = z_up.skeleton.names.index("lfoot")
    d = z_up.skeleton.rest_global_positions[toes] - z_up.skeleton.rest_global_positions[foot]
    assert d[1] > abs(d[0]) and d[1] > abs(d[2])
