"""Left and right from the body: names written from the viewer's side put ``l_`` on the
character's right. The character's left is up x forward, with up from the hips to the head and
forward where the toes point and the knees bend (the knees' share counts half); when that says the
opposite of the side names, clearly, the names' sides are swapped.

Positions are global (J, 3), in any units and facing: only directions between joints are used.
"""
from __future__ import annotations

import numpy as np

#: a vote (-1..1) at least this strong against the names swaps them
MIRRORED_VOTE = 0.3
#: the knee's offset from the line between hip and ankle, in thigh lengths, that counts as a full vote
KNEE_BEND = 0.2


def mirrored_vote(positions: np.ndarray, skeleton, joints: dict[str, str], up: np.ndarray) -> float:
    """-1..1: how clearly the body says its left is where the names put ``r_`` (> 0: mirrored
    names), 0 when the feet and knees do not show the front. ``up`` (3,): the body's up. A knee
    the names do not give is the joint between hip and ankle farthest from the line joining them."""
    index = skeleton.index

    def at(name: str) -> np.ndarray | None:
        joint = joints.get(name)
        if joint is None and name[2:] == "knee":
            joint = _between(positions, skeleton, joints.get(name[:2] + "hip"), joints.get(name[:2] + "ankle"))
        return positions[index[joint]] if joint is not None else None

    lateral = [at(f"l_{j}") - at(f"r_{j}") for j in ("hip", "shoulder") if at(f"l_{j}") is not None
               and at(f"r_{j}") is not None]
    if not lateral:
        return 0.0
    left = np.sum([v / max(np.linalg.norm(v), 1e-12) for v in lateral], axis=0)
    forward = np.cross(left, up)  # the front if the names are right
    norm = np.linalg.norm(forward)
    if norm < 1e-9:
        return 0.0
    forward /= norm
    toes, knees = [], []
    for s in "lr":
        ankle, tip = at(f"{s}_ankle"), next((p for p in (at(f"{s}_forefoot"), at(f"{s}_toe")) if p is not None), None)
        if ankle is not None and tip is not None and np.linalg.norm(tip - ankle) > 1e-9:
            toes.append(float((tip - ankle) @ forward) / float(np.linalg.norm(tip - ankle)))
        hip, knee = at(f"{s}_hip"), at(f"{s}_knee")
        if hip is not None and knee is not None and ankle is not None:
            thigh = max(float(np.linalg.norm(knee - hip)), 1e-9)
            off = float((knee - 0.5 * (hip + ankle)) @ forward) / thigh
            knees.append(float(np.clip(off / KNEE_BEND, -1.0, 1.0)))
    toe = float(np.mean(toes)) if toes else 0.0
    knee = float(np.mean(knees)) if knees else 0.0
    vote = toe if abs(toe) >= MIRRORED_VOTE or not knees else float(np.clip(toe + 0.5 * knee, -1.0, 1.0))
    return -vote


def _between(positions: np.ndarray, skeleton, top: str | None, bottom: str | None) -> str | None:
    """The joint on the tree path from ``top`` down to ``bottom`` farthest from the line joining them."""
    if top is None or bottom is None:
        return None
    index, parents = skeleton.index, skeleton.parents
    a, b = positions[index[top]], positions[index[bottom]]
    line = (b - a) / max(float(np.linalg.norm(b - a)), 1e-12)
    best, best_off = None, -1.0
    j = int(parents[index[bottom]])
    while j >= 0 and j != index[top]:
        v = positions[j] - a
        off = float(np.linalg.norm(v - (v @ line) * line))
        if off > best_off:
            best, best_off = skeleton.names[j], off
        j = int(parents[j])
    return best if j == index[top] else None


def swapped(joints: dict[str, str]) -> dict[str, str]:
    """``joints`` with every left and right canonical name exchanged."""
    def other(name: str) -> str:
        if name[:2] in ("l_", "r_"):
            return ("r_" if name[0] == "l" else "l_") + name[2:]
        for a, b in (("_left", "_right"), ("_right", "_left")):
            if name.endswith(a):
                return name[: -len(a)] + b
        return name
    return {other(k): v for k, v in joints.items()}
