"""Targets of the manipulation controllers, and positions in a character's own frame."""
from __future__ import annotations

import numpy as np

from infuse import quaternions as quat
from infuse.errors import UsageError
from infuse.runtime.targets import JointTarget, Target, as_target


def resolve_target(runtime, target) -> Target:
    """The :class:`~infuse.runtime.targets.Target` of a name (a runtime target, a character, or
    ``"character:joint"``), a point or a target; :class:`UsageError` naming what is unknown."""
    resolved = runtime.target(target) if isinstance(target, str) else as_target(target)
    if isinstance(resolved, JointTarget):
        resolved.resolve(runtime)  # the character and the joint exist
    return resolved


def own_positions(rig, world: np.ndarray) -> np.ndarray:
    """World positions (..., 3) in the character's own frame (its placement undone), metres."""
    return quat.rotate(quat.conjugate(rig.rotation), np.asarray(world, dtype=np.float64) - rig.position)


def world_positions(rig, own: np.ndarray) -> np.ndarray:
    """Positions (..., 3) in the character's own frame placed in the world, metres."""
    return quat.rotate(rig.rotation, np.asarray(own, dtype=np.float64)) + rig.position


def check_point(value, what: str) -> tuple[float, float, float]:
    """A finite (x, y, z) point, or :class:`UsageError` naming ``what``."""
    point = np.asarray(value, dtype=np.float64)
    if point.shape != (3,) or not np.all(np.isfinite(point)):
        raise UsageError(f"{what} must be three finite numbers (metres), got {value!r}")
    x, y, z = (float(v) for v in point)
    return x, y, z
