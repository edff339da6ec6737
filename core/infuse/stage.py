"""The realization seam: what a scene hands the controller plugin that realizes one of its BML behaviours.

A scheduled BML behaviour (an :class:`~infuse.bml.Activation`) names a behaviour kind
(``activation.controller``). The registry picks the installed controller that realizes that kind
(:func:`infuse.registry.realizer`); when its :class:`~infuse.plugin_types.ControllerFactory` has a
``realize(activation, stage)``, the scene calls it with a :class:`Stage`, and the plugin builds its
controllers, asks where things are, starts activities and reports what it cannot show. Without one,
the scene plays the controller the factory's ``from_bml`` builds from the activation's start to its end
(:meth:`Stage.play`).

What each hand of each character holds is the stage's to keep (:class:`Held`), so one plugin's grab can
be put down by another's reach: the plugin that takes an object records it with :meth:`Stage.hold`,
saying how its hand lets go; whichever lets go of it calls :meth:`Stage.let_go`.

A plugin that needs to follow its behaviours across a whole scene (walks that go on from one another,
an object a hand holds) keeps a :class:`Stagehand`: one object per scene, made on first use by
:meth:`Stage.stagehand` and owned by the scene, which calls it before each evaluated block.

Times are global seconds; positions metres in the scene's frame (+Y up). The warningFeedback types
(``CANNOT_CREATE_BEHAVIOR``, ``NO_SUCH_TARGET``, ``BEHAVIOR_DEGRADED``...) are in :mod:`infuse.bml.model`.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable, Protocol, TypeVar

if TYPE_CHECKING:
    from .bml import Activation
    from .motion import Motion
    from .packs.infusion import BlendSpace
    from .runtime import Activity, Controller, Runtime
    from .speech import Utterance

__all__ = ["Held", "Stage", "Stagehand", "end_s", "until_s"]

T = TypeVar("T")


@dataclass(frozen=True)
class Held:
    """An object in a hand of a character: ``obj`` (its name as the scene spells it) in the ``hand``
    ("left" or "right") of ``character`` from ``since_s`` (global seconds: when the hand closes on it).
    ``let_go(at_s)`` opens that hand at ``at_s`` the way the plugin that took it knows (its fingers, the
    object's track: it stays where the hand leaves it, unless whoever lets go puts it somewhere)."""

    character: str
    hand: str
    obj: str
    since_s: float
    let_go: Callable[[float], None]


class Stagehand(Protocol):
    """A plugin's helper for one scene (see the module doc). Each method is optional; the scene calls
    those it has."""

    def before_block(self) -> None:
        """Called before each block of frames is evaluated, at the scene's current frame."""

    def frames_ahead(self, most: int) -> int:
        """How many frames (1..``most``) the next block may hold: fewer when something must happen at a
        frame within it."""

    def end_s(self) -> float:
        """When what it follows has ended (seconds); the scene runs at least until then."""


class Stage(Protocol):
    """What a scene offers the controller plugin realizing one of its activations.

    Names: characters, scene objects and named targets (moving points, ``"character:joint"``); BML
    spells them without regard to case, :meth:`resolve` gives the scene's spelling.
    """

    #: Frames per second of the scene.
    fps: float
    #: The layered runtime the scene evaluates (:class:`~infuse.runtime.Runtime`): rigs, targets, activities.
    runtime: Runtime

    @property
    def time(self) -> float:
        """Seconds evaluated so far: the time of the next frame."""

    def resolve(self, name: str) -> str:
        """``name`` as the scene spells it (unknown names come back as they are)."""

    def locate(self, name: str) -> tuple[float, float, float] | None:
        """(x, y, z) metres of an object, or where a character stands (where its last walk takes it);
        None for an unknown name."""

    def what(self, name: str) -> str | None:
        """What ``name`` (as the scene spells it) is: ``"character"``, ``"object"`` (a thing that can be
        carried), ``"target"`` (a named point or joint) or None."""

    def blend_space(self, character: str, kind: str) -> BlendSpace | None:
        """The :class:`~infuse.packs.BlendSpace` of ``kind`` the character was infused with (the first of
        its behaviour packs that has one), or None."""

    def clip(self, character: str, name: str) -> Motion | None:
        """The character's clip ``name`` (:class:`~infuse.Motion`, from its behaviour packs, else its own
        file; case ignored), or None."""

    def map_file(self, character: str) -> Path | None:
        """The character's map file (joint and face channels), or None."""

    def utterance(self, activation: Activation) -> Utterance | None:
        """The :class:`~infuse.speech.Utterance` the scene synthesized for a speech activation (the one its
        timing came from), or None."""

    def activate(self, activation: Activation, controller: Controller, end_s: float | None,
                 **options: Any) -> Activity:
        """Start ``controller`` on the activation's character at its start until ``end_s`` (None: until
        stopped); ``options`` as :meth:`~infuse.runtime.Runtime.activate`. Returns the activity."""

    def play(self, activation: Activation) -> Activity | None:
        """Realize the activation the generic way: the controller its kind's ``from_bml`` (else its
        factory, given the parameters) builds, from its start to :func:`end_s`; a controller that is an
        idle default stops the character's idle one. Returns the activity, or None (reported)."""

    def play_clip(self, activation: Activation) -> Activity | None:
        """Realize the activation as a clip of the character (``clip`` parameter) on the base layer, as
        the scene plays ``<animation>``; returns the activity or None (warned)."""

    def activities(self, character: str) -> list[Activity]:
        """The activities BML started on the character so far (oldest first)."""

    def warn(self, activation: Activation, kind: str, message: str) -> None:
        """warningFeedback of type ``kind`` (see :mod:`infuse.bml.model`)
        about the activation."""

    def stop_idle(self, character: str, kind: str, at_s: float) -> None:
        """Stop the character's idle default of controller ``kind`` at ``at_s`` (BML sets its own)."""

    def note_object_move(self, name: str, at_s: float) -> None:
        """Object ``name`` is picked up or put down at ``at_s`` (its runtime target changed then)."""

    def held(self, character: str) -> tuple[Held, ...]:
        """What the character's hands hold once the behaviours realized so far have played, the latest
        taken last."""

    def hold(self, held: Held) -> None:
        """Record that a hand takes an object (a grab, a pick-up), as :meth:`held` answers from now on."""

    def let_go(self, character: str, at_s: float, obj: str | None = None, hand: str | None = None) -> Held | None:
        """The character lets go at ``at_s`` (global seconds) of ``obj`` (None: what it took last; ``hand``:
        only what that hand holds): the record goes and its :attr:`Held.let_go` is called. Returns it, or
        None when the character holds no such thing."""

    def set_destination(self, character: str, x_m: float, z_m: float) -> None:
        """Where the character will stand once its walk ends: :meth:`locate` answers it from now on."""

    def stagehand(self, key: str, make: Callable[[Stage], T]) -> T:
        """The plugin's :class:`Stagehand` ``key`` for this scene, made with ``make(stage)`` on first use."""


def end_s(activation: Activation) -> float | None:
    """When an activity playing ``activation`` ends: its end (None when persistent), cut at its
    interruption (``stop_s``)."""
    end = None if activation.persistent else activation.end
    if activation.stop_s is not None:
        end = activation.stop_s if end is None else min(end, activation.stop_s)
    return end


def until_s(activation: Activation) -> float:
    """When a behaviour that does not persist stops: its end, or its interruption."""
    end = end_s(activation)
    return activation.end if end is None else end
