"""The :class:`~infuse.stage.Stage` a scene hands the controller plugins that realize its BML, and the
stagehands they keep in it."""
from __future__ import annotations

from dataclasses import replace

from .. import registry
from ..bml.model import BEHAVIOR_TYPE_NOT_SUPPORTED
from ..errors import UsageError
from ..stage import Held


class SceneStage:
    """One scene as its realizing plugins see it (see :class:`infuse.stage.Stage` for each method)."""

    def __init__(self, scene):
        self.scene = scene
        self.runtime = scene.runtime
        self.fps = scene.fps
        self.stagehands: dict[str, object] = {}
        self.holding: dict[str, list[Held]] = {}  # character -> what its hands hold, the latest taken last

    @property
    def time(self) -> float:
        return self.scene.time

    def resolve(self, name: str) -> str:
        return self.scene.resolve_name(name)

    def locate(self, name: str):
        return self.scene.locate(name)

    def what(self, name: str) -> str | None:
        scene = self.scene
        if name in scene.characters:
            return "character"
        if name in scene.objects:
            return "object"
        if name in scene.targets:
            return "target"
        return None

    def blend_space(self, character: str, kind: str):
        return self.scene.pack_space(character, kind)

    def clip(self, character: str, name: str):
        return self.scene.find_clip(character, name)

    def map_file(self, character: str):
        return self.scene.character(character).map_file

    def utterance(self, activation):
        return self.scene.speech.utterance(activation.parameters)

    def activate(self, activation, controller, end_s, **options):
        return self.scene.activate(activation, controller, end_s, **options)

    def play(self, activation):
        return self.play_with(registry.realizer(activation.controller), activation)

    def play_with(self, descriptor, activation):
        """:meth:`play` through ``descriptor``, the realizer of the activation's kind looked up already."""
        if descriptor is None:
            self.warn(activation, BEHAVIOR_TYPE_NOT_SUPPORTED,
                      f"<{activation.element}>: no installed controller realizes {activation.controller!r} behaviours")
            return None
        target = activation.parameters.get("target")
        if isinstance(target, str) and self.resolve(target) != target:  # names match without regard to case
            activation = replace(activation, parameters={**activation.parameters, "target": self.resolve(target)})
        for name, idle in registry.table("controller").items():  # BML sets its own: the idle default stops
            if idle.idle is not None and activation.controller in idle.behaviour_kinds:
                self.stop_idle(activation.character, name, activation.start)
        return self.runtime.realize(activation, activation.character, component=descriptor)

    def play_clip(self, activation):
        from .realize import play_clip

        return play_clip(self.scene, activation)

    def activities(self, character: str) -> list:
        return [a for a in self.scene.activities.values() if a.rig.name == character]

    def warn(self, activation, kind: str, message: str) -> None:
        self.scene.warn(activation, kind, message)

    def stop_idle(self, character: str, kind: str, at_s: float) -> None:
        activity = self.scene.character(character).idle.pop(kind, None)
        if activity is not None:
            self.runtime.stop(activity, at_s)

    def note_object_move(self, name: str, at_s: float) -> None:
        self.scene.note_object_move(name, at_s)

    def held(self, character: str) -> tuple[Held, ...]:
        return tuple(self.holding.get(character, ()))

    def hold(self, held: Held) -> None:
        if held.hand not in ("left", "right"):
            raise UsageError(f"a hand is left or right, got {held.hand!r}")
        self.holding.setdefault(held.character, []).append(held)

    def let_go(self, character: str, at_s: float, obj: str | None = None, hand: str | None = None):
        holding = self.holding.get(character, [])
        for i in range(len(holding) - 1, -1, -1):
            held = holding[i]
            if (obj is None or held.obj.lower() == obj.lower()) and (hand is None or held.hand == hand):
                del holding[i]
                held.let_go(float(at_s))
                return held
        return None

    def set_destination(self, character: str, x_m: float, z_m: float) -> None:
        self.scene.character(character).destination = (float(x_m), float(z_m))

    def stagehand(self, key: str, make):
        if key not in self.stagehands:
            self.stagehands[key] = make(self)
        return self.stagehands[key]

    # -- what the scene asks its stagehands ------------------------------------------------------------
    def before_block(self) -> None:
        """Let every stagehand act before the next block."""
        for hand in list(self.stagehands.values()):
            if hasattr(hand, "before_block"):
                hand.before_block()

    def frames_ahead(self, most: int) -> int:
        """How many frames the next block may hold (1..``most``), as every stagehand allows."""
        n = int(most)
        if self.scene._recorder is not None:  # an object's target is swapped at most once a block
            n = self.scene._recorder.frames_ahead(self.runtime.frame, n)
        for hand in self.stagehands.values():
            if hasattr(hand, "frames_ahead"):
                n = min(n, int(hand.frames_ahead(n)))
        return max(n, 1)

    def end_s(self) -> float:
        """When what every stagehand follows has ended (seconds; 0 without any)."""
        return max([0.0] + [float(hand.end_s()) for hand in self.stagehands.values() if hasattr(hand, "end_s")])
