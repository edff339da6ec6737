"""The layered controller runtime: controllers acting on characters through their canonical mapping.

See :mod:`infuse.runtime.runtime` for the API (``Runtime``, ``activate``, ``run``, ``motion``),
:mod:`infuse.runtime.controller` for what a controller plugin implements, and
:mod:`infuse.runtime.swing` for the aligned frames controllers express rotations in.
Controller plugins register :class:`~infuse.plugin_types.ControllerFactory` objects through the
``infuse_controllers`` hook (entry-point group ``infuse.controllers``); :func:`controller` builds one by name.
"""
from __future__ import annotations

from .clip import Clip, sample_motion
from .controller import Block, Controller, Job
from .layers import Layer, Mode, blend_weights, smoothstep
from .pose import PoseBlock
from .rig import Rig, body_frame, reference_pose
from .runtime import Activity, Runtime
from .targets import FunctionTarget, JointTarget, PointTarget, Target, TrackTarget, as_target
from .tracks import Tracks


def controller_components() -> dict:
    """Installed controllers: kind -> :class:`~infuse.plugin_types.ControllerFactory`."""
    from .. import registry

    return registry.table("controller")


def controller(kind: str, **settings) -> Controller:
    """Build the installed controller ``kind`` (``"clip"``, ``"head"``...) with ``settings``."""
    from ..errors import UsageError

    table = controller_components()
    if kind not in table:
        raise UsageError(f"no controller named {kind!r}; installed: {', '.join(sorted(table)) or 'none'}")
    return table[kind].factory(**settings)


__all__ = [
    "Clip", "sample_motion", "Block", "Controller", "Job", "Layer", "Mode", "blend_weights", "smoothstep", "PoseBlock",
    "Rig", "body_frame", "reference_pose", "Activity", "Runtime", "FunctionTarget", "JointTarget", "PointTarget", "Target", "TrackTarget",
    "as_target", "Tracks", "controller_components", "controller",
]
