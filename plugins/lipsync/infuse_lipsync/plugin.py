"""Registers ``infuse speak`` (entry point group ``infuse.commands``) and the ``speech`` and ``face``
runtime controllers (group ``infuse.controllers``)."""
from __future__ import annotations

from infuse import hookimpl
from infuse.plugin_types import Command, ControllerFactory

from . import command
from .controllers import FaceExpression, Speech, face_from_bml, speech_from_bml


@hookimpl
def infuse_commands():
    return [Command("speak", "say a text with a character: writes the lip-sync animation, the WAV and the phoneme/viseme "
                             "timeline", command.add_arguments, command.run)]


def _realize_speech(activation, stage):
    from .realize import realize_speech

    return realize_speech(activation, stage)


def _prepare_speech(activation, stage):
    from .realize import prepare_speech

    prepare_speech(activation, stage)


def _realize_face(activation, stage):
    from .realize import realize_face

    return realize_face(activation, stage)


@hookimpl
def infuse_controllers():
    return [ControllerFactory("speech", Speech, "lip sync of an utterance on the character's mouth (morphs, face poses or jaw)",
                              from_bml=speech_from_bml, realize=_realize_speech, prepare=_prepare_speech),
            ControllerFactory("face", FaceExpression, "a facial lexeme or FACS action unit held on the character's face",
                              from_bml=face_from_bml, realize=_realize_face)]
