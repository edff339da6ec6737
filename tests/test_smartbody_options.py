"""SmartBody reader options and fallbacks: skeleton choice, flat skeleton, units, up axis, timing."""
from __future__ import annotations

import numpy as np
import pytest

import infuse
from infuse import quaternions as quat
from infuse.kinematics import motion_fk
from corpus_data import corpus_file

WALK = "smartbody/behaviorsets/MaleLocomotion/motions/ChrUtah_Walk001.skm"
UTAH = "smartbody/behaviorsets/MaleLocomotion/skeletons/test_utah.sk"
COMMON = "smartbody/behaviorsets/reaching/skeletons/common.sk"


def _channel_joint_names(text: str) -> list[str]:
    lines = text.splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith("channels"))
    names = [line.split()[0] for line in lines[start + 1:start + 1 + int(lines[start].split()[1])]]
    return list(dict.fromkeys(names))


def test_lone_motion_falls_back_to_flat_skeleton(tmp_path):
    lone = tmp_path / "walk.skm"
    lone.symlink_to(corpus_file(WALK))
    asset = infuse.load(lone)
    joints = _channel_joint_names(corpus_file(WALK).read_text())
    assert list(asset.skeleton.names) == joints
    assert np.all(asset.skeleton.parents == -1)
    assert asset.meta["skeleton_file"] is None and "flat" in asset.meta["skeleton_note"]
    motion = asset.motions["ChrUtah_Walk001"]
    # Without a skeleton every channel is free: the hips keep the small translations Utah's .sk freezes.
    hip = joints.index("l_hip")
    assert np.abs(motion.joint_translations[:, hip]).max() > 0.005
    assert "limited_channels" not in asset.meta


def test_skeleton_option_and_none(tmp_path):
    walk = corpus_file(WALK)
    chosen = infuse.load(walk, skeleton=corpus_file(COMMON))
    assert chosen.meta["skeleton_file"] == str(corpus_file(COMMON))
    assert chosen.meta["skeleton_found_in"] == "given by the caller"
    found = infuse.load(walk)
    assert found.meta["skeleton_found_in"] == "behaviour-set skeletons folder"
    # Utah's skeleton has an 'initial_base' above 'base'; common.sk starts at 'base'.
    assert found.skeleton.names[0] == "initial_base" and chosen.skeleton.names[0] == "base"
    flat = infuse.load(walk, skeleton="none")
    assert flat.meta["skeleton_file"] is None and np.all(flat.skeleton.parents == -1)


def test_units_override_scales_motion_translations():
    walk = corpus_file(WALK)
    cm = infuse.load(walk).motions["ChrUtah_Walk001"]
    metres = infuse.load(walk, units="m")
    assert metres.units_detected_by == "override" and metres.source_units == "m"
    m = metres.motions["ChrUtah_Walk001"]
    base = m.skeleton.names.index("base")
    moved = m.joint_translations[:, base] - m.skeleton.rest_translations[base]
    moved_cm = cm.joint_translations[:, base] - cm.skeleton.rest_translations[base]
    np.testing.assert_allclose(moved, moved_cm * 100, atol=1e-9)


def test_up_axis_override_turns_the_whole_motion():
    walk = corpus_file(WALK)
    y_up = infuse.load(walk).motions["ChrUtah_Walk001"]
    z_up = infuse.load(walk, up_axis="Z")
    assert z_up.source_up_axis == "Z"
    _, p_y = motion_fk(y_up)
    _, p_z = motion_fk(z_up.motions["ChrUtah_Walk001"])
    turn = infuse.conventions.UP_AXIS_ROTATIONS["Z"]
    np.testing.assert_allclose(p_z, quat.rotate(turn, p_y), atol=1e-9)


def _pose_file(tmp_path, times, rows, extra=""):
    body = "\n".join(f"kt {t} fr " + " ".join(map(str, r)) for t, r in zip(times, rows))
    path = tmp_path / "pose.skm"
    path.write_text(f"SkMotion\nname \"pose\"\nchannels 2\nj XPos\nj Quat\n{extra}frames {len(times)}\n{body}\n"
                    "ready time: 0.6\nrelax time: 0.8\nmood: calm\n")
    return path


def test_irregular_key_times_are_resampled(tmp_path):
    times = [0.0, 0.1, 0.25, 0.3, 0.4]
    rows = [[0.0, 0, 0, 0], [1.0, 0, 0, 0.5], [2.5, 0, 0, 1.0], [3.0, 0, 0, 1.0], [4.0, 0, 0, 1.0]]
    asset = infuse.load(_pose_file(tmp_path, times, rows), skeleton="none")
    motion = asset.motions["pose"]
    assert "resampled" in asset.meta and motion.fps == 10
    assert motion.num_frames == 5
    # Position is linear in time here, so resampling at 0.2 s gives 2.0 (metres: no header, no skeleton).
    np.testing.assert_allclose(motion.root_translations[:, 0], [0.0, 1.0, 2.0, 3.0, 4.0], atol=1e-12)
    angles = np.linalg.norm(quat.to_rotvec(motion.local_rotations[:, 0]), axis=-1)
    np.testing.assert_allclose(angles[2], 0.5 + 0.5 * (0.1 / 0.15), atol=1e-9)
    assert asset.meta["metadata"] == {"mood": "calm"}


def test_start_kt_shifts_sync_points_and_single_frame_fps(tmp_path):
    asset = infuse.load(_pose_file(tmp_path, [0.0, 1 / 30], [[0, 0, 0, 0], [1, 0, 0, 0]], "start_kt 0.5\n"), skeleton="none")
    assert asset.motions["pose"].sync_points == pytest.approx({"ready": 0.1, "relax": 0.3})
    single = infuse.load(_pose_file(tmp_path, [0.0], [[0, 0, 0, 0]]), skeleton="none")
    assert single.motions["pose"].fps == 30 and "fps_note" in single.meta
