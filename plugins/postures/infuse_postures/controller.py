"""The ``posture`` controller: a standing posture of a postures pack on the whole body, its idle looping.

The posture's clip (retargeted onto the character by infusing it with the pack, once per character
file and mapping) plays on the base layer above walks and idle clips (priority :data:`PRIORITY`),
over the whole body. It is placed where the character stands: the feet stay on the footprints of the
pose below at the frame the posture begins (both ankles, where they are and how they are turned), the
clip turned to that pose's facing and moved so its own feet land there. Through the blend in and out,
and on a character whose stance is wider or narrower than the pack's, two-joint leg IK holds the
ankles on those footprints (the pelvis lowered where a leg could not reach). So a posture follows any
other posture, or the idle below, with the feet planted. Through a blend the arms go by the pack's
neutral posture, hanging a little away from the sides; a wrist that comes from or goes behind the back
travels around the body (about the vertical through the pelvis: off the body, round it by its own side,
onto it; arm IK). From hands behind the back to hands clasped in front, say, the hands come round the
hips instead of through them. Layers above add as usual: breathing, gestures, gaze, head and face.

A hand the posture rests on a thigh (seated: its wrist, in the pack's own clip, over the thigh and within
:data:`ON_THIGH` thigh lengths of its bone) is put where that clip has it in the thigh's frame, scaled by
the character's thigh length (arm IK, once per character): retargeting by joint rotations alone would
leave it in the thigh of a character whose arms are longer for its legs than the pack's, or above it.

A posture started while another plays takes its footprints from the pose that one makes (postures
are evaluated in the order they started); a lasting posture ends the lasting ones before it once it
has blended in; a temporary one blends back out to what plays below it. One asked for while the
character walks begins once it stands. When the pose below walks
away (a foot more than :data:`WALK_AWAY_M` from where it stood), the posture gives way: it blends
out, letting the feet go with it. The feet, not the hips, tell: a seated posture's hips are far from
where the standing pose below has them, while the feet of every posture stay on the same footprints.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from infuse import Motion, quaternions as quat
from infuse.errors import MissingJointsError, UsageError
from infuse.kinematics import forward_kinematics
from infuse.runtime import Controller, Layer, Mode, sample_motion, smoothstep
from infuse.runtime.limb_ik import solve_limb
from infuse.runtime.swing import local_offsets, swing

#: Base-layer priority: above walks (which count up from 1) and the scene's idle clip.
PRIORITY = 10_000
#: Default blend into and out of a posture, seconds.
TRANSITION_S = 1.0
#: A standing leg reaches at most this share of its length (the knee never locks).
LEG_REACH = 0.995
#: A foot of the pose below this far (metres, horizontally) from where it stood: the character walks off.
WALK_AWAY_M = 0.15
#: The pose below stands when its hips move slower than this, metres per second (an idle sways at a few cm/s).
STILL_M_S = 0.15
#: The posture whose arms a blend passes by (hanging at the sides), and the shares of the blend over which
#: the arms leave the pose below for it and go from it to the posture's.
VIA = "neutral"
VIA_SHARE = 0.6
#: How far the arms are lifted out to the sides, beyond the neutral posture's, as they pass by it (radians).
VIA_ABDUCTION = np.radians(20.0)
#: How far a wrist going round the body bulges out on the way, metres, for a quarter turn or more about it.
BULGE_M = 0.05
#: A wrist of a posture's own clip this close to its thigh's bone, in thigh lengths, and over it (from hip to
#: knee, or up to this share past the knee), rests on the thigh.
ON_THIGH = 0.35
#: How far round from the front (degrees about the body) a wrist must start or end for it to begin to take
#: the way round the body, and to take it in full: hands behind the back.
ROUND_DEG = (110.0, 140.0)


def facing(left: np.ndarray) -> float:
    """Heading (radians about +Y, + turning the front toward +X) of a body whose left is ``left`` (3,)."""
    return float(np.arctan2(-left[2], left[0]))


def _yaw(angle: float) -> np.ndarray:
    """The rotation (4,) by ``angle`` radians about +Y."""
    return quat.from_axis_angle(np.array([0.0, 1.0, 0.0]), np.array(angle))


@dataclass(frozen=True, eq=False)
class PostureBinding:
    """A posture bound to one character (positions in metres, in the posture clip's first frame).

    - ``motion``: the posture's idle, infused on the character; ``via``: the posture whose arms a blend
      passes by (:data:`VIA`), None for that posture itself or a pack without it;
    - ``legs`` (2, 3): hip, knee and ankle of the left and right legs; ``reach`` (2,): how far each hip
      may be from its planted ankle (:data:`LEG_REACH` of the leg's length);
    - ``centre`` (3,): between the ankles; ``yaw``: the heading of the hips (radians, :func:`facing`);
    - ``arms`` (A,): the joints of both arms; ``abduction``: the shoulder joints (K,) and the local
      offsets (K, 4) lifting each arm out to its side;
    - ``hands`` (2, 3): shoulder, elbow and wrist of each arm, None without a way round the body;
      ``base``: the pelvis joint, or None.
    """

    motion: Motion
    via: Motion | None
    legs: np.ndarray
    reach: np.ndarray
    centre: np.ndarray
    yaw: float
    arms: np.ndarray
    abduction: tuple[np.ndarray, np.ndarray]
    hands: np.ndarray | None
    base: int | None


@dataclass(frozen=True, eq=False)
class Footprints:
    """Where the pose below a posture stands on the frame the posture begins, in the character's own frame:
    ``ankles`` (2, 3) metres and ``ankle_rotations`` (2, 4) global, left then right; ``centre`` (3,) between
    them; ``yaw`` the hips' heading (radians, :func:`facing`) and ``forward`` (3,) its unit vector;
    ``ankles_world`` (2, 3) the ankles in the world, metres."""

    ankles: np.ndarray
    ankle_rotations: np.ndarray
    centre: np.ndarray
    yaw: float
    forward: np.ndarray
    ankles_world: np.ndarray


@dataclass
class PostureState:
    """What a posture activity carries between blocks: its ``footprints`` (None until the pose below stands)
    and ``leave_s``, when the pose below walked away (global seconds; None while it stays)."""

    footprints: Footprints | None = None
    leave_s: float | None = None


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
        self.replaces: list = []  # activities this posture ends once it is in (see posture_from_bml)

    def describe(self) -> str:
        return f"posture {self.clip}"

    def bind(self, rig, report) -> PostureBinding:
        from infuse.packs import space_on  # packs load lazily: importing a plugin stays cheap

        space = space_on(rig, self.pack)
        if self.clip not in space.clips:
            raise UsageError(f"pack {space.pack!r} has no posture {self.clip!r} (its postures: {', '.join(space.clips)})")
        motion = space.clips[self.clip].motion
        names = [f"{s}_{j}" for s in "lr" for j in ("hip", "knee", "ankle")]
        missing = [n for n in names if rig.joint(n) is None]
        if missing:
            raise MissingJointsError(rig.character.asset.path, f"posture {self.clip!r} plants the feet with "
                                                               f"{', '.join(missing)}, which the mapping lacks")
        legs = np.array([[rig.joint(f"{s}_{j}") for j in ("hip", "knee", "ankle")] for s in "lr"], dtype=np.int64)
        hands = _hands(rig)
        if hands is not None:
            motion = _on_thighs(rig.skeleton, motion, legs, hands, _own_clip(space.pack, self.clip))
        via = space.clips[VIA].motion if VIA in space.clips and self.clip != VIA else None
        jt = None if motion.joint_translations is None else motion.joint_translations[:1]
        _, g_pos = forward_kinematics(motion.skeleton, motion.local_rotations[:1], motion.root_translations[:1], jt)
        rest = rig.skeleton.rest_global_positions
        lengths = np.linalg.norm(rest[legs[:, 1]] - rest[legs[:, 0]], axis=-1) + \
            np.linalg.norm(rest[legs[:, 2]] - rest[legs[:, 1]], axis=-1)
        return PostureBinding(motion=motion, via=via, legs=legs, reach=LEG_REACH * lengths,
                              centre=g_pos[0, legs[:, 2]].mean(axis=0), yaw=facing(g_pos[0, legs[0, 0]] - g_pos[0, legs[1, 0]]),
                              arms=_arms(rig), abduction=_abduction(rig), hands=hands, base=rig.joint("base"))

    @classmethod
    def evaluate(cls, jobs, block) -> None:
        # In the order they started: a posture takes its footprints from the one it follows.
        for job in sorted(jobs, key=lambda j: (j.activity.start_s, j.activity.id)):
            job.controller.evaluate_one(job, block)

    def evaluate_one(self, job, block) -> None:
        b: PostureBinding = job.binding
        pose, state = job.pose, job.state_of(PostureState)
        if state.footprints is None:
            k = self._standing(job, block)
            if k is None:
                return
            state.footprints = self._footprints(pose, b.legs, k)
        feet = state.footprints
        pin = self._leaving(job, block, state, feet)
        live = job.weight > 0.0
        if not live.any():
            return
        sk = pose.rig.skeleton
        times = self.phase_s + np.maximum(job.local_times, 0.0)
        target, root, _, _ = sample_motion(b.motion, times, loop=True)
        turn = _yaw(feet.yaw - b.yaw)
        target[:, 0] = quat.multiply(turn, target[:, 0])
        root = feet.centre + quat.rotate(turn, root - b.centre)
        w = job.weight[:, None]
        rotations = quat.slerp(pose.local_rotations, target, np.broadcast_to(w, target.shape[:2]))
        blending = live & (job.weight < 1.0)
        if b.via is not None and b.arms.size and blending.any():
            rotations[blending] = self._by_the_sides(pose.local_rotations[blending], target[blending], rotations[blending],
                                                     job.weight[blending], b, b.via, times[blending])
        placed = root
        root = pose.root_translations + w * (root - pose.root_translations)
        jt = pose.joint_translations
        goals = np.broadcast_to(feet.ankles, (len(root), 2, 3))
        root = self._lowered(sk, rotations, root, jt, b.legs, goals, b.reach)
        solve_limb(sk, rotations, root, jt, b.legs, goals, weight=np.repeat((pin * live)[:, None], 2, axis=1),
                   pole=feet.forward, end_rotation=np.broadcast_to(feet.ankle_rotations, (len(root), 2, 4)),
                   distance=False)
        if b.hands is not None and blending.any():
            k = blending
            rotations[k] = self._around_the_body(sk, b, feet.yaw, job.weight[k], rotations[k], root[k],
                                                 (pose.local_rotations[k], pose.root_translations[k]),
                                                 (target[k], placed[k]), None if jt is None else jt[k])
        on = live.astype(float)
        pose.set_rotations(np.arange(sk.num_joints), rotations, on)
        pose.set_root(root, on)

    @staticmethod
    def _around_the_body(sk, b: PostureBinding, yaw: float, weight, rotations, root, below, target, jt) -> np.ndarray:
        """``rotations`` (K, J, 4) of blending frames with each wrist that comes from or goes behind the back put
        on its way around the body, from where the pose ``below`` has it to where the posture's ``target`` pose
        does (both (rotations (K, J, 4), root (K, 3))), ``weight`` (K,) of the way along: about the vertical
        through the pelvis, off the body by up to :data:`BULGE_M`, round it (its angle, distance and height
        going from one end's to the other's), onto it (arm IK, the hands keeping their turn)."""
        hands, base = b.hands, b.base
        face = _yaw(-yaw)

        def around(pose):  # (K, 2) angle, distance, height of each wrist about the pelvis, in the body's frame
            _, g_pos = forward_kinematics(sk, pose[0], pose[1], jt)
            d = quat.rotate(face, g_pos[:, hands[:, 2]] - g_pos[:, base, None])
            return np.arctan2(d[..., 0], d[..., 2]), np.hypot(d[..., 0], d[..., 2]), d[..., 1]

        (a0, r0, y0), (a1, r1, y1) = around(below), around(target)
        # Each hand goes round its own side (left +1, right -1): the shorter way, unless its middle lies well
        # over on the other side and the longer way's on the hand's own (from behind the back to the front by
        # the hip, not across the belly).
        short = np.angle(np.exp(1j * (a1 - a0)))
        long = short - np.sign(short) * 2.0 * np.pi
        side = np.array([1.0, -1.0])
        crossing = (side * np.sin(a0 + 0.5 * short) < -0.5) & (side * np.sin(a0 + 0.5 * long) > 0.5)
        turn = np.where(crossing, long, short)
        # Off the body first, round it, then onto it: the way round over the middle of the blend, the bulge
        # out over its first quarter and back in over its last.
        u = weight[:, None]
        along = smoothstep((u - 0.2) / 0.6)
        out = smoothstep(u / 0.25) * (1.0 - smoothstep((u - 0.75) / 0.25))
        bulge = BULGE_M * np.clip(np.abs(turn) / (0.5 * np.pi), 0.0, 1.0)
        angle = a0 + turn * along
        distance = r0 + (r1 - r0) * along + bulge * out
        height = y0 + (y1 - y0) * along
        _, g_pos = forward_kinematics(sk, rotations, root, jt)
        offset = np.stack((distance * np.sin(angle), height, distance * np.cos(angle)), axis=-1)
        goals = g_pos[:, base, None] + quat.rotate(_yaw(yaw), offset)
        # Only a hand coming from or going behind the back takes the way round (in full from ROUND_DEG[1] off
        # the front); in front and at the sides the blend's own way, by the sides, clears the body.
        behind = np.degrees(np.maximum(np.abs(a0), np.abs(a1)))
        share = smoothstep((behind - ROUND_DEG[0]) / (ROUND_DEG[1] - ROUND_DEG[0]))
        solved = np.ascontiguousarray(rotations)
        if share.any():
            solve_limb(sk, solved, root, jt, hands, goals, weight=np.broadcast_to(share, goals.shape[:2]), distance=False)
        return solved

    @staticmethod
    def _by_the_sides(below, target, rotations, weight, b: PostureBinding, via_motion: Motion, times) -> np.ndarray:
        """``rotations`` (K, J, 4) of blending frames with the arms' going from ``below`` to ``target`` (K, J, 4)
        by the arms of the posture ``via_motion`` (the binding's ``via``): toward them over the first
        :data:`VIA_SHARE` of the blend ``weight`` (K,), from them to the target's over the last."""
        arms = b.arms
        via, _, _, _ = sample_motion(via_motion, times, loop=True, joints=arms)
        leave = smoothstep(weight / VIA_SHARE)[:, None]
        arrive = smoothstep((weight - (1.0 - VIA_SHARE)) / VIA_SHARE)[:, None]
        joints, offsets = b.abduction
        columns = np.searchsorted(arms, joints)
        via[:, columns] = quat.multiply(via[:, columns], offsets)
        passing = quat.slerp(below[:, arms], via, np.broadcast_to(leave, via.shape[:2]))
        out = rotations.copy()
        out[:, arms] = quat.slerp(passing, target[:, arms], np.broadcast_to(arrive, via.shape[:2]))
        return out

    def _standing(self, job, block) -> int | None:
        """The first frame of the block, from the posture's start on, where the pose below stands (its hips
        slower than :data:`STILL_M_S`), or None. A posture asked for while the character still walks (its
        stop steps, a walk that lasts longer than planned) waits for it to stand: the activity is moved to
        start there (its end with it) and the job's weights and times follow."""
        started = job.local_times >= -1e-9
        if not started.any():
            return None
        hips = job.pose.chain_pose(job.binding.legs[:, 0])[1].mean(axis=1)  # (F, 3) in the world
        previous = self._previous_hips(job)
        before = np.concatenate(([hips[0] if previous is None else previous], hips[:-1]))
        speed = np.linalg.norm((hips - before)[:, [0, 2]], axis=-1) * block.fps
        still = np.flatnonzero(started & (speed < STILL_M_S))
        if not still.size:
            return None
        k = int(still[0])
        activity = job.activity
        late = float(block.times[k]) - activity.start_s
        if late > 1e-9:
            activity.start_s += late
            if activity.end_s is not None:
                activity.end_s += late
            for earlier in self.replaces:  # what it replaces plays on until it is in (unless it is over or walked off)
                walked_off = earlier.state.get(PostureState, PostureState()).leave_s is not None
                if earlier.end_s is not None and earlier.end_s > block.times[0] and not walked_off:
                    earlier.end_s += late
            job.weight = activity.weights(block.times)
            job.local_times = block.times - activity.start_s
        return k

    @staticmethod
    def _previous_hips(job) -> np.ndarray | None:
        """The hips' centre (3,) in the world on the frame before the block, as the runtime wrote it, or None."""
        runtime = job.activity.runtime
        local, root, _ = runtime.last_poses(job.rig.name, 1)
        if not len(local):
            return None
        _, g_pos = forward_kinematics(job.rig.skeleton, local, root)
        return g_pos[0, job.binding.legs[:, 0]].mean(axis=0)

    @staticmethod
    def _leaving(job, block, state: PostureState, feet: Footprints) -> np.ndarray:
        """(F,) how firmly the feet stay planted: 1, fading with the posture once the pose below walks away
        from ``feet`` (then the activity ends after its blend out, and ``job.weight`` fades with it)."""
        if state.leave_s is None:
            ankles = job.pose.chain_pose(job.binding.legs[:, 2])[1]  # (F, 2, 3) in the world
            moved = np.linalg.norm((ankles - feet.ankles_world)[..., [0, 2]], axis=-1).max(axis=1)
            away = (moved > WALK_AWAY_M) & (job.local_times >= 0.0)
            if not away.any():
                return np.ones(len(block))
            state.leave_s = float(block.times[int(np.argmax(away))])
            activity = job.activity
            end = state.leave_s + activity.blend_out_s
            if activity.end_s is None or end < activity.end_s:
                activity.end_s = end
                # This block's weights were taken before the activity had that end: the blend out, as later blocks have it.
                job.weight = activity.weights(block.times)
        return 1.0 - smoothstep((block.times - state.leave_s) / max(job.activity.blend_out_s, 1e-9))

    @staticmethod
    def _footprints(pose, legs: np.ndarray, k: int) -> Footprints:
        """Where the pose below stands at frame ``k`` of the block."""
        jt = None if pose.joint_translations is None else pose.joint_translations[k:k + 1]
        g_rot, g_pos = forward_kinematics(pose.rig.skeleton, pose.local_rotations[k:k + 1], pose.root_translations[k:k + 1], jt)
        ankles = g_pos[0, legs[:, 2]]
        yaw = facing(g_pos[0, legs[0, 0]] - g_pos[0, legs[1, 0]])
        return Footprints(ankles=ankles, ankle_rotations=g_rot[0, legs[:, 2]], centre=ankles.mean(axis=0), yaw=yaw,
                          forward=np.array([np.sin(yaw), 0.0, np.cos(yaw)]), ankles_world=pose.chain_pose(legs[:, 2])[1][k])

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


def _own_clip(pack: str, clip: str) -> Motion | None:
    """The posture's clip as the pack has it, on the pack's own skeleton, or None when that is not readable."""
    import infuse
    from infuse.errors import InfuseError
    from infuse.packs import load_pack

    try:
        return next(iter(infuse.load(load_pack(pack).manifest.clip(clip).file).motions.values()), None)
    except (InfuseError, KeyError, OSError):
        return None


def _thigh_frames(sk, motion: Motion, legs: np.ndarray, wrists: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Each wrist (``wrists`` (2,) joints) in its thigh's frame, per frame: coordinates (F, 2, 3) in thigh lengths
    (+Z from the hip to the knee, +X from the right hip to the left, +Y up off the thigh), the frames (F, 2, 3, 3)
    (rows: the axes) and the thighs' lengths (F, 2, 1), metres."""
    jt = motion.joint_translations
    _, g_pos = forward_kinematics(sk, motion.local_rotations, motion.root_translations, jt)
    hip, knee = g_pos[:, legs[:, 0]], g_pos[:, legs[:, 1]]  # (F, 2, 3)
    length = np.linalg.norm(knee - hip, axis=-1, keepdims=True)
    z = (knee - hip) / length
    x = np.broadcast_to((hip[:, 0] - hip[:, 1])[:, None], z.shape)
    x = x - np.sum(x * z, axis=-1, keepdims=True) * z
    x = x / np.linalg.norm(x, axis=-1, keepdims=True)
    axes = np.stack((x, np.cross(z, x), z), axis=-2)
    return np.einsum("fkij,fkj->fki", axes, g_pos[:, wrists] - hip) / length, axes, length


def _on_thighs(sk, motion: Motion, legs: np.ndarray, hands: np.ndarray, own: Motion | None) -> Motion:
    """``motion`` (the posture infused on the character) with each hand that ``own`` (the pack's clip) rests on a
    thigh put where ``own`` has it in the thigh's frame, scaled by the character's thigh (arm IK); as is when
    no hand rests on a thigh or ``own`` lacks the canonical leg and arm joints."""
    names = [[f"{s}_{j}" for j in ("hip", "knee")] for s in "lr"]
    if own is None or any(n not in own.skeleton.index for side in names for n in side) or \
            any(f"{s}_wrist" not in own.skeleton.index for s in "lr"):
        return motion
    index = own.skeleton.index
    own_legs = np.array([[index[n] for n in side] for side in names], dtype=np.int64)
    wanted, _, _ = _thigh_frames(own.skeleton, own, own_legs, np.array([index["l_wrist"], index["r_wrist"]]))
    frames = np.minimum(np.round(np.arange(motion.num_frames) / motion.fps * own.fps).astype(np.int64), own.num_frames - 1)
    wanted = wanted[frames]  # (F, 2, 3) thigh lengths
    off = np.linalg.norm(wanted[..., :2], axis=-1)
    resting = (off < ON_THIGH) & (wanted[..., 2] > 0.0) & (wanted[..., 2] < 1.0 + ON_THIGH) & (wanted[..., 1] > 0.0)
    if not resting.any():
        return motion
    _, axes, length = _thigh_frames(sk, motion, legs, hands[:, 2])
    _, g_pos = forward_kinematics(sk, motion.local_rotations, motion.root_translations, motion.joint_translations)
    goals = g_pos[:, legs[:, 0]] + np.einsum("fkji,fkj->fki", axes, wanted * length)
    local = np.array(motion.local_rotations)
    solve_limb(sk, local, motion.root_translations, motion.joint_translations, hands, goals,
               weight=resting.astype(float), distance=False)
    return motion.replace(local_rotations=local)


def _arms(rig) -> np.ndarray:
    """(K,) the joints of both arms: the shoulder girdles (or the shoulders) and every joint below them."""
    roots = {j for j in (rig.joint(f"{s}_acromioclavicular") or rig.joint(f"{s}_shoulder") for s in "lr") if j is not None}
    parents = rig.skeleton.parents
    out = []
    for j in range(rig.skeleton.num_joints):
        k = j
        while k >= 0 and k not in roots:
            k = parents[k]
        if k >= 0:
            out.append(j)
    return np.array(out, dtype=np.int64)


def _hands(rig) -> np.ndarray | None:
    """(2, 3) shoulder, elbow and wrist of each arm, or None when the mapping lacks one (no path round the body)."""
    names = [[f"{s}_{j}" for j in ("shoulder", "elbow", "wrist")] for s in "lr"]
    joints = [[rig.joint(n) for n in arm] for arm in names]
    if rig.joint("base") is None or any(j is None for arm in joints for j in arm):
        return None
    return np.array(joints, dtype=np.int64)


def _abduction(rig) -> tuple[np.ndarray, np.ndarray]:
    """The shoulder joints (K,) and the local offsets (K, 4) that lift each arm out to its side by
    :data:`VIA_ABDUCTION` (a roll about the body's forward axis, in the joints' aligned frames)."""
    joints = [(rig.joint(f"{s}_shoulder"), sign) for s, sign in (("l", 1.0), ("r", -1.0)) if rig.joint(f"{s}_shoulder") is not None]
    if not joints:
        return np.zeros(0, dtype=np.int64), np.zeros((0, 4))
    index = np.array([j for j, _ in joints], dtype=np.int64)
    rolls = np.array([sign * VIA_ABDUCTION for _, sign in joints])
    return index, local_offsets(rig.aligned[index], swing(np.zeros(len(index)), np.zeros(len(index)), rolls))


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
                posture.replaces.append(a)
    return posture
