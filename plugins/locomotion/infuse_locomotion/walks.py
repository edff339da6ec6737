"""Walks that go on from one another, and characters that stand where a walk left them: the
:class:`Walks` stagehand a scene keeps for the locomotion plugin (:mod:`infuse.stage`).

A locomotion activity starts from the character's own origin unless told otherwise. So when a character
walks again, the new walk takes over the state of the one before (where it is, its heading, speed, gait
phase, planted feet) at the frame it starts, as the controller's ``handover`` gives it. Evaluation stops at that frame for the handover. The old
walk plays on under the new one until the new one has blended in.

A walk that has arrived would go on evaluating the pack's idle on the spot, frame by frame. Instead,
once the character stands still past the walk's scheduled end and the controller says the walk is at
rest (:meth:`~infuse.runtime.Controller.at_rest`), the pack's idle clip takes over, turned
and moved to where the character stands. It is placed from the output pose, not from the controller's
internals, and crossfaded over :data:`SETTLE_BLEND_S`.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from infuse import quaternions as quat
from infuse.bml.model import BEHAVIOR_DEGRADED
from infuse.runtime import Activity, Clip
from infuse.stage import Stage

from .state import LocomotionState
from .steering import SteeringState

#: Crossfade from a walk that has arrived to the idle clip, seconds.
SETTLE_BLEND_S = 0.5
#: The character counts as standing when its root moved less than this (metres) over the last
#: :data:`STILL_S` seconds.
STILL_M, STILL_S = 0.015, 0.5


#: A walk handed over farther than this (metres) from its last point is reported as not arrived.
SHORT_M = 0.15


@dataclass
class Walk:
    """One walk of a character: the activity, when it stands at its last point (seconds, as planned),
    the frame at which to see whether it stands still, the idle that took over, and the steering's
    state planned for its end (in the character's own frame)."""

    activity: Activity
    end_s: float
    check_frame: int
    settled: Activity | None = None
    final: SteeringState | None = None


class Walks:
    """Walk continuity for the characters of one scene (see the module doc).

    Base-layer priorities keep the order: a character's k-th walk plays at ``2k + 2`` and the idle that
    settles it at ``2k + 3``, so each blends over the one before (the pack's first idle plays at 0).
    """

    def __init__(self, stage: Stage):
        self.stage = stage
        self.walks: dict[str, list[Walk]] = {}
        self._handovers: list[tuple[int, Activity, Activity | None]] = []

    def priority(self, name: str) -> int:
        """The base-layer priority of the character's next walk."""
        return 2 * len(self.walks.get(name, ())) + 2

    def expected_state(self, name: str) -> SteeringState | None:
        """Where the character's last walk is planned to leave it (its steering state), or None."""
        walks = self.walks.get(name)
        return walks[-1].final if walks else None

    def end_s(self) -> float:
        """When the last walk of any character stands at its target (seconds; 0 without walks); a walk
        stopped earlier counts until it stopped."""
        ends = [w.end_s if w.activity.end_s is None else min(w.end_s, w.activity.end_s)
                for walks in self.walks.values() for w in walks]
        return max(ends, default=0.0)

    def start(self, name: str, activity, end_s: float, final: SteeringState | None = None,
              arrives_s: float | None = None) -> None:
        """``activity`` (a locomotion, at :meth:`priority`) becomes the character's walk from its start;
        it is planned to arrive at its last point at ``arrives_s`` (default ``end_s``) and to be at rest
        there by ``end_s``, its steering then in state ``final``; the scene looks whether it stands
        from its arrival on."""
        runtime = self.stage.runtime
        walks = self.walks.setdefault(name, [])
        previous = walks[-1] if walks else None
        if previous is not None:  # the old pose shows until the new walk has blended in
            until = activity.start_s + activity.blend_in_s
            runtime.stop(previous.activity, until, blend_out_s=0.0)
            if previous.settled is not None:
                runtime.stop(previous.settled, until, blend_out_s=0.0)
        fps = self.stage.fps
        first_look = end_s if arrives_s is None else arrives_s
        walks.append(Walk(activity, float(end_s), math.ceil(first_look * fps - 1e-9), final=final))
        frame = max(math.ceil(activity.start_s * fps - 1e-9), 0)
        self._handovers.append((frame, activity, previous.activity if previous is not None else None))

    def _waiting(self):
        """(character, walk, the walk after it or None) for walks that may still settle."""
        for name, walks in self.walks.items():
            for k, walk in enumerate(walks):
                after = walks[k + 1] if k + 1 < len(walks) else None
                if walk.settled is None and (after is None or after.activity.start_s > walk.end_s + STILL_S):
                    yield name, walk, after

    def frames_ahead(self, most: int) -> int:
        """How many frames to evaluate next: at most ``most``, stopping at the frame a walk takes over or
        should be seen standing."""
        frame = self.stage.runtime.frame
        ahead = [f - frame for f, _, _ in self._handovers if f > frame]
        ahead += [w.check_frame - frame for _, w, _ in self._waiting() if w.check_frame > frame]
        return max(min([most] + ahead), 1)

    def before_block(self) -> None:
        """Hand over the walks that start now, and settle those that have arrived."""
        frame = self.stage.runtime.frame
        due = [h for h in self._handovers if h[0] <= frame]
        self._handovers = [h for h in self._handovers if h[0] > frame]
        for _, activity, previous in due:
            if previous is not None and previous.state and not activity.state:
                self._report_short(previous)
                activity.state.update(activity.controller.handover(previous.state))
        for name, walk, after in list(self._waiting()):
            now = self.stage.time
            if walk.activity.start_s <= now and frame >= walk.check_frame and \
                    (after is None or after.activity.start_s > now + SETTLE_BLEND_S):
                self._settle(name, walk, after)

    def _report_short(self, activity) -> None:
        """warningFeedback for a walk handed over before it reached its last point."""
        path = getattr(getattr(activity.controller, "steering", None), "path", None)
        if path is None or activity.source is None:
            return
        walked = activity.state_of(LocomotionState)
        short = math.hypot(walked.x - path[-1][0], walked.z - path[-1][1])
        if short > SHORT_M:
            self.stage.warn(activity.source, BEHAVIOR_DEGRADED, f"<{activity.source.element}>: {short:.2f} m short of its "
                                                                f"target when the next walk took over at {self.stage.time:.2f} s")

    def _settle(self, name: str, walk: Walk, after: Walk | None) -> None:
        stage, runtime = self.stage, self.stage.runtime
        idle = stage.clip(name, "idle")
        still = int(round(STILL_S * stage.fps))
        walk.check_frame = runtime.frame + still  # unless it settles now, look again then
        if idle is None or idle.skeleton.names != runtime.rig(name).skeleton.names or runtime.frame <= still:
            return
        if idle.joint_translations is not None and np.ptp(idle.joint_translations, axis=0).max() > 1e-6:
            walk.check_frame = np.iinfo(np.int64).max  # its travel is on another joint than the root: it walks on the spot
            return
        rig = runtime.rig(name)
        rotations, root = runtime.last_frames(name, still)  # in the character's own frame
        if np.linalg.norm(np.ptp(root[:, [0, 2]], axis=0)) > STILL_M:
            return  # still on its way
        if not walk.activity.controller.at_rest(walk.activity.state):
            return  # standing, but its last steps or the fade into its idle still run
        heading_now = _heading(rig, rotations[-1, 0])
        turn = quat.from_axis_angle(np.array([0.0, 1.0, 0.0]), heading_now - _heading(rig, idle.local_rotations[0, 0]))
        start = idle.root_translations[0] * np.array([1.0, 0.0, 1.0])
        here = root[-1] * np.array([1.0, 0.0, 1.0])
        at = stage.time  # the idle turned to the heading and moved to where the walk stands: no copy of it made
        placement = (turn, here - quat.rotate(turn, start))
        walk.settled = runtime.activate(name, Clip(idle, loop=True, placement=placement), at, blend_in_s=SETTLE_BLEND_S,
                                        priority=walk.activity.priority + 1)
        runtime.stop(walk.activity, at + SETTLE_BLEND_S, blend_out_s=0.0)
        if after is not None:  # until the next walk has blended in over it
            runtime.stop(walk.settled, after.activity.start_s + after.activity.blend_in_s, blend_out_s=0.0)


def _heading(rig, root_rotation: np.ndarray) -> float:
    """Radians about +Y of the character's forward when its root joint has local rotation ``root_rotation``."""
    forward_local = quat.rotate(quat.conjugate(rig.reference_rotations[0]), quat.rotate(rig.body, np.array([0.0, 0.0, 1.0])))
    forward = quat.rotate(root_rotation, forward_local)
    return math.atan2(forward[0], forward[2])
