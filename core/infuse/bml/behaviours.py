"""The contract between the scheduler and BML behaviour plugins.

A plugin's ``infuse_bml_behaviours`` hook returns :class:`~infuse.plugin_types.BMLBehaviour` objects:
the ``elements`` they handle (names as :mod:`infuse.bml.names` writes them: ``"head"``, ``"sbm:reach"``,
``"{uri}name"``), the ``attributes`` they understand (others are reported as unsupported) and a
``priority`` (a higher one wins an element; default 0). Their ``plan(behaviour, context) -> BehaviourPlan``
turns a parsed behaviour into a timing model and an activation record, or raises :class:`BehaviourError`
when it cannot.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Callable

from .. import registry
from .names import normalize_name
from .speech import EstimatedSpeechTimer, SpeechTimer
from .sync import TimingModel

if TYPE_CHECKING:
    from ..plugin_types import BMLBehaviour


class BehaviourError(ValueError):
    """A behaviour plugin cannot build this behaviour (bad attribute value, missing target...)."""


def _no_clip(name: str):
    return None


def _nowhere(name: str):
    return None


@dataclass(frozen=True)
class BehaviourContext:
    """What a behaviour factory may ask about the world while planning.

    ``clip_timing(name)`` -> ``{sync: seconds from clip start}`` including ``"end"`` (from behaviour packs), or
    None; ``locate(name)`` -> (x, y, z) metres of a scene object or character, or None; ``speech_timer``
    times speech; ``dialect`` is the block's (``"bml1.0"``, ``"smartbody"``, ``"draft"``).
    """

    character: str | None = None
    dialect: str = "bml1.0"
    speech_timer: SpeechTimer = field(default_factory=EstimatedSpeechTimer)
    clip_timing: Callable[[str], dict | None] = _no_clip
    locate: Callable[[str], tuple | None] = _nowhere


@dataclass(frozen=True)
class BehaviourPlan:
    """A behaviour ready to schedule.

    ``timing``: its sync points; ``controller``: which controller kind realizes it (``"head"``, ``"gaze"``,
    ``"speech"``...); ``parameters``: plain data for that controller; ``persistent``: its effect stays after
    its end (posture shifts, SmartBody gaze); ``notes``: warnings about the behaviour that did not stop it;
    ``own_sync_attributes``: sync attributes the plugin interpreted itself (e.g. as durations), which the
    scheduler then does not treat as sync references.
    """

    timing: TimingModel
    controller: str
    parameters: dict = field(default_factory=dict)
    persistent: bool = False
    notes: tuple[str, ...] = ()
    own_sync_attributes: frozenset = frozenset()


@dataclass(frozen=True)
class Handler:
    """One element's handler, resolved from the plugins."""

    element: str
    behaviour: BMLBehaviour

    @property
    def attributes(self):
        names = self.behaviour.attributes
        return None if names is None else frozenset(names)

    def plan(self, behaviour, context: BehaviourContext) -> BehaviourPlan:
        return self.behaviour.plan(behaviour, context)


def handlers_from(behaviours) -> dict[str, Handler]:
    """Element name -> handler from :class:`~infuse.plugin_types.BMLBehaviour` objects; the highest
    ``priority`` wins, then the first."""
    table: dict[str, tuple[int, Handler]] = {}
    for plugin in behaviours:
        for element in plugin.elements:
            name = normalize_name(element)
            if name not in table or plugin.priority > table[name][0]:
                table[name] = (plugin.priority, Handler(name, plugin))
    return {name: handler for name, (_, handler) in table.items()}


def installed_handlers() -> dict[str, Handler]:
    """The handlers of every installed BML behaviour plugin."""
    return handlers_from(registry.table("bml-behaviour").values())
