"""BML ``<gaze>``, ``<gazeShift>`` and ``<headDirectionShift>`` activations -> :class:`~infuse_gaze.Gaze`.

The parameters are those the built-in BML behaviour handlers produce: ``target`` (a scene object,
a character, or ``character:joint``), ``target_position`` (x, y, z metres), ``influence``,
``offset_angle_deg``, ``offset_direction``, ``joint_range`` (SmartBody group words), ``priority_joint``,
``joint_speed_deg_s`` and ``smooth``.
"""
from __future__ import annotations

from infuse.errors import UsageError
from infuse.runtime.targets import JointTarget

from .controller import Gaze
from .model import GROUP_NAMES, group_name


def gaze_from_bml(parameters: dict, runtime, character: str, activation=None) -> Gaze:
    """A :class:`Gaze` for one scheduled BML gaze activation of ``character`` in ``runtime``."""
    target = parameters.get("target")
    if parameters.get("target_position") is not None:
        target = tuple(float(v) for v in parameters["target_position"])
    elif target is None:
        target = _straight_ahead(runtime, character)
    else:
        resolved = runtime.target(target)  # raise now if nothing has that name
        if isinstance(resolved, JointTarget):
            resolved.resolve(runtime)  # or the character or joint named
    groups = None
    if parameters.get("joint_range"):
        groups = sorted({group_name(w) for w in parameters["joint_range"]}, key=GROUP_NAMES.index)
    priority = parameters.get("priority_joint") or "eyes"
    try:
        priority = group_name(priority)
    except ValueError:
        priority = "eyes"
    speed = parameters.get("joint_speed_deg_s")
    smooth = parameters.get("smooth")
    return Gaze(target, influence=parameters.get("influence"), priority=priority, groups=groups,
                offset_angle_deg=float(parameters.get("offset_angle_deg") or 0.0),
                offset_direction=parameters.get("offset_direction"),
                speed_deg_s={"head": speed, "cervical": 2 * speed} if speed else None,
                smooth={g: smooth for g in ("lumbar", "thoracic", "cervical", "head")} if smooth is not None else None)


def _straight_ahead(runtime, character: str):
    """A point 2 m in front of the character's face at rest: the target of an offset-only gaze."""
    import numpy as np

    from infuse import quaternions as quat

    rig = runtime.rig(character)
    joints = [j for j in (rig.joint("eyeball_left"), rig.joint("eyeball_right"), rig.joint("skullbase")) if j is not None]
    if not joints:
        raise UsageError(f"{character!r} has no head to look ahead from")
    origin = rig.skeleton.rest_global_positions[joints].mean(axis=0)
    return tuple(origin + 2.0 * quat.rotate(rig.body, np.array([0.0, 0.0, 1.0])))
