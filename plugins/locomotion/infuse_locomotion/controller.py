"""The ``locomotion`` controller: a pack's locomotion cycles blended by speed, turn rate and direction.

Each frame the steering (:mod:`.steering`) asks for a speed, a turn rate and a travel direction. Their
point (velocity along and across the facing, turn rate) gets barycentric weights in the pack's
tessellation, as infused onto the character. The blend is **phase-synchronized and time-warped**: one
phase runs through every cycle at once, advancing by ``dt / T`` with T the weighted cycle duration,
and each clip maps it to its own time through its keys (left strike at phase 0, right strike at 0.5),
so the blended clips step together. **Root motion** is the weighted clips' velocities (so the realized
speed is the requested one inside the pack's range), turned by the integrated heading; each clip
contributes its pelvis motion relative to its own straight or circular path.

**Planted feet** follow the clips' weighted contact phases (heel down from heel strike to heel off,
ball down from foot flat to toe off). From heel strike to heel off the ankle stays where it landed;
from heel off to toe off the ball (``forefoot``, else ``toe``) stays put and the foot pivots about
it: the ankle goal is the pinned ball plus the animated ball-to-ankle offset, which carries the
foot's pitch, and the two-joint leg IK (``infuse.runtime.limb_ik``) reaches it with the foot keeping
its animated rotation. The switch from ankle to ball carries the foot's correction over, so it is
continuous, and at toe off the correction fades out over :data:`RELEASE_S`.
"""
from __future__ import annotations

import math

import numpy as np

from infuse import quaternions as quat
from infuse.errors import MissingFeatureError, UsageError
from infuse.runtime import Controller, Layer, Mode, sample_motion
from infuse.runtime.limb_ik import solve_limb
from infuse.runtime.pose import chain_fk

from .steering import Steering

_INFUSIONS: dict = {}

#: Seconds over which a released foot's pin correction fades back to the animation.
RELEASE_S = 0.15
#: Anchor of a foot in a frame: none (swinging), the ankle (heel down), the ball (heel off).
FREE, ANKLE, BALL = 0, 1, 2


def infusion_for(rig, pack: str, cache=None):
    """The :class:`~infuse.packs.BlendSpace` of ``pack`` on a runtime character (infused once per process)."""
    from infuse.packs import infuse_character

    key = (id(rig.character), id(rig.mapping), str(pack))
    if key not in _INFUSIONS:
        infusion = infuse_character(rig.character, [pack], mapping=rig.mapping, cache=cache)
        _INFUSIONS[key] = (rig.character, next(iter(infusion.spaces.values())))
    return _INFUSIONS[key][1]


def yaw(angle) -> np.ndarray:
    angle = np.asarray(angle, dtype=np.float64)
    return quat.from_axis_angle(np.broadcast_to(np.array([0.0, 1.0, 0.0]), angle.shape + (3,)), angle)


def clip_path(params: dict, t: np.ndarray) -> np.ndarray:
    """(T, 3) ground path of a clip's pelvis from its start: straight, or a circle when it turns."""
    vf, vl, w, h0 = params["forward_speed"], params["lateral_speed"], params["turn_rate"], params["heading_start"]
    speed, direction = math.hypot(vf, vl), math.atan2(vl, vf)
    a = h0 + direction
    if abs(w) < 1e-6:
        return np.stack((speed * math.sin(a) * t, 0 * t, speed * math.cos(a) * t), axis=-1)
    r = speed / w
    return np.stack((r * (math.cos(a) - np.cos(a + w * t)), 0 * t, r * (np.sin(a + w * t) - math.sin(a))), axis=-1)


def canonical_clip(clip):
    """The clip with its facing and its travel taken out: joint 0 turned by minus the clip's linear
    heading, the mover's translation made relative to the clip's path, in the clip's facing frame.
    Returns (motion, mover joint)."""
    m = clip.motion
    t = np.arange(m.num_frames) / m.fps
    p = clip.parameters
    h = p["heading_start"] + p["turn_rate"] * t
    undo = yaw(-h)
    mover, pos = 0, m.root_translations
    if np.ptp(pos, axis=0).max() < 1e-6 and m.joint_translations is not None:
        moving = np.nonzero(np.ptp(m.joint_translations, axis=0).max(axis=1) > 1e-6)[0]
        if moving.size:
            mover, pos = int(moving[0]), m.joint_translations[:, moving[0]]
    path = clip_path(p, t)
    start = pos[0] * np.array([1.0, 0.0, 1.0])
    offset = quat.rotate(undo, pos - start - path)
    rot = np.array(m.local_rotations)
    rot[:, 0] = quat.multiply(undo, rot[:, 0])
    if mover == 0:
        return m.replace(local_rotations=rot, root_translations=offset), mover
    jt = np.array(m.joint_translations)
    jt[:, mover] = offset
    return m.replace(local_rotations=rot, joint_translations=jt), mover


def warp(keys: np.ndarray, phase: np.ndarray) -> np.ndarray:
    """Clip times (seconds) of ``phase`` in [0, 1) through the clip's keys at phases 0, 0.5, 1."""
    first = phase < 0.5
    return np.where(first, keys[0] + (keys[1] - keys[0]) * phase * 2.0, keys[1] + (keys[2] - keys[1]) * (phase - 0.5) * 2.0)


class Locomotion(Controller):
    """Locomotion from a behaviour pack (an installed name, a folder, or a :class:`BlendSpace`).

    - ``speed`` m/s, ``turn_rate`` rad/s (+ left), ``direction`` rad of travel from the facing (+ left):
      numbers or functions of the activity's time; or ``path`` (ground points in the character's own
      frame, metres) / ``target`` (one point) to walk to, stopping there.
    - ``max_accel``, ``max_decel`` (m/s²), ``max_turn_rate`` (rad/s), ``max_turn_accel`` (rad/s²).
    - ``pin_feet``: pin planted feet with leg IK (default on).
    """

    kind = "locomotion"
    layer = Layer.BASE
    mode = Mode.OVERRIDE
    blend_in_s = 0.0
    blend_out_s = 0.3

    def __init__(self, pack="locomotion-male", speed=1.3, turn_rate=0.0, direction=0.0, path=None, target=None,
                 max_accel: float = 1.5, max_decel: float = 2.5, max_turn_rate: float = math.radians(90.0),
                 max_turn_accel: float = math.radians(240.0), pin_feet: bool = True, cache=None):
        if path is not None and target is not None:
            raise UsageError("give a path or a target, not both")
        if target is not None:
            path = [target]
        try:
            self.steering = Steering(speed, turn_rate, direction, path, max_accel, max_decel, max_turn_rate, max_turn_accel)
        except ValueError as exc:
            raise UsageError(str(exc)) from None
        self.pack = pack
        self.pin_feet = bool(pin_feet)
        self.cache = cache

    def describe(self) -> str:
        return f"locomotion ({getattr(self.pack, 'pack', self.pack)})"

    def bind(self, rig, report):
        from infuse.packs import BlendSpace

        space = self.pack if isinstance(self.pack, BlendSpace) else infusion_for(rig, self.pack, self.cache)
        if space.kind != "locomotion" or "locomotion" not in space.tessellations:
            raise UsageError(f"pack {space.pack!r} is not a locomotion pack")
        clips = space.group("locomotion")
        prepared = [canonical_clip(c) for c in clips]
        legs = []
        for s in "lr":
            names = (f"{s}_hip", f"{s}_knee", f"{s}_ankle")
            if all(rig.joint(n) is not None for n in names):
                ball = rig.joint(f"{s}_forefoot")
                ball = rig.joint(f"{s}_toe") if ball is None else ball
                legs.append(tuple(rig.joint(n) for n in names) + (ball,))
        if self.pin_feet and len(legs) < 2:
            report("no mapped hips, knees and ankles: feet are not pinned")
        if not clips:
            raise MissingFeatureError(None, f"pack {space.pack!r} has no locomotion cycles")
        p = lambda k: np.array([c.parameters[k] for c in clips])  # noqa: E731
        # Steer no harder than the pack's examples turn, so the realized path follows the steering's.
        reach = 0.9 * float(np.abs(p("turn_rate")).max())
        if reach > 0:
            self.steering.max_turn_rate = min(self.steering.max_turn_rate, reach)
        return {"space": space, "clips": clips, "motions": [m for m, _ in prepared], "movers": [mv for _, mv in prepared],
                "forward": p("forward_speed"), "lateral": p("lateral_speed"), "turn": p("turn_rate"),
                "durations": np.array([(c.keys[2] - c.keys[0]) for c in clips]), "legs": legs}

    def evaluate_one(self, job, block) -> None:
        b = job.binding
        active = np.nonzero(job.local_times >= -1e-9)[0]
        if not active.size:
            return
        st = job.state
        if not st:
            st.update(x=0.0, z=0.0, heading=0.0, speed=0.0, turn=0.0, waypoint=0, phase=0.0,
                      anchor=np.zeros(2, np.int64), pins=np.zeros((2, 3)), offset=np.zeros((2, 3)), released=np.full(2, 1e9))
        dt = 1.0 / block.fps
        times = job.local_times[active]
        x0, z0, h0 = st["x"], st["z"], st["heading"]
        req = self.steering.run(st, times, dt)
        speed, turn, direction = req[:, 0], req[:, 1], req[:, 2]
        query = np.stack((speed * np.cos(direction), speed * np.sin(direction), turn), axis=-1)
        w, _ = b["space"].weights("locomotion", query)
        vf, vl, vt = w @ b["forward"], w @ b["lateral"], w @ b["turn"]
        # Root motion: integrate the blend's own velocities from where the last block ended.
        heading = h0 + np.concatenate(([0.0], np.cumsum(vt[:-1] * dt)))
        step_x = (vf * np.sin(heading) + vl * np.cos(heading)) * dt
        step_z = (vf * np.cos(heading) - vl * np.sin(heading)) * dt
        px = x0 + np.concatenate(([0.0], np.cumsum(step_x[:-1])))
        pz = z0 + np.concatenate(([0.0], np.cumsum(step_z[:-1])))
        st.update(x=float(px[-1] + step_x[-1]), z=float(pz[-1] + step_z[-1]), heading=float(heading[-1] + vt[-1] * dt))
        period = np.maximum(w @ b["durations"], 1e-3)
        phase = st["phase"] + np.concatenate(([0.0], np.cumsum(dt / period[:-1])))
        st["phase"] = float((phase[-1] + dt / period[-1]) % 1.0)
        phase = phase % 1.0
        rot, root, jt, contact = self._blend(b, w, phase)
        # Place the blended pose on the integrated path.
        turn_q = yaw(heading)
        rot[:, 0] = quat.multiply(turn_q, rot[:, 0])
        ground = np.stack((px, np.zeros_like(px), pz), axis=-1)
        mover = b["movers"][int(np.argmax(w.sum(axis=0)))]
        if mover == 0:
            root = ground + quat.rotate(turn_q, root)
        else:
            jt[:, mover] = ground + quat.rotate(turn_q, jt[:, mover])
        if self.pin_feet and len(b["legs"]) == 2:
            self._pin(job, st, rot, root, jt, contact, heading, dt)
        pose = job.pose
        full = np.repeat(pose.local_rotations[:1], len(job.weight), axis=0)
        full[active] = rot
        weight = np.zeros(len(job.weight))
        weight[active] = job.weight[active]
        pose.set_rotations(np.arange(rot.shape[1]), full, weight, job.mode)
        roots = np.array(pose.root_translations)
        roots[active] = root
        pose.set_root(roots, weight, job.mode)
        if jt is not None:
            moved = np.array(pose.joint_translations) if pose.joint_translations is not None else np.repeat(
                job.rig.skeleton.rest_translations[None], len(job.weight), axis=0)
            moved[active] = jt
            pose.set_translations(np.arange(1, jt.shape[1]), moved[:, 1:], weight, job.mode)

    def _blend(self, b, w, phase):
        """Weighted, sign-aligned rotations, root offsets, joint translations and foot contact phases
        (F, 2, 2): the weight of the clips with each foot's heel and ball down."""
        used = np.nonzero(w.max(axis=0) > 1e-6)[0]
        order = used[np.argsort(-w[:, used].sum(axis=0))]
        rot = root = jt = None
        contact = np.zeros((len(phase), 2, 2))
        for i in order:
            clip, motion = b["clips"][i], b["motions"][i]
            t = warp(clip.keys, phase) % max(motion.duration, 1e-9)
            r, p, j, _ = sample_motion(motion, t, loop=True)
            wi = w[:, i][:, None]
            if rot is None:
                rot = r * wi[:, :, None]
                root = p * wi
                jt = None if j is None else j * wi[:, :, None]
            else:
                sign = np.where(np.sum(rot * r, axis=-1, keepdims=True) < 0.0, -1.0, 1.0)
                rot += sign * r * wi[:, :, None]
                root += p * wi
                if j is not None and jt is not None:
                    jt += j * wi[:, :, None]
            frame = np.minimum(np.rint(t * motion.fps).astype(np.int64), len(clip.phases) - 1)
            contact += clip.phases[frame] * wi[:, :, None]
        rot = quat.normalize(rot)
        return rot, root, jt, contact

    def _pin(self, job, st, rot, root, jt, contact, heading, dt) -> None:
        """Pin planted feet by leg IK: the ankle while the heel is down, the ball while only it is down
        (the foot pivoting about it); fade the correction out after toe off. ``contact`` (F, 2, 2)."""
        sk = job.rig.skeleton
        forward = np.stack((np.sin(heading), 0 * heading, np.cos(heading)), axis=-1)
        for k, (hip, knee, ankle, ball) in enumerate(job.binding["legs"]):
            heel_w, ball_w = contact[:, k, 0], contact[:, k, 1]
            planted = np.maximum(heel_w, ball_w) > 0.5
            anchor = np.where(planted, np.where((ball_w > heel_w) & (ball is not None), BALL, ANKLE), FREE)
            joints = [ankle] if ball is None else [ankle, ball]
            _, pos = chain_fk(sk, rot, root, jt, joints)
            ankle_pos = pos[:, 0]
            point = np.where((anchor == BALL)[:, None], pos[:, -1], ankle_pos)  # the animated anchor
            goal = ankle_pos.copy()
            weight = np.zeros(len(anchor))
            prev = int(st["anchor"][k])
            offset, pin, released = st["offset"][k].copy(), st["pins"][k].copy(), float(st["released"][k])
            change = np.nonzero(np.diff(np.concatenate(([prev], anchor))) != 0)[0]
            bounds = np.concatenate((change, [len(anchor)]))
            if not change.size or change[0] != 0:
                bounds = np.concatenate(([0], bounds))
            for s, e in zip(bounds[:-1], bounds[1:]):
                kind = int(anchor[s])
                if kind == FREE:
                    if prev != FREE:
                        released = 0.0
                    age = released + dt * np.arange(1, e - s + 1)
                    fade = 1.0 - _ease(age / RELEASE_S)
                    goal[s:e] = ankle_pos[s:e] + offset * fade[:, None]
                    weight[s:e] = fade > 0.0
                    released = float(age[-1])
                    if fade[-1] <= 0.0:
                        offset = np.zeros(3)
                else:
                    if kind != prev:
                        # The anchor lands, or switches: it stays where the corrected foot puts it now.
                        carried = offset * (1.0 - _ease(released / RELEASE_S)) if prev == FREE else offset
                        pin = point[s] + carried
                    goal[s:e] = pin + ankle_pos[s:e] - point[s:e]
                    weight[s:e] = 1.0
                    offset = goal[e - 1] - ankle_pos[e - 1]
                    offset[1] = 0.0
                prev = kind
            goal[:, 1] = ankle_pos[:, 1]
            if weight.any():
                solve_limb(sk, rot, root, jt, (hip, knee, ankle), goal, weight=weight, pole=forward)
            st["anchor"][k], st["pins"][k], st["offset"][k], st["released"][k] = prev, pin, offset, released


def _ease(x) -> np.ndarray:
    """Smoothstep 3x² - 2x³ of ``x`` clipped to [0, 1]."""
    x = np.clip(x, 0.0, 1.0)
    return x * x * (3.0 - 2.0 * x)
