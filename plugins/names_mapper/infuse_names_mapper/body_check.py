"""The humanoid test on joints found by their names: two legs and two arms on a trunk, the legs
pointing away from the head in the body's own frame (a rest pose that is not a standing body is
replaced by the first frame of motion). Names alone accept a flying head whose arms carry
humanoid names; this refuses it, with the reason."""
from __future__ import annotations

import numpy as np
from infuse.mapping import resolve_pose

#: cos(legs direction, spine direction) above which a body is not standing (about 140 degrees)
STANDING_COS = -0.75
#: each limb needs its first joint and one of the next two on both sides
LIMBS = {"legs": ("hip", ("knee", "ankle")), "arms": ("shoulder", ("elbow", "wrist"))}
#: joints above the hips that stand for "up", the highest first
UPPER = ("skullbase", "spine5", "spine4", "spine3", "spine2", "spine1")


def refusal(skeleton, joints: dict[str, str], pose=None) -> str | None:
    """Why the canonical -> joint name map ``joints`` of ``skeleton`` is not a humanoid body, or
    ``None``. ``pose``: optional (J, 3) or (F, J, 3) global positions (or a callable returning them)."""
    for kind, (first, nexts) in LIMBS.items():
        sides = [s for s in "lr" if f"{s}_{first}" in joints and any(f"{s}_{n}" in joints for n in nexts)]
        if len(sides) < 2:
            return (f"its names give it {len(sides)} {kind[:-1] if len(sides) == 1 else kind} "
                    f"({first} and {' or '.join(nexts)} joints on both sides wanted): a humanoid has two legs "
                    "and two arms on a trunk")
    index = skeleton.index
    upper = next((joints[n] for n in UPPER if n in joints), None)
    if upper is None:
        upper_names = [joints["l_shoulder"], joints["r_shoulder"]]
    else:
        upper_names = [upper]
    cos = _standing_cos(skeleton.rest_global_positions, index, joints, upper_names)
    if cos > STANDING_COS:
        frames = resolve_pose(pose)
        if frames is not None:
            frames = np.asarray(frames, dtype=np.float64)
            first_frame = frames[0] if frames.ndim == 3 else frames
            if first_frame.shape == (skeleton.num_joints, 3) and np.all(np.isfinite(first_frame)):
                cos = min(cos, _standing_cos(first_frame, index, joints, upper_names))
    if cos > STANDING_COS:
        angle = np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))
        return (f"its legs do not point away from its head (they are {angle:.0f} degrees from the spine's "
                "direction instead of about 180): a four-legged or lying body")
    return None


def _standing_cos(positions: np.ndarray, index: dict, joints: dict[str, str], upper_names: list[str]) -> float:
    """Cosine between the legs' direction (hips to ankles, or knees) and up (hips to ``upper_names``)
    for global positions (J, 3)."""
    def mean(names):
        return positions[[index[n] for n in names]].mean(axis=0)

    hips = mean([joints["l_hip"], joints["r_hip"]])
    end = "ankle" if "l_ankle" in joints and "r_ankle" in joints else "knee"
    if f"l_{end}" not in joints or f"r_{end}" not in joints:
        return -1.0
    down = mean([joints[f"l_{end}"], joints[f"r_{end}"]]) - hips
    up = mean(upper_names) - hips
    norms = float(np.linalg.norm(down) * np.linalg.norm(up))
    return float(down @ up) / norms if norms > 1e-12 else 1.0
