"""SmartBody FK: infuse's vectorized FK against an independent per-joint 4x4 matrix chain.

The chain follows SmartBody's SkJoint: row-vector matrices, ``lmat = [R(prerot) R(quat)]^T`` with
translation ``offset + position channels``, ``gmat = lmat * parent_gmat``. It is built here from
the raw numbers of the files with rotation matrices from Rodrigues' formula (no quaternions).
"""
from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

import infuse
from infuse.kinematics import motion_fk
from corpus_data import corpus_file

WALKS = {
    # motion, skeleton, metres per file unit, head joint, foot joints
    "utah": ("smartbody/behaviorsets/MaleLocomotion/motions/ChrUtah_Walk001.skm",
             "smartbody/behaviorsets/MaleLocomotion/skeletons/test_utah.sk", 0.01,
             "skullbase", ["l_ankle", "r_ankle", "l_toe", "r_toe"]),
    "harmony": ("smartbody/behaviorsets/FemaleLocomotion/motions/ChrHarmony@Walk01.skm",
                "smartbody/behaviorsets/FemaleLocomotion/skeletons/ChrHarmony.sk", 1.0,
                "JtSkullA", ["JtAnkleLf", "JtAnkleRt", "JtToeLf", "JtToeRt"]),
}
SKELETONS = ["smartbody/ChrBrad/ChrBrad.sk", "smartbody/ChrRachel/ChrRachel.sk",
             "smartbody/behaviorsets/FemaleLocomotion/skeletons/ChrHarmony.sk",
             "smartbody/behaviorsets/MaleLocomotion/skeletons/test_utah.sk",
             "smartbody/behaviorsets/reaching/skeletons/common.sk"]


# -- an independent reading of the raw numbers ------------------------------------------------
def rodrigues(rotvec: np.ndarray) -> np.ndarray:
    """(...,3,3) column-vector rotation matrices from rotation vectors (radians)."""
    rotvec = np.asarray(rotvec, dtype=np.float64)
    angle = np.linalg.norm(rotvec, axis=-1)[..., None, None]
    axis = rotvec / np.where(angle[..., 0] > 0, angle[..., 0], 1.0)
    k = np.zeros(rotvec.shape[:-1] + (3, 3))
    k[..., 0, 1], k[..., 0, 2], k[..., 1, 2] = -axis[..., 2], axis[..., 1], -axis[..., 0]
    k = k - np.swapaxes(k, -1, -2)
    return np.eye(3) + np.sin(angle) * k + (1 - np.cos(angle)) * (k @ k)


def raw_sk(text: str) -> list[dict]:
    """Joints of an .sk: name, parent, offset, prerot rotvec, free position dofs, Quat channel, Euler."""
    tokens = " ".join(line for line in text.splitlines() if not line.lstrip().startswith("#")).split()
    joints, stack, i = [], [], 0
    while i < len(tokens):
        t = tokens[i]
        if t in ("root", "joint"):
            joints.append(dict(name=tokens[i + 1], parent=stack[-1] if stack else -1, offset=np.zeros(3),
                               pre=np.eye(3), post=np.eye(3), free=np.zeros(3, bool), lim=np.zeros((3, 2)),
                               quat=False, euler=None, rot=np.zeros(3), rlim=np.zeros((3, 2)), rfree=np.zeros(3, bool)))
            i += 2
            continue
        if t == "{":
            stack.append(len(joints) - 1)
        elif t == "}":
            stack.pop()
        elif t == "offset":
            joints[-1]["offset"] = np.array(tokens[i + 1:i + 4], float)
            i += 3
        elif t in ("prerot", "postrot"):  # prerot axis x y z ang deg
            axis = np.array(tokens[i + 2:i + 5], float)
            n = np.linalg.norm(axis)
            r = rodrigues(axis / n * np.radians(float(tokens[i + 6]))) if n else np.eye(3)
            joints[-1]["pre" if t == "prerot" else "post"] = joints[-1]["pre" if t == "prerot" else "post"] @ r
            i += 6
        elif t == "euler":
            joints[-1]["euler"] = tokens[i + 1]
        elif t == "channel":
            kind = tokens[i + 1]
            if kind == "Quat":  # Quat [axis x y z ang deg] [frozen]
                skip = 6 if tokens[i + 2] == "axis" else 0
                frozen = i + 2 + skip < len(tokens) and tokens[i + 2 + skip] == "frozen"
                joints[-1]["quat"] = not frozen
                i += 1 + skip + frozen
            else:
                d = "XYZ".index(kind[0])
                value, rest = float(tokens[i + 2]), tokens[i + 3]
                free = rest == "free"
                lim = (0.0, 0.0) if free else tuple(map(float, tokens[i + 4:i + 6]))
                if kind.endswith("Pos"):
                    joints[-1]["free"][d], joints[-1]["lim"][d] = free, lim
                else:
                    joints[-1]["euler"] = joints[-1]["euler"] or "YXZ"
                    joints[-1]["rfree"][d], joints[-1]["rlim"][d] = free, np.radians(lim)
                    joints[-1]["rot"][d] = np.radians(value)
                i += 3 if free else 5
        i += 1
    return joints


def raw_skm(text: str) -> tuple[list[tuple[str, str]], np.ndarray]:
    lines = text.splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith("channels"))
    count = int(lines[start].split()[1])
    channels = [tuple(line.split()) for line in lines[start + 1:start + 1 + count]]
    values = np.array([line.split()[3:] for line in lines if line.startswith("kt ")], float)
    return channels, values


def euler_matrix(kind: str, angles: np.ndarray) -> np.ndarray:
    """SkJointEuler as matrices: YXZ = Rz Rx Ry, XYZ = Rz Ry Rx, ZY = Ry Rz (column vectors)."""
    rx, ry, rz = (rodrigues(np.eye(3)[d] * angles[..., d:d + 1]) for d in range(3))
    return {"YXZ": rz @ rx @ ry, "XYZ": rz @ ry @ rx, "ZY": ry @ rz}[kind]


def chain_positions(sk_text: str, skm_text: str | None, scale: float, frames: int = 1) -> np.ndarray:
    """(F,J,3) global joint positions in metres from SmartBody's row-vector matrix chain."""
    joints = raw_sk(sk_text)
    index = {j["name"]: k for k, j in enumerate(joints)}
    pos = np.zeros((frames, len(joints), 3))
    rotvec = np.zeros((frames, len(joints), 3))
    euler = np.broadcast_to([j["rot"] for j in joints], (frames, len(joints), 3)).copy()
    if skm_text is not None:
        channels, values = raw_skm(skm_text)
        col = 0
        for name, kind in channels:
            j = joints[index[name]]
            if kind == "Quat":
                if j["quat"]:
                    rotvec[:, index[name]] = values[:, col:col + 3]
                col += 3
                continue
            d = "XYZ".index(kind[0])
            v = values[:, col]
            if kind.endswith("Pos"):  # a dof without a free channel clamps to its limits (frozen at 0)
                pos[:, index[name], d] = v if j["free"][d] else np.clip(v, *j["lim"][d])
            elif j["euler"]:
                r = np.radians(v)
                euler[:, index[name], d] = r if j["rfree"][d] else np.clip(r, *j["rlim"][d])
            col += 1
    gmats = np.zeros((frames, len(joints), 4, 4))
    for k, j in enumerate(joints):
        value = rodrigues(rotvec[:, k]) if j["euler"] is None else euler_matrix(j["euler"], euler[:, k])
        local = j["pre"] @ value @ j["post"]
        lmat = np.zeros((frames, 4, 4))
        lmat[:, :3, :3] = np.swapaxes(local, -1, -2)
        lmat[:, 3, :3] = j["offset"] + pos[:, k]
        lmat[:, 3, 3] = 1.0
        gmats[:, k] = lmat if j["parent"] < 0 else lmat @ gmats[:, j["parent"]]
    return gmats[:, :, 3, :3] * scale


# -- tests ------------------------------------------------------------------------------------
@pytest.fixture(scope="module", params=sorted(WALKS))
def walk(request):
    skm_rel, sk_rel, scale, head, feet = WALKS[request.param]
    asset = infuse.load(corpus_file(skm_rel))
    motion = next(iter(asset.motions.values()))
    _, positions = motion_fk(motion)
    return dict(asset=asset, motion=motion, positions=positions, head=head, feet=feet, scale=scale,
                skm_text=corpus_file(skm_rel).read_text(), sk_text=corpus_file(sk_rel).read_text())


def test_walk_fk_matches_matrix_chain(walk):
    motion = walk["motion"]
    expected = chain_positions(walk["sk_text"], walk["skm_text"], walk["scale"], motion.num_frames)
    names = [j["name"] for j in raw_sk(walk["sk_text"])]
    assert list(motion.skeleton.names) == names
    err = np.abs(walk["positions"] - expected).max()
    assert err < 1e-6, f"largest FK difference {err} m"


def test_walk_is_upright_human_sized_and_grounded(walk):
    names = walk["motion"].skeleton.names
    pos = walk["positions"]
    head = pos[:, names.index(walk["head"]), 1]
    feet = pos[:, [names.index(n) for n in walk["feet"]], 1]
    assert np.all(head > feet.max(axis=1) + 1.0), "head well above the feet in every frame"
    assert 1.4 < walk["motion"].skeleton.height() < 2.1
    lowest = feet.min(axis=1)
    assert np.all(np.abs(lowest) < 0.1), f"a foot near the ground in every frame, lowest {lowest.min()}..{lowest.max()}"
    travel = pos[-1, names.index(walk["head"])] - pos[0, names.index(walk["head"])]
    assert travel[2] > 1.0 and abs(travel[0]) < 0.2, "a straight walk goes forward, along +Z"


def test_walk_keeps_timing_metadata(walk):
    written = dict(re.findall(r"^(\w+) time: (\S+)$", walk["skm_text"], re.M))
    assert written, "the corpus walks carry ready/stroke/relax times"
    assert walk["motion"].sync_points == pytest.approx({k: float(v) for k, v in written.items()})


@pytest.mark.parametrize("rel", SKELETONS, ids=lambda r: Path(r).name)
def test_rest_pose_matches_matrix_chain(rel):
    path = corpus_file(rel)
    asset = infuse.load(path)
    scale = 1.0 if asset.units_detected_by == "file" else 0.01
    assert asset.source_units == ("m" if scale == 1.0 else "cm")
    expected = chain_positions(path.read_text(), None, scale)[0]
    sk = asset.skeleton
    assert np.abs(sk.rest_global_positions - expected).max() < 1e-6
    assert 1.4 < sk.height() < 2.1


SYNTHETIC_SK = """# hand-written test skeleton, Units: cm
set_name synthetic
skeleton
root hips
{ offset 0 100 0
  channel XPos 0 free
  channel YPos 0 free
  channel ZPos 0 free
  channel Quat
  joint arm
  { offset 10 0 0
    euler XYZ
    channel XRot 0 lim -45 45
    channel YRot 10 free
    channel ZRot 0 free
    prerot axis 0 0 1 ang 90
    postrot axis 1 0 0 ang 30
    joint hand
    { offset 0 20 0
      euler ZY
      channel YRot 0 free
      channel ZRot 0 free
      channel XPos 0 lim -1 1
    }
  }
  joint leg
  { offset 0 -50 0
    channel Quat axis 1 0 0 ang 45 frozen
  }
}
end
"""


def _synthetic_skm(rows: np.ndarray) -> str:
    channels = ["hips XPos", "hips YPos", "hips ZPos", "hips Quat", "arm XRot", "arm YRot", "arm ZRot",
                "hand XRot", "hand YRot", "hand ZRot", "hand XPos", "leg Quat"]
    frames = "\n".join(f"kt {k / 30:.6f} fr " + " ".join(f"{v:.6f}" for v in row) for k, row in enumerate(rows))
    return (f"# SKM Motion Definition\n# test   Units: cm\n\nSkMotion\n\nname \"synthetic\"\n\nchannels {len(channels)}\n"
            + "\n".join(channels) + f"\n\nframes {len(rows)}\n{frames}\n\nready time: 0.1\nstroke time: 0.2\nrelax time: 0.3\n")


def test_euler_limits_pre_and_post_rotations(tmp_path):
    rng = np.random.default_rng(7)
    rows = np.concatenate([rng.normal(0, 5, (6, 3)), rng.normal(0, 1.5, (6, 3)), rng.uniform(-80, 80, (6, 6)),
                           rng.normal(0, 3, (6, 1)), rng.normal(0, 1, (6, 3))], axis=1)
    folder = tmp_path / "set"
    (folder / "skeletons").mkdir(parents=True)
    (folder / "motions").mkdir()
    (folder / "skeletons" / "synthetic.sk").write_text(SYNTHETIC_SK)
    skm = folder / "motions" / "synthetic.skm"
    skm.write_text(_synthetic_skm(rows))
    asset = infuse.load(skm)
    motion = asset.motions["synthetic"]
    _, positions = motion_fk(motion)
    # The matrix chain reads the numbers as written (6 decimals), like the reader.
    expected = chain_positions(SYNTHETIC_SK, skm.read_text(), 0.01, len(rows))
    assert np.abs(positions - expected).max() < 1e-6
    # Limits: the arm's XRot is clamped to 45 deg, the hand's X position to 1 cm; with Euler ZY the
    # hand's X rotation is frozen; the leg's Quat channel is frozen, so its values are ignored.
    assert {"arm XRot", "hand XPos", "hand XRot"} <= set(asset.meta["limited_channels"])
    assert asset.meta["ignored_channels"] == ["leg Quat"]
    assert motion.sync_points == {"ready": 0.1, "stroke": 0.2, "relax": 0.3}


def test_rotation_kind_change_drops_earlier_prerot(tmp_path):
    """SmartBody starts a new rotation object when a joint turns Euler after its prerot."""
    sk = tmp_path / "quirk.sk"
    sk.write_text("skeleton\nroot a\n{ offset 0 0 0\n  joint b\n  { offset 0 1 0\n    prerot axis 0 0 1 ang 90\n"
                  "    channel XRot 0 free\n    joint c\n    { offset 0 1 0\n    }\n  }\n}\nend\n")
    asset = infuse.load(sk, units="m")
    np.testing.assert_allclose(asset.skeleton.rest_global_positions[2], [0.0, 2.0, 0.0], atol=1e-12)
    assert asset.units_detected_by == "override"
