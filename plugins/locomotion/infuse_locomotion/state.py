"""What a walk carries from one block of frames to the next: a :class:`LocomotionState`, the activity's
(``job.state_of(LocomotionState)``), handed on whole to a walk that follows it.

Feet are ordered left, right; positions are metres in the character's own frame (+Y up), angles radians
about +Y (+ turns left), rotations (x, y, z, w) quaternions, times seconds.
"""
from __future__ import annotations

from dataclasses import dataclass, field, fields

import numpy as np

from .steering import SteeringState

#: How a transition clip is placed (:func:`~.transitions.placement`): its turn (radians), its pelvis's
#: first ground point (2,), where that goes (2,), the scale of its ground travel and its easing.
Placement = tuple[float, np.ndarray, np.ndarray, float, float]


def _feet(*shape: int, value: float = 0.0) -> np.ndarray:
    return np.full((2, *shape), value)


def _unturned() -> np.ndarray:
    return np.tile(np.array([0.0, 0.0, 0.0, 1.0]), (2, 1))


def _columns(values) -> dict[str, tuple[slice | int, tuple[float, ...]]]:
    out: dict[str, tuple[slice | int, tuple[float, ...]]] = {}
    at = 0
    for name, rest in values:
        out[name] = (at if len(rest) == 1 else slice(at, at + len(rest)), rest)
        at += len(rest)
    return out


_TURNED = (0.0, 0.0, 0.0, 1.0)
#: The planted feet's values a held stretch carries (:class:`~.controller.HeldFeet`, the first
#: :data:`HELD_COLUMNS` columns) and those it leaves (the corrections a release fades out), side by side
#: in :attr:`LocomotionState.feet` (2, :data:`FOOT_COLUMNS`): by name, the columns and the value at rest.
FOOT_VALUES = _columns((("pins", (0.0,) * 3), ("landed", _TURNED), ("landed_as", _TURNED), ("across", (0.0,) * 3),
                        ("landed_spun", (0.0,)), ("toes_up", (0.0,)), ("foot_heading", (0.0,)), ("held_swivel", (0.0,)),
                        ("offset", (0.0,) * 3), ("ball_offset", (0.0,) * 3), ("rise", (0.0,) * 3), ("foot_turn", _TURNED),
                        ("let_go", (-np.inf,) * 3)))
HELD_COLUMNS = sum(len(rest) for _, rest in list(FOOT_VALUES.values())[:list(FOOT_VALUES).index("held_swivel") + 1])  # pins to held_swivel
FOOT_COLUMNS = sum(len(rest) for _, rest in FOOT_VALUES.values())


def _planted() -> np.ndarray:
    return np.tile(np.concatenate([rest for _, rest in FOOT_VALUES.values()]), (2, 1))


class _FootValues:
    """One of the planted feet's values, (2, ...) columns of :attr:`LocomotionState.feet` (a view; set in place)."""

    def __set_name__(self, owner, name: str) -> None:
        self.columns = FOOT_VALUES[name][0]

    def __get__(self, state: LocomotionState, owner=None) -> np.ndarray:
        view: np.ndarray = state.feet[:, self.columns]
        return view

    def __set__(self, state: LocomotionState, value) -> None:
        state.feet[:, self.columns] = value


@dataclass
class LocomotionState(SteeringState):
    """The steering's state (:class:`~.steering.SteeringState`), and:

    - the gait: ``phase`` in [0, 1) (left strike 0, right strike 0.5); stopping (:func:`~.controller._clock`):
      ``settled`` (standing, its stop steps over), ``landings`` since the stop began (-1: not stopping),
      ``to_go`` phase left to where it holds (-1: not known yet), ``floor`` the cadence factor it began
      at, ``stop_age`` seconds since, ``idle_frames_left`` how many frames the idle's share has still to
      rise to be whole (0: the idle fully in; the fade's length in frames: fully out); ``spun`` the heading's turn
      spun at the root so far; ``laid`` (2,) how far each foot is laid down; ``toe_bend`` (2,) the toes'
      bend up (radians);
    - the transitions played whole (:mod:`.transitions`): ``playing`` and ``fading`` (the clip's name, its
      start in the activity's time, its :data:`Placement`) or None, ``chooser`` the walk that decided
      (its controller's id), ``trace`` the steered stretch's ground points, headings, speeds, phases
      and each frame's advance of the phase (F,) each, where a stop may take over;
    - each planted foot (:meth:`~.controller.Locomotion._pin`): ``anchor`` (2,) what holds it (free, ankle,
      ball); ``feet`` (2, :data:`FOOT_COLUMNS`) its values side by side (:data:`FOOT_VALUES`), each also
      under its name (a view of its columns): ``pins`` (2, 3) where, ``offset`` (2, 3) and ``ball_offset`` (2, 3) the ankle's and ball's
      corrections, ``released`` (2,) seconds since let go, ``free_s`` (2,) seconds in the air, ``let_go``
      (2, 3) where the ball was let go, ``last`` (2, 2, 3) the ankle and ball a frame earlier and ``last_rot``
      (2, 4) the ankle's rotation then, ``rise``
      (2, 3) the heel's extra rise (rotation vector), ``landed`` and ``landed_as`` (2, 4) the foot's
      rotation as it landed, animated and corrected, ``landed_spun`` (2,) the turn spun at the root then,
      ``across`` (2, 3) the axis across it, ``foot_turn`` (2, 4) its correction; held by its heel,
      ``foot_heading`` (2,) its heading a frame earlier (radians about +Y, from +Z) and ``held_swivel``
      (2,) the turn about the vertical held off it while its ball is down, ``toes_up`` (2,) how far its
      toes are up from as it landed (radians, a frame earlier); ``shared`` (2,) held by the
      idle's fading share a frame earlier, ``clear`` (2,) let go by it (its ball held along the ground
      until clear of it); ``touched`` (2,) what holds a
      swinging foot that has touched the ground before its strike (:func:`~.controller._touch_downs`; 0: none);
    - ``blend`` (N,) the moving clips' weights a frame earlier (None: none yet; :func:`~.controller._eased`),
      ``blend_held`` whether the next frame's may move only at the eased rate (they lag the asked ones, or the request
      lies outside the tessellation);
    - ``warned``: a speed the pack cannot realize has been reported.
    """

    phase: float = 0.0
    settled: bool = True
    landings: int = -1
    to_go: float = -1.0
    floor: float = 0.0
    stop_age: float = 0.0
    idle_frames_left: float = 0.0
    spun: float = 0.0
    laid: np.ndarray = field(default_factory=lambda: _feet())
    toe_bend: np.ndarray = field(default_factory=lambda: _feet())
    playing: tuple[str, float, Placement] | None = None
    fading: tuple[str, float, Placement] | None = None
    chooser: int | None = None
    trace: tuple[np.ndarray, ...] | None = None
    anchor: np.ndarray = field(default_factory=lambda: np.zeros(2, np.int64))
    feet: np.ndarray = field(default_factory=_planted)
    released: np.ndarray = field(default_factory=lambda: _feet(value=1e9))
    free_s: np.ndarray = field(default_factory=lambda: _feet(value=1e9))
    last: np.ndarray = field(default_factory=lambda: _feet(2, 3))
    last_rot: np.ndarray = field(default_factory=_unturned)
    touched: np.ndarray = field(default_factory=lambda: np.zeros(2, np.int64))
    shared: np.ndarray = field(default_factory=lambda: np.zeros(2, bool))
    clear: np.ndarray = field(default_factory=lambda: np.zeros(2, bool))
    blend: np.ndarray | None = None
    blend_held: bool = False
    warned: bool = False
    pins = _FootValues()
    landed = _FootValues()
    landed_as = _FootValues()
    across = _FootValues()
    landed_spun = _FootValues()
    toes_up = _FootValues()
    foot_heading = _FootValues()
    held_swivel = _FootValues()
    offset = _FootValues()
    ball_offset = _FootValues()
    rise = _FootValues()
    foot_turn = _FootValues()
    let_go = _FootValues()

    def restore(self, saved: LocomotionState) -> None:
        """Become ``saved`` (a copy taken earlier) again, in place."""
        for f in fields(self):
            setattr(self, f.name, getattr(saved, f.name))
