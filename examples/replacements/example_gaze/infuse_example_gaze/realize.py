"""BML ``<gaze>`` and ``<gazeShift>`` realized in a scene through its :class:`~infuse.stage.Stage`."""
from __future__ import annotations

from infuse.bml.model import CANNOT_CREATE_BEHAVIOR, NO_SUCH_TARGET
from infuse.errors import UsageError
from infuse.runtime.targets import JointTarget
from infuse.stage import end_s

from .controller import HeadGaze


def realize_gaze(activation, stage):
    """Turn the head toward the activation's target (``target_position``, else ``target``: an object, a
    character or ``character:joint``), from its start to its end; a lasting gaze (``gazeShift``) ends
    the character's earlier ones. Returns the activity, or None (warned)."""
    p = activation.parameters
    if p.get("target_position") is not None:
        target = tuple(float(v) for v in p["target_position"])
    elif p.get("target"):
        target = stage.resolve(p["target"])
        try:
            found = stage.runtime.target(target)
            if isinstance(found, JointTarget):
                found.resolve(stage.runtime)
        except UsageError as exc:
            stage.warn(activation, NO_SUCH_TARGET, f"<{activation.element}>: {exc}")
            return None
    else:
        stage.warn(activation, CANNOT_CREATE_BEHAVIOR, f"<{activation.element}>: head-gaze needs a target")
        return None
    if activation.persistent:
        for earlier in stage.activities(activation.character):
            if isinstance(earlier.controller, HeadGaze) and (earlier.end_s is None or earlier.end_s > activation.start):
                stage.runtime.stop(earlier, activation.start)
    return stage.activate(activation, HeadGaze(target), end_s(activation))
