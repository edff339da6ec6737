"""What a walk needs of a locomotion pack on one character: a :class:`LocomotionBinding`, made by the
controller's ``bind`` and shared, read only, by every walk of characters made of one asset.

N is the pack's locomotion clips, J the skeleton's joints, B the joints outside the legs; a leg is
(hip, knee, ankle, ball) joint indices, the ball None where the foot has no ball joint; feet and legs
are ordered left, right. Positions are metres, in the facing frame of the clips (+Y up, +Z forward).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property
from typing import TYPE_CHECKING, Any

import numpy as np

from infuse.runtime.clip import LoopTable
from infuse.skeleton import Skeleton

if TYPE_CHECKING:
    from infuse.packs import BlendClip, BlendSpace

Leg = tuple[int, int, int, int | None]


def _no_joints() -> np.ndarray:
    return np.zeros(0, dtype=np.int64)


@dataclass(frozen=True, eq=False)
class FootFloors:
    """How low each foot may go (:func:`~.controller._keep_feet_up`), from the pose the feet stand in.

    - ``ankles``, ``balls`` (2,): joints (a foot without a ball joint: its ankle as its ball);
      ``ankle_parents``, ``ball_parents`` (2,) the joints they hang from; ``joints`` (8,) the four of
      each foot (ankle's parent, ankle, ball's parent, ball), for one FK;
    - ``point`` (2, 3): the tip of a foot without a ball joint, offset in its ankle's frame; ``kept``
      (2,) bool: the feet that have one;
    - ``tip`` (2, 3): the toes' tip, offset in the ball's frame; ``toes`` (2,) bool: the feet that have one;
    - ``point_floor``, ``tip_floor`` (2,): the heights (m) the two tips stand at;
    - ``across`` (2, 3): the horizontal axis across each foot as it stands (its ankle-to-tip direction
      x +Y), a unit vector in its ankle's frame: the axis the foot and toes turn about, carried by the
      ankle (the ankle-to-tip direction of a foot pitched over its ball points down or back);
    - ``release``: how fast (rad/s) toes bent up to keep their tip off the ground unbend at most: as
      fast as the pack's toes turn against their feet;
    - ``heels`` (H, 2): (foot, joint) children of a ball joint that carry joints lying behind the ball
      (a heel joint hanging from the toes), kept turned with the foot, not the toes, by ``heel_turns``
      (H, 4): each one's global rotation against its ankle's at rest.
    """

    ankles: np.ndarray
    balls: np.ndarray
    ankle_parents: np.ndarray
    ball_parents: np.ndarray
    joints: np.ndarray
    point: np.ndarray
    kept: np.ndarray
    tip: np.ndarray
    toes: np.ndarray
    point_floor: np.ndarray
    tip_floor: np.ndarray
    across: np.ndarray
    release: float
    heels: np.ndarray
    heel_turns: np.ndarray


@dataclass(frozen=True, eq=False)
class LocomotionBinding:
    """A locomotion pack prepared for one skeleton (see the module doc for N, J, B and legs).

    The pack: ``space`` (its :class:`~infuse.packs.BlendSpace`), ``clips`` (N) its locomotion clips,
    ``limit`` its speed limit (called with a travel direction, radians: the top speed, m/s; its ``hull``
    gives the turn rates the pack holds), ``table`` the canonical clips'
    :class:`~infuse.runtime.clip.LoopTable`, ``movers`` (N) the joint each clip travels on.
    Per clip (N, ...): ``velocities`` (N, 3) forward and lateral speed (m/s) and turn rate (rad/s),
    ``durations`` (N,) cycle seconds, ``keys`` (N, 3) its phase keys (s), ``events`` (N, 2, 4) each
    foot's contact events (phases), ``stepping`` (N,) whether it has them, ``idle`` (N,) bool,
    ``slowest`` (N,) one at the slowest straight walk, ``body_means`` (N, B * 4) the sign-aligned mean
    rotations of the joints outside the legs, ``ankle_means`` (N, 2, 3) each ankle's mean offset from the
    hips' midpoint, ``ankle_low`` (N, 2) its lowest height (m).
    The transitions played whole (:mod:`.transitions`): ``played``, ``stops`` among them, and each one's
    ``played_facing`` (F,) radians, ``played_phases`` (F, 2, 2) heel and ball contacts and
    ``played_motions`` (its motion, swivelling feet lifted: :mod:`.swivels`), by name.
    The skeleton: ``skeleton``, ``pelvis``, ``legs`` (0 or 2), ``limbs`` (J,) 0 body, 1 left leg, 2
    right leg, ``body`` (B,) the joints outside the legs, ``grounded_m`` how near the ground a foot
    counts as on it (m), ``stance_feet`` (2, 2, 4) or None each foot's ankle and ball global rotations
    standing, ``heel_levers`` (2, 3) or None (feet with a ball) each foot's sole under the heel (the
    point below the ankle at the ball's height) as the foot lies flat in the clips, in the foot's frame
    (:func:`infuse.contacts.foot_frames`: forward, side, up): where a planted heel is pinned, and how
    high a pose has lifted it, ``floors`` or None (:class:`FootFloors`).
    With two legs: ``leg_limbs`` (hip, knee, ankle) each, ``balls`` (2,) (the ankle without a ball
    joint), ``has_ball`` (2,) bool, ``balls_on_ankles`` the feet whose ball hangs from the ankle, and the
    joints one FK gives the stride and the pinning (``pin_joints``: hip, knee, ankle, the hip's parent
    and the ball of each leg).
    The straight walk's cadence (cycles per second) ``walk_cadences`` (S,) at speeds ``walk_speeds``
    (S,) m/s, from standing to the top speed (:func:`~.controller.straight_walk`), for pacing its stops.
    Touching down (:func:`~.controller._touch_downs`): ``sole_floor`` (2,) the height (m) each foot's sole
    rests at in the clips (its ball's, planted), ``touch_m`` how near it a swinging foot coming down
    counts as landed (m) if slower than ``landing_m_s`` (m/s).
    Without an idle, ``stand_height`` the pelvis's height (m) a walk comes to rest at: the legs as
    straight as the slowest walk's straightest stance leg (:func:`~.controller._stand_height`; 0 with an idle).
    """

    space: BlendSpace
    clips: list[BlendClip]
    limit: Any  # infuse.packs.coverage.SpeedLimit, which the public API does not name
    table: LoopTable
    movers: list[int]
    velocities: np.ndarray
    durations: np.ndarray
    keys: np.ndarray
    events: np.ndarray
    stepping: np.ndarray
    idle: np.ndarray
    slowest: np.ndarray
    body_means: np.ndarray
    ankle_means: np.ndarray
    ankle_low: np.ndarray
    played: list[BlendClip]
    stops: list[BlendClip]
    played_facing: dict[str, np.ndarray]
    played_phases: dict[str, np.ndarray]
    played_motions: dict[str, Any]
    skeleton: Skeleton
    pelvis: int
    legs: list[Leg]
    limbs: np.ndarray
    body: np.ndarray
    grounded_m: float
    stance_feet: np.ndarray | None
    floors: FootFloors | None
    leg_limbs: list[tuple[int, int, int]] = field(default_factory=list)
    balls: np.ndarray = field(default_factory=_no_joints)
    has_ball: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=bool))
    balls_on_ankles: np.ndarray = field(default_factory=_no_joints)
    pin_joints: list[int] = field(default_factory=list)
    walk_speeds: np.ndarray = field(default_factory=lambda: np.zeros(0))
    walk_cadences: np.ndarray = field(default_factory=lambda: np.zeros(0))
    heel_levers: np.ndarray | None = None
    sole_floor: np.ndarray = field(default_factory=lambda: np.zeros(2))
    touch_m: float = 0.0
    landing_rad_s: float = math.inf
    stand_height: float = 0.0

    @cached_property
    def has_idle(self) -> bool:
        """Whether an idle is among the clips (``idle.any()``, asked every block)."""
        return bool(self.idle.any())

    @cached_property
    def body_columns(self) -> slice | np.ndarray:
        """``body`` as a slice where its joints run in one stretch (a slice of the pose costs less than a
        gather), else as it is."""
        body = self.body
        if body.size and np.array_equal(body, np.arange(body[0], body[0] + body.size)):
            return slice(int(body[0]), int(body[0]) + body.size)
        return body

    @cached_property
    def stop_marks(self) -> dict:
        """Each stop clip's phase at its start and its travel (:func:`~.controller._stop_marks`), by the
        clip's name and the frame rate, filled as walks come to stop."""
        return {}

    @cached_property
    def by_weights(self) -> dict:
        """What the walks work out from blend weights alone (:func:`~.controller._kept`: the requests' weights,
        how the blend sums its clips, each walk's order of them, the shorter steps' cycle means), by the work's
        name and its inputs as bytes, filled as they come up."""
        return {}

    @cached_property
    def clip_sets(self) -> dict:
        """What the blend takes of the binding for each set of clips it blends
        (:class:`~.controller.ClipSet`, by the clips' indices as bytes), filled as sets come up."""
        return {}
