"""Frames at a take's ends that are not part of its motion (a capture's calibration T-pose), cut away.

A capture often opens with the actor's calibration pose (a T-pose, held) and then cuts to the take;
exports may likewise end on a frame of another pose. Played whole as a start, stop or turn, or found
as a cycle's stride, such frames teleport the body. A **cut** is a frame whose pose jumps from the
one before by more than :data:`CUT_DEG` on some joint (the root's rotation included) and by more than
:data:`CUT_MEDIANS` times the take's median largest change per frame: real takes turn a joint by at
most 56 degrees from one frame to the next at 24-120 fps (SmartBody's tight running circle at 30 fps,
its median 28), a T-pose cut to a walk by 75-180. The frames before the first cut in a take's first
half, and after the last cut in its second half, are dropped.
"""
from __future__ import annotations

import numpy as np

from .. import quaternions as quat
from ..motion import Motion

#: A cut turns some joint by more than this from one frame to the next (degrees)...
CUT_DEG = 60.0
#: ...and by more than this many times the take's median largest turn per frame.
CUT_MEDIANS = 3.0


def kept_frames(rotations: np.ndarray) -> tuple[int, int]:
    """(first, end exclusive) frames of a take's local rotations (F, J, 4) between the cuts at its ends."""
    frames = len(rotations)
    if frames < 3:
        return 0, frames
    step = np.degrees(quat.angle_between(rotations[:-1], rotations[1:])).max(axis=1)  # (F - 1,): frame f to f + 1
    cuts = np.nonzero(step > max(CUT_DEG, CUT_MEDIANS * float(np.median(step))))[0]
    first = [int(c) + 1 for c in cuts if c + 1 <= frames // 2]
    last = [int(c) + 1 for c in cuts if c + 1 > frames // 2]
    return (first[-1] if first else 0), (last[0] if last else frames)


def without_cuts(motion: Motion) -> tuple[Motion, int, int]:
    """``motion`` without the frames beyond the cuts at its ends (see the module doc), and how many frames
    were dropped at its start and at its end (0, 0: ``motion`` itself)."""
    first, end = kept_frames(motion.local_rotations)
    if first == 0 and end == motion.num_frames:
        return motion, 0, 0
    jt = None if motion.joint_translations is None else motion.joint_translations[first:end]
    return (motion.replace(local_rotations=motion.local_rotations[first:end],
                           root_translations=motion.root_translations[first:end], joint_translations=jt),
            first, motion.num_frames - end)
