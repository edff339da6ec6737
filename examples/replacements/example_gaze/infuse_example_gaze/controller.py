"""``head-gaze``: the head turns toward a target, eyes and spine left as the layers below put them.

Each frame, the direction from the head joint (canonical ``skullbase``) to the target, expressed in the
aligned frame of the head's parent joint (see :mod:`infuse.runtime.swing`), gives a heading and a pitch,
clamped to :data:`HEADING_LIMIT_DEG` and :data:`PITCH_LIMITS_DEG`; the head's local rotation is its
reference-pose rotation turned by them. The activity's blend weight eases it in and out.
"""
from __future__ import annotations

import numpy as np

from infuse import quaternions as quat
from infuse.errors import MissingJointsError
from infuse.runtime import Controller, Layer, Mode
from infuse.runtime.swing import direction_angles, swing
from infuse.runtime.targets import as_target

#: Most the head turns left or right of its parent's forward, degrees.
HEADING_LIMIT_DEG = 75.0
#: Most it pitches (down, up), degrees.
PITCH_LIMITS_DEG = (-50.0, 40.0)


class HeadGaze(Controller):
    """Turn the head toward ``target``: a runtime target's name (a scene object, a character's face,
    ``"character:joint"``; looked up every block, so a carried object is followed), a point (x, y, z)
    metres, or any :class:`~infuse.runtime.targets.Target`."""

    kind = "head-gaze"
    layer = Layer.GAZE
    mode = Mode.OVERRIDE
    blend_in_s = 0.4
    blend_out_s = 0.4

    def __init__(self, target):
        self.target = target if isinstance(target, str) else as_target(target)

    def describe(self) -> str:
        return f"head-gaze at {self.target!r}"

    def bind(self, rig, report):
        """The head joint, its parent, and both joints' aligned frames."""
        head = rig.joint("skullbase")
        if head is None:
            raise MissingJointsError(rig.name, "no head (skullbase) is mapped; it cannot turn its head")
        parent = int(rig.skeleton.parents[head])
        if parent < 0:
            raise MissingJointsError(rig.name, "the head is the root joint; it cannot turn it")
        return {"head": head, "parent": parent, "parent_aligned": rig.aligned[parent],
                "head_aligned_inverse": quat.conjugate(rig.aligned[head])}

    def evaluate_one(self, job, block) -> None:
        """Vectorized over the block's frames."""
        b = job.binding
        target = block.runtime.target(self.target) if isinstance(self.target, str) else self.target
        points = target.positions(block.times, block)                                  # (F, 3) metres
        rotations, positions = job.pose.chain_pose([b["parent"], b["head"]])           # (F, 2, 4), (F, 2, 3)
        frame = quat.multiply(rotations[:, 0], b["parent_aligned"])                    # (F, 4) parent's aligned frame
        heading, pitch = direction_angles(quat.rotate(quat.conjugate(frame), points - positions[:, 1]))
        limit = np.radians(HEADING_LIMIT_DEG)
        heading = np.clip(heading, -limit, limit)
        pitch = np.clip(pitch, *np.radians(PITCH_LIMITS_DEG))
        local = quat.multiply(quat.multiply(b["parent_aligned"], swing(heading, pitch)), b["head_aligned_inverse"])
        job.pose.set_rotations([b["head"]], local[:, None], job.weight, job.mode)
