"""Scenes: characters from any file, objects, and BML (or a small builder API) realized as animation,
speech audio and BML feedback; scene files for ``infuse run``.

See :mod:`infuse.scene.scene` for the API (:class:`Scene`), :mod:`infuse.scene.realize` for how each BML
behaviour is realized, and :mod:`infuse.scene.scenefile` for the scene file format.
"""
from __future__ import annotations

from ..bml.model import BEHAVIOR_DEGRADED
from .scene import Scene, SceneCharacter, SceneObject

__all__ = ["BEHAVIOR_DEGRADED", "Scene", "SceneCharacter", "SceneObject"]
