"""Synthetic skeletons and clips for retargeting tests: the canonical T-pose and variants of it
(other local frames, A-pose, turned, scaled, extra or missing joints), and a smooth random clip."""
from __future__ import annotations

import numpy as np

from infuse import Motion, Skeleton
from infuse import quaternions as quat
from infuse.canonical import BODY_NAMES, canonical_skeleton


def from_globals(names, parent_names, rotations, positions) -> Skeleton:
    """A skeleton from global rest rotations (J, 4) and positions (J, 3), joints in any order with
    parents given by name (None for the root); the result is in depth-first order."""
    kids: dict[str | None, list[int]] = {}
    for j, p in enumerate(parent_names):
        kids.setdefault(p, []).append(j)
    order: list[int] = []
    stack = list(reversed(kids.get(None, [])))
    while stack:
        j = stack.pop()
        order.append(j)
        stack.extend(reversed(kids.get(names[j], [])))
    index = {names[j]: k for k, j in enumerate(order)}
    parents = np.array([index[parent_names[j]] if parent_names[j] is not None else -1 for j in order])
    g = np.asarray(rotations, dtype=float)[order]
    p = np.asarray(positions, dtype=float)[order]
    gp = np.where((parents >= 0)[:, None], g[np.maximum(parents, 0)], quat.IDENTITY)
    pp = np.where((parents >= 0)[:, None], p[np.maximum(parents, 0)], 0.0)
    return Skeleton([names[j] for j in order], parents, quat.rotate(quat.conjugate(gp), p - pp),
                    quat.multiply(quat.conjugate(gp), g))


def parts(sk: Skeleton):
    """(names, parent names, global rest rotations, global rest positions) of ``sk``, as lists."""
    names = list(sk.names)
    parents = [sk.names[p] if p >= 0 else None for p in sk.parents]
    return names, parents, list(sk.rest_global_rotations), list(sk.rest_global_positions)


def canonical() -> Skeleton:
    """The 69-joint canonical skeleton in its T-pose."""
    return canonical_skeleton(extras=False)


def identity_map(sk: Skeleton) -> dict[str, str]:
    return {n: n for n in sk.names}


def reframed(sk: Skeleton, seed: int = 1) -> Skeleton:
    """The same rest positions with a random rest rotation on every joint (other local axes)."""
    names, parents, rots, pos = parts(sk)
    rng = np.random.default_rng(seed)
    extra = quat.normalize(rng.normal(size=(len(names), 4)))
    return from_globals(names, parents, quat.multiply(np.array(rots), extra), pos)


def a_pose(sk: Skeleton, degrees: float = 45.0) -> Skeleton:
    """Arms lowered by ``degrees`` at the shoulders (about the forward axis)."""
    names, parents, rots, pos = parts(sk)
    pos = np.array(pos)
    rots = np.array(rots)
    for side, sign in (("l", -1.0), ("r", 1.0)):
        turn = quat.from_axis_angle(np.array([0.0, 0.0, 1.0]), np.radians(degrees) * sign)
        pivot = pos[names.index(f"{side}_shoulder")]
        below = _subtree(names, parents, f"{side}_shoulder")
        pos[below] = pivot + quat.rotate(turn, pos[below] - pivot)
        rots[below] = quat.multiply(turn, rots[below])
    return from_globals(names, parents, rots, pos)


def _subtree(names, parents, root: str) -> list[int]:
    inside = {root}
    changed = True
    while changed:
        changed = False
        for n, p in zip(names, parents):
            if p in inside and n not in inside:
                inside.add(n)
                changed = True
    return [names.index(n) for n in inside]


def inserted(sk: Skeleton, parent: str, child: str, name: str, fraction: float = 0.5) -> Skeleton:
    """A joint ``name`` inserted on the bone from ``parent`` to ``child`` (``child`` hangs from it)."""
    names, parents, rots, pos = parts(sk)
    a, b = names.index(parent), names.index(child)
    names.append(name)
    parents.append(parent)
    rots.append(rots[a])
    pos.append(pos[a] + fraction * (pos[b] - pos[a]))
    parents[b] = name
    return from_globals(names, parents, rots, pos)


def removed(sk: Skeleton, name: str) -> Skeleton:
    """``sk`` without joint ``name``; its children hang from its parent."""
    names, parents, rots, pos = parts(sk)
    k = names.index(name)
    up = parents[k]
    parents = [up if p == name else p for p in parents]
    del names[k], parents[k], rots[k], pos[k]
    return from_globals(names, parents, rots, pos)


def renamed(sk: Skeleton, prefix: str) -> tuple[Skeleton, dict[str, str]]:
    """``sk`` with every joint renamed ``prefix + index``, and the canonical map to the new names."""
    new = [f"{prefix}{j}" for j in range(sk.num_joints)]
    out = Skeleton(new, sk.parents, sk.rest_translations, sk.rest_rotations)
    return out, {n: new[j] for j, n in enumerate(sk.names)}


def smooth_clip(sk: Skeleton, frames: int = 60, fps: float = 30.0, seed: int = 0, amplitude: float = 0.5,
                joints=BODY_NAMES) -> Motion:
    """A smooth random clip: the body joints turn by up to ``amplitude`` radians, the root walks +Z."""
    rng = np.random.default_rng(seed)
    t = np.arange(frames) / fps
    rot = np.broadcast_to(sk.rest_rotations, (frames,) + sk.rest_rotations.shape).copy()
    for n in joints:
        if n not in sk.index:
            continue
        freq = rng.uniform(0.5, 1.5, size=3)
        phase = rng.uniform(0, 2 * np.pi, size=3)
        vec = amplitude * np.sin(2 * np.pi * freq * t[:, None] + phase) * rng.uniform(0.3, 1.0, size=3)
        j = sk.index[n]
        rot[:, j] = quat.multiply(sk.rest_rotations[j], quat.from_rotvec(vec))
    root = sk.rest_translations[0] + np.stack((0.1 * np.sin(t), 0.02 * np.sin(4 * t), 1.2 * t), axis=1)
    return Motion(sk, fps, rot, root, name="smooth")
