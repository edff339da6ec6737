"""Generate the example-wave behaviour pack: a skeleton, five procedural waving clips, the manifest, the build.

    python examples/example_pack/make_pack.py [OUT_FOLDER]

Writes into ``infuse_example_pack/pack/`` (or ``OUT_FOLDER``): ``skeleton.bvh`` (the canonical skeleton without fingers, in
its T-pose), ``clips/wave_*.bvh``, ``manifest.toml``, and then runs the pack builder (the same as
``infuse pack build``), which stores ``analysis.json`` and ``analysis.npz`` beside the manifest.

Each clip, 2 s at 30 fps: the right arm rises from hanging at the side to a waving pose in 0.6 s
(a smoothstep), holds still for 0.15 s, then the forearm swings side to side (25 degrees, 1.6 Hz)
until the end. The clips differ in where the upper arm points (azimuth from the side toward the
front, elevation above the horizontal), so the hand waves at five places around the body; the pack
builder measures each wrist position at the stroke (when the hand arrives) and tessellates them.
Everything is in the core frame: metres, +Y up, +Z forward, +X the character's left.
"""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

import infuse
from infuse import quaternions as quat
from infuse.canonical import canonical_skeleton, names_in_group
from infuse.packs import build_pack, summary
from infuse.packs.manifest import write_manifest
from infuse.skeleton import Skeleton

PACK = Path(__file__).resolve().parent / "infuse_example_pack" / "pack"
FPS = 30.0
DURATION_S = 2.0
RAISE_S, HOLD_S = 0.6, 0.15
WAVE_DEG, WAVE_HZ = 25.0, 1.6
#: Clip name -> (azimuth from the character's right toward its front, elevation above horizontal), degrees.
POSES = {
    "wave_side_low": (0.0, 20.0),
    "wave_side_high": (10.0, 65.0),
    "wave_front_high": (70.0, 55.0),
    "wave_front_low": (80.0, 10.0),
    "wave_corner_mid": (40.0, 35.0),
}
X, Y, Z = np.eye(3)


def skeleton() -> Skeleton:
    """The canonical skeleton (69 required names) without its 40 finger joints."""
    full = canonical_skeleton(extras=False)
    fingers = set(names_in_group("hand"))
    keep = [i for i, n in enumerate(full.names) if n not in fingers]
    new_index = {old: new for new, old in enumerate(keep)}
    parents = np.array([new_index[full.parents[i]] if full.parents[i] >= 0 else -1 for i in keep])
    return Skeleton(tuple(full.names[i] for i in keep), parents, full.rest_translations[keep], full.rest_rotations[keep])


def smoothstep(x):
    x = np.clip(x, 0.0, 1.0)
    return x * x * (3.0 - 2.0 * x)


def wave_clip(sk: Skeleton, azimuth_deg: float, elevation_deg: float, name: str) -> infuse.Motion:
    """(F, J) local rotations of one wave; every joint but the right arm's stays at rest, the left arm hangs."""
    t = np.arange(int(round(DURATION_S * FPS)) + 1) / FPS
    f = len(t)
    idx = sk.index
    rest_dir = -X  # the right arm's bones point to the character's right in the T-pose
    hang_upper = quat.between(rest_dir, np.array([-0.12, -1.0, 0.0]))
    hang_fore = quat.between(rest_dir, np.array([-0.10, -0.95, 0.25]))
    az, el = np.radians(azimuth_deg), np.radians(elevation_deg)
    upper_dir = np.array([-np.cos(el) * np.cos(az), np.sin(el), np.cos(el) * np.sin(az)])
    fore_dir = np.array([0.0, 1.0, 0.15]) / np.hypot(1.0, 0.15)
    raised = smoothstep(t / RAISE_S)
    g_upper = quat.slerp(np.broadcast_to(hang_upper, (f, 4)), np.broadcast_to(quat.between(rest_dir, upper_dir), (f, 4)), raised)
    g_fore = quat.slerp(np.broadcast_to(hang_fore, (f, 4)), np.broadcast_to(quat.between(rest_dir, fore_dir), (f, 4)), raised)
    waving = t - RAISE_S - HOLD_S
    swing = np.radians(WAVE_DEG) * np.sin(2.0 * np.pi * WAVE_HZ * np.maximum(waving, 0.0)) * smoothstep(waving / 0.2)
    g_fore = quat.multiply(quat.from_axis_angle(np.broadcast_to(Z, (f, 3)), swing), g_fore)
    rotations = quat.identity((f, len(sk.names)))
    rotations[:, idx["r_shoulder"]] = g_upper                                   # its parents stay at rest
    rotations[:, idx["r_elbow"]] = quat.multiply(quat.conjugate(g_upper), g_fore)
    rotations[:, idx["l_shoulder"]] = quat.between(X, np.array([0.12, -1.0, 0.0]))
    rotations[:, idx["l_elbow"]] = quat.multiply(quat.conjugate(rotations[0, idx["l_shoulder"]]),
                                                 quat.between(X, np.array([0.10, -0.95, 0.25])))
    root = np.broadcast_to(sk.rest_translations[idx["base"]], (f, 3)).copy()
    return infuse.Motion(sk, FPS, rotations, root, name=name)


def main(out: Path = PACK) -> None:
    sk = skeleton()
    (out / "clips").mkdir(parents=True, exist_ok=True)
    infuse.save(infuse.Asset(None, "bvh", sk), out / "skeleton.bvh")
    clips = []
    for name, (azimuth, elevation) in POSES.items():
        motion = wave_clip(sk, azimuth, elevation, name)
        infuse.save(infuse.Asset(None, "bvh", sk, {name: motion}), out / "clips" / f"{name}.bvh")
        clips.append({"name": name, "file": f"clips/{name}.bvh", "role": "reach", "tags": ["wave"], "loop": False,
                      "hand": "right"})
    write_manifest(out / "manifest.toml", {
        "name": "example-wave", "version": "0.1.0", "kind": "reach", "skeleton": "skeleton.bvh",
        "analysis": "analysis.json", "description": "example: the right hand waves at five places around the body",
    }, clips)
    print(summary(build_pack(out)))


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else PACK)
