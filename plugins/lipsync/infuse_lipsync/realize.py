"""BML ``<speech>`` and face behaviours realized in a scene, through its :class:`~infuse.stage.Stage`.

The scene synthesizes an utterance once, times the block with it and keeps its audio; the lip sync
plays that very utterance on the character's mouth channels (its map file's face entry, if any).
"""
from __future__ import annotations

from infuse.bml.model import CANNOT_CREATE_BEHAVIOR
from infuse.errors import InfuseError
from infuse.stage import end_s, until_s

from .controllers import Speech, face_from_bml


def realize_speech(activation, stage):
    """Lip sync of the utterance the scene synthesized for ``activation``, until the speech ends or is
    interrupted; None (warned) when there is none."""
    utterance = stage.utterance(activation)
    if utterance is None:
        stage.warn(activation, CANNOT_CREATE_BEHAVIOR, f"<{activation.element}>: no synthesized utterance to lip-sync")
        return None
    return stage.activate(activation, _speech(utterance, activation, stage), until_s(activation))


def prepare_speech(activation, stage) -> None:
    """Work out the lip sync of the activation's utterance on its character ahead (the costly part of
    realizing it), on the caller's thread; :func:`realize_speech` binds it from there when it realizes
    the very same utterance on the same face (:meth:`Speech.prepare`). Reads the stage only."""
    utterance = stage.utterance(activation)
    if utterance is not None:
        _speech(utterance, activation, stage).prepare(stage.runtime.rig(activation.character))


def _speech(utterance, activation, stage) -> Speech:
    return Speech(utterance, fps=stage.fps, map_file=stage.map_file(activation.character))


def realize_face(activation, stage):
    """A facial lexeme or action unit on the character's face channels, in from start to attackPeak and
    out from relax to end; None (warned) when it names nothing the face can show."""
    try:
        face = face_from_bml(activation.parameters, stage.runtime, activation.character, activation,
                             map_file=stage.map_file(activation.character))
    except (InfuseError, ValueError, KeyError) as exc:
        stage.warn(activation, CANNOT_CREATE_BEHAVIOR, f"<{activation.element}> cannot be shown: {exc}")
        return None
    if activation.parameters.get("shift"):  # a face shift lasts until the next, which blends it out as it comes in
        for activity in stage.activities(activation.character):
            source = getattr(activity.source, "parameters", None) or {}
            if source.get("shift") and activity.start_s < activation.start \
                    and (activity.end_s is None or activity.end_s > activation.start):
                stage.runtime.stop(activity, activation.start, blend_out_s=face.blend_in_s)
    return stage.activate(activation, face, end_s(activation))
