"""The ``posture`` controller: a standing posture of a postures pack on the whole body, its idle looping.

The posture's clip (retargeted onto the character by infusing it with the pack, once per character
file and mapping) plays on the base layer above walks and idle clips (priority :data:`PRIORITY`),
over the whole body. It is placed where the character stands: the feet stay on the footprints of the
pose below at the frame the posture begins (both ankles, where they are and how they are turned), the
clip turned to that pose's facing and moved so its own feet land there. Through the blend in and out,
and on a character whose stance is wider or narrower than the pack's, two-joint leg IK holds the
ankles on those footprints (the pelvis lowered where a leg could not reach). So a posture follows any
other posture, or the idle below, with the feet planted. Layers above add as usual: breathing,
gestures, gaze, head and face.

A posture started while another plays takes its footprints from the pose that one makes (postures
are evaluated in the order they started); a lasting posture ends the lasting ones before it once it
has blended in; a temporary one blends back out to what plays below it. When the pose below walks
away (the hips more than :data:`WALK_AWAY_M` from where they stood), the posture gives way: it blends
out, letting the feet go with it.
"""
from __future__ import annotations

import numpy as np

from infuse import quaternions as quat
from infuse.errors import MissingJointsError, UsageError
from infuse.kinematics import forward_kinematics
from infuse.runtime import Controller, Layer, Mode, sample_motion, smoothstep
from infuse.runtime.limb_ik import solve_limb

#: Base-layer priority: above walks (which count up from 1) and the scene's idle clip.
PRIORITY = 10_000
#: Default blend into and out of a posture, seconds.
TRANSITION_S = 1.0
#: A standing leg reaches at most this share of its length (the knee never locks).
LEG_REACH = 0.995
#: The hips of the pose below this far (metres, horizontally) from where they stood: the character walks off.
WALK_AWAY_M = 0.15
_INFUSIONS: dict = {}


def posture_space(rig, pack):
    """The :class:`~infuse.packs.BlendSpace` of posture pack ``pack`` on the rig's character (infused once)."""
    from infuse.packs import BlendSpace, infuse_character

    if isinstance(pack, BlendSpace):
        return pack
    # Keyed by the asset and mapping, which scenes share when they add the same Character (kept alive with it).
    key = (id(rig.character.asset), id(rig.mapping), str(pack))
    if key not in _INFUSIONS:
        infusion = infuse_character(rig.character, [pack], mapping=rig.mapping)
        _INFUSIONS[key] = (rig.character.asset, rig.mapping, next(iter(infusion.spaces.values())))
    return _INFUSIONS[key][2]


def facing(left: np.ndarray) -> float:
    """Heading (radians about +Y, + turning the front toward +X) of a body whose left is ``left`` (3,)."""
    return float(np.arctan2(-left[2], left[0]))


def _yaw(angle: float) -> np.ndarray:
    return quat.from_axis_angle(np.array([0.0, 1.0, 0.0]), np.array(angle))


class Posture(Controller):
    """Stand in posture ``clip`` of ``pack`` (its idle looping), blending in and out over ``transition_s``
    seconds, the feet planted where they stand. ``phase_s``: where in its loop the idle starts."""

    kind = "posture"
    layer = Layer.BASE
    mode = Mode.OVERRIDE
    priority = PRIORITY

    def __init__(self, clip: str, pack="postures", transition_s: float = TRANSITION_S, phase_s: float = 0.0):
        if not (np.isfinite(transition_s) and transition_s >= 0) or not np.isfinite(phase_s):
            raise UsageError(f"posture {clip!r}: transition_s must be a number >= 0 and phase_s a number")
        self.clip, self.pack = str(clip), pack
        self.phase_s = float(phase_s)
        self.blend_in_s = self.blend_out_s = float(transition_s)

    def describe(self) -> str:
        return f"posture {self.clip}"

    def bind(self, rig, report):
        space = posture_space(rig, self.pack)
        if self.clip not in space.clips:
            raise UsageError(f"pack {space.pack!r} has no posture {self.clip!r} (its postures: {', '.join(space.clips)})")
        motion = space.clips[self.clip].motion
        names = [f"{s}_{j}" for s in "lr" for j in ("hip", "knee", "ankle")]
        missing = [n for n in names if rig.joint(n) is None]
        if missing:
            raise MissingJointsError(rig.character.asset.path, f"posture {self.clip!r} plants the feet with "
                                                               f"{', '.join(missing)}, which the mapping lacks")
        legs = np.array([[rig.joint(f"{s}_{j}") for j in ("hip", "knee", "ankle")] for s in "lr"], dtype=np.int64)
        jt = None if motion.joint_translations is None else motion.joint_translations[:1]
        _, g_pos = forward_kinematics(motion.skeleton, motion.local_rotations[:1], motion.root_translations[:1], jt)
        rest = rig.skeleton.rest_global_positions
        lengths = np.linalg.norm(rest[legs[:, 1]] - rest[legs[:, 0]], axis=-1) + \
            np.linalg.norm(rest[legs[:, 2]] - rest[legs[:, 1]], axis=-1)
        return {"motion": motion, "legs": legs, "centre": g_pos[0, legs[:, 2]].mean(axis=0),
                "yaw": facing(g_pos[0, legs[0, 0]] - g_pos[0, legs[1, 0]]), "reach": LEG_REACH * lengths}

    @classmethod
    def evaluate(cls, jobs, block) -> None:
        # In the order they started: a posture takes its footprints from the one it follows.
        for job in sorted(jobs, key=lambda j: (j.activity.start_s, j.activity.id)):
            job.controller.evaluate_one(job, block)

    def evaluate_one(self, job, block) -> None:
        b, pose, state = job.binding, job.pose, job.state
        started = np.flatnonzero(job.local_times >= -1e-9)
        if "ankles" not in state:
            if not started.size:
                return
            state.update(self._footprints(pose, b["legs"], int(started[0])))
        pin = self._leaving(job, block)
        live = job.weight > 0.0
        if not live.any():
            return
        sk = pose.rig.skeleton
        times = self.phase_s + np.maximum(job.local_times, 0.0)
        target, root, _, _ = sample_motion(b["motion"], times, loop=True)
        turn = _yaw(state["yaw"] - b["yaw"])
        target[:, 0] = quat.multiply(turn, target[:, 0])
        root = state["centre"] + quat.rotate(turn, root - b["centre"])
        w = job.weight[:, None]
        rotations = quat.slerp(pose.local_rotations, target, np.broadcast_to(w, target.shape[:2]))
        root = pose.root_translations + w * (root - pose.root_translations)
        jt = pose.joint_translations
        goals = np.broadcast_to(state["ankles"], (len(root), 2, 3))
        root = self._lowered(sk, rotations, root, jt, b["legs"], goals, b["reach"])
        solve_limb(sk, rotations, root, jt, b["legs"], goals, weight=np.repeat((pin * live)[:, None], 2, axis=1),
                   pole=state["forward"], end_rotation=np.broadcast_to(state["ankle_rotations"], (len(root), 2, 4)),
                   distance=False)
        on = live.astype(float)
        pose.set_rotations(np.arange(sk.num_joints), rotations, on)
        pose.set_root(root, on)

    def _leaving(self, job, block) -> np.ndarray:
        """(F,) how firmly the feet stay planted: 1, fading with the posture once the pose below walks away
        (then the activity ends after its blend out, and ``job.weight`` fades with it)."""
        state = job.state
        if "leave_s" not in state:
            hips = job.pose.chain_pose(job.binding["legs"][:, 0])[1].mean(axis=1)  # (F, 3) in the world
            away = (np.linalg.norm((hips - state["hips"])[:, [0, 2]], axis=-1) > WALK_AWAY_M) & (job.local_times >= 0.0)
            if not away.any():
                return np.ones(len(block))
            state["leave_s"] = float(block.times[int(np.argmax(away))])
            activity = job.activity
            end = state["leave_s"] + activity.blend_out_s
            if activity.end_s is None or end < activity.end_s:
                activity.end_s = end
                # This block's weights were taken before the activity had that end: the blend out, as later blocks have it.
                job.weight = activity.weights(block.times)
        return 1.0 - smoothstep((block.times - state["leave_s"]) / max(job.activity.blend_out_s, 1e-9))

    @staticmethod
    def _footprints(pose, legs: np.ndarray, k: int) -> dict:
        """Where the pose below stands at frame ``k``: ankle positions (2, 3) and global rotations (2, 4),
        their centre (3,), its facing (radians) and forward (3,), in the character's own frame; the hips'
        centre (3,) in the world."""
        jt = None if pose.joint_translations is None else pose.joint_translations[k:k + 1]
        g_rot, g_pos = forward_kinematics(pose.rig.skeleton, pose.local_rotations[k:k + 1], pose.root_translations[k:k + 1], jt)
        ankles = g_pos[0, legs[:, 2]]
        yaw = facing(g_pos[0, legs[0, 0]] - g_pos[0, legs[1, 0]])
        hips = pose.chain_pose(legs[:, 0])[1][k].mean(axis=0)
        return {"ankles": ankles, "ankle_rotations": g_rot[0, legs[:, 2]], "centre": ankles.mean(axis=0), "yaw": yaw,
                "forward": np.array([np.sin(yaw), 0.0, np.cos(yaw)]), "hips": hips}

    @staticmethod
    def _lowered(sk, rotations, root, jt, legs, goals, reach) -> np.ndarray:
        """Root translations (F, 3) lowered, frame by frame, just enough for each hip to reach its ankle goal
        (F, 2, 3) within ``reach`` (2,) metres."""
        _, g_pos = forward_kinematics(sk, rotations, root, jt)
        d = goals - g_pos[:, legs[:, 0]]  # (F, 2, 3) hip to ankle
        across = np.sum(d[..., [0, 2]] ** 2, axis=-1)
        drop = -d[..., 1] - np.sqrt(np.maximum(reach ** 2 - across, 0.0))  # how far the hip must come down
        out = root.copy()
        out[:, 1] -= np.maximum(drop.max(axis=1), 0.0)
        return out


def posture_from_bml(parameters: dict, runtime, character: str, activation=None) -> Posture | None:
    """A :class:`Posture` from a planned BML posture (``parameters["posture"]``: the pack's clip). It blends in
    from start to ready (a shift: over its whole span) and, when temporary, out from relax to end; a lasting
    one ends the character's earlier lasting postures (this controller's, or a posture clip of the character)
    once it is in."""
    clip = parameters.get("posture")
    if not clip:
        return None
    start = activation.start if activation is not None else runtime.time
    persistent = activation.persistent if activation is not None else True
    ready = activation.time("ready") if activation is not None else None
    transition = parameters.get("transition_s")
    if transition is None:
        transition = (ready - start) if ready is not None else \
            (activation.end - start) if activation is not None else TRANSITION_S
    posture = Posture(clip, parameters.get("pack") or "postures", max(float(transition), 1.0 / runtime.fps))
    if activation is not None and not persistent:
        relax = activation.time("relax")
        posture.blend_out_s = max(activation.end - (relax if relax is not None else activation.end), 1.0 / runtime.fps)
    if persistent:
        for a in runtime.activities:
            lasting_posture = isinstance(a.controller, Posture) or getattr(a.source, "controller", None) == "posture"
            if a.rig.name == character and lasting_posture and a.end_s is None and a.start_s < start:
                a.end_s, a.blend_out_s = start + posture.blend_in_s, 0.0
    return posture
