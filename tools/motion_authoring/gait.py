"""A procedural gait: looping walk, jog, run, turn and strafe cycles on the canonical skeleton.

The model, per stride of duration T (left heel strike at phase 0, right at 0.5):

- **Path.** The pelvis travels at ``speed`` in ``direction`` (radians from the facing, + to the left)
  while the facing turns at ``turn_rate`` (rad/s, + to the left): a straight line or a circle.
- **Footprints.** Each foot is planted for ``duty`` of the stride, centred on the moment the pelvis
  passes it, ``step_width / 2`` to its side (plus half the lateral travel of a stride for side
  steps) and toed out by ``toe_out``.
- **Rockers.** In stance the foot rolls: about the heel from ``heel_strike`` (toes up) to flat,
  flat, then about the ball to ``toe_off`` (heel up), the toes staying on the ground. In swing the
  ankle travels from toe off to the next heel strike, lifted by ``clearance`` early in the swing
  (the knee flexion peak), and the foot pitches from toe off to heel strike.
- **Pelvis.** Vertical bob (high at mid stance for walks, at mid flight for runs), lateral sway
  toward the stance foot, transverse rotation bringing the swing hip forward, obliquity dropping the
  swing side just after heel strike, and a forward lean. Its height is lowered until both legs
  reach their footprints with the knee never fully straight.
- **Legs** by two-bone IK with the knee toward the foot's heading. **Trunk** counter-rotates,
  the head stays level and faces the path. **Arms** hang, swing opposite to the legs, elbows flexed.

All angles in radians, lengths in metres, times in seconds.
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from infuse import quaternions as quat
from infuse.motion import Motion

from .body import X, Y, Z, Body, power, rot, smooth, two_bone

FPS = 30.0


@dataclass(frozen=True)
class Gait:
    """One gait's parameters (see the module doc). Angles are amplitudes (half the range) in radians."""

    speed: float = 1.4
    cadence: float = 108.0           # steps per minute
    direction: float = 0.0            # travel direction, radians from the facing, + left
    turn_rate: float = 0.0            # rad/s, + left
    duty: float = 0.60                # stance share of the stride
    run: bool = False                 # a flight phase: pelvis lowest at mid stance
    step_width: float = 0.10
    toe_out: float = np.radians(6.0)
    heel_strike: float = np.radians(18.0)
    toe_off: float = np.radians(40.0)
    clearance: float = 0.09           # ankle lift above the straight line, mid swing
    bob: float = 0.025               # vertical pelvis amplitude
    extra_drop: float = 0.045         # lower the pelvis this much below what the legs need
    sway: float = 0.025               # lateral pelvis amplitude
    pelvis_rotation: float = np.radians(4.0)
    pelvis_obliquity: float = np.radians(3.7)
    pelvis_tilt: float = np.radians(4.0)
    trunk_lean: float = np.radians(2.0)
    trunk_rotation: float = np.radians(3.0)   # thorax, counter to the pelvis
    trunk_sway: float = np.radians(2.0)       # thorax roll toward the stance side
    arm_swing: float = np.radians(15.0)
    arm_forward: float = np.radians(3.0)      # mean shoulder flexion
    arm_abduction: float = np.radians(10.0)   # arms away from the body (from hanging straight down)
    elbow: float = np.radians(12.0)
    elbow_swing: float = np.radians(8.0)      # more flexion with the arm forward
    carrying_angle: float = np.radians(12.0)  # forearm outward from the upper arm
    finger_curl: float = np.radians(15.0)
    head_pitch: float = np.radians(-2.0)      # + up
    turn_lean: float = 1.0                    # share of the centripetal lean atan(v·ω/g)
    strike_reach: float = 0.99                # hip-to-ankle distance at heel strike, leg lengths

    @property
    def stride(self) -> float:
        """Seconds per stride (two steps)."""
        return 120.0 / self.cadence

    @property
    def frames(self) -> int:
        """Frames per stride at :data:`FPS` (the clip has one more: the last closes the loop)."""
        return max(int(round(self.stride * FPS)), 8)

    def looped(self) -> "Gait":
        """The same gait with the cadence nudged so a stride is a whole number of frames."""
        return replace(self, cadence=120.0 * FPS / self.frames)


def path(g: Gait, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Pelvis path positions (T, 3) on the ground and facing angles (T,) at times ``t`` (from the origin at 0)."""
    t = np.asarray(t, dtype=np.float64)
    psi = g.turn_rate * t
    if abs(g.turn_rate) < 1e-9:
        v = g.speed * np.array([np.sin(g.direction), 0.0, np.cos(g.direction)])
        return t[:, None] * v, psi
    r = g.speed / g.turn_rate
    x = r * (np.cos(g.direction) - np.cos(psi + g.direction))
    z = r * (np.sin(psi + g.direction) - np.sin(g.direction))
    return np.stack((x, np.zeros_like(x), z), axis=-1), psi


def heading(psi) -> np.ndarray:
    return rot(Y, psi)


def rockers(g: Gait) -> tuple[float, float]:
    """Stance shares where the heel rocker ends (the foot is flat) and the heel starts to rise: in a
    walk at 60% of the stance (about 35% of the stride), the rise gathering speed toward toe off."""
    return (0.12, 0.6) if not g.run else (0.08, 0.35)


def foot_pitch_stance(g: Gait, s: np.ndarray) -> np.ndarray:
    """Foot pitch (+ toes up) over stance share ``s`` in [0, 1]: heel rocker, flat, forefoot rocker."""
    heel_end, roll_start = rockers(g)
    down = g.heel_strike * (1.0 - smooth(s / heel_end))
    up = -g.toe_off * np.clip((s - roll_start) / (1.0 - roll_start), 0.0, 1.0) ** (1.6 if g.run else 2.0)
    return np.where(s < heel_end, down, np.where(s < roll_start, 0.0, up))


def stance_ankle(body: Body, flat: np.ndarray, yaw: np.ndarray, pitch: np.ndarray) -> np.ndarray:
    """Ankle positions (F, 3) of a foot whose ankle is at ``flat`` when flat, pitched by ``pitch``
    about the heel (pitch > 0) or the ball (pitch < 0). The ball pivot is the forefoot joint itself
    (the metatarsophalangeal hinge): the toes stay flat on the ground while the heel rises, so the
    forefoot joint does not slide."""
    pivot = np.where((pitch > 0)[:, None], body.heel, body.offset("l_forefoot"))
    r_flat = heading(yaw)
    r_foot = quat.multiply(r_flat, rot(X, -pitch))
    return flat + quat.rotate(r_flat, pivot) - quat.rotate(r_foot, pivot)


@dataclass
class FootTrack:
    """One foot over the clip: ankle positions (F, 3), foot yaw and pitch (F,), toe bend (F,) and
    planted flags (F,)."""

    ankle: np.ndarray
    yaw: np.ndarray
    pitch: np.ndarray
    toe: np.ndarray
    planted: np.ndarray


class Pelvis:
    """The pelvis of gait ``g`` at any times: ground path, oscillations, rotation and hip positions."""

    def __init__(self, body: Body, g: Gait, height: float):
        self.body, self.g, self.height = body, g, height

    def at(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Positions (T, 3), global rotations (T, 4) and facing angles (T,) at times ``t``."""
        g = self.g
        t = np.asarray(t, dtype=np.float64)
        phi = t / g.stride
        ground, psi = path(g, t)
        face = heading(psi)
        mid = g.duty / 2.0
        high = mid + (0.25 if g.run else 0.0)
        vertical = g.bob * np.cos(4.0 * np.pi * (phi - high))
        sway = g.sway * np.cos(2.0 * np.pi * (phi - mid))
        yaw_osc = -g.pelvis_rotation * np.cos(2.0 * np.pi * phi)
        oblique = g.pelvis_obliquity * np.cos(2.0 * np.pi * (phi - 0.15))
        tilt = g.pelvis_tilt + 0.3 * g.pelvis_tilt * np.cos(4.0 * np.pi * (phi - mid))
        r_pelvis = quat.multiply(quat.multiply(rot(Y, yaw_osc), rot(Z, oblique - self.lean)), rot(X, tilt))
        lateral = quat.rotate(face, np.stack((sway, 0 * t, 0 * t), axis=-1))
        pos = ground + lateral + np.stack((0 * t, self.height + vertical, 0 * t), axis=-1)
        return pos, quat.multiply(face, r_pelvis), psi

    @property
    def lean(self) -> float:
        """Roll into a turn (radians, + to the left side down... for a left turn)."""
        return self.g.turn_lean * np.arctan(self.g.speed * self.g.turn_rate / 9.81)

    def hip(self, t: np.ndarray, side: str) -> np.ndarray:
        pos, r, _ = self.at(t)
        return pos + quat.rotate(r, self.body.rest(f"{side}_hip") - self.body.rest("base"))


#: A planted foot's ankle stays within this many leg lengths of the hip (the knee keeps a little
#: flexion); beyond it the heel rises about the ball.
STANCE_REACH = 0.99

#: Heel-up foot pitches tried when the leg cannot otherwise reach its planted ball (radians).
_PITCHES = -np.radians(np.arange(0.0, 66.0, 1.0))


def reach_pitch(body: Body, pelvis: Pelvis, side: str, t: np.ndarray, flat: np.ndarray, yaw: np.ndarray,
                pitch: np.ndarray) -> np.ndarray:
    """Foot pitch (F,): ``pitch``, or the smallest heel rise about the ball that brings the ankle within
    reach of the hip at times ``t`` (the heel rises because the leg is at full length)."""
    hip = pelvis.hip(t, side)
    limit = STANCE_REACH * body.leg
    cands = np.minimum(pitch[:, None], _PITCHES[None, :])  # (F, K), less than or equal to the profile
    f, k = cands.shape
    ankles = stance_ankle(body, np.repeat(flat, k, axis=0), np.repeat(yaw, k), cands.ravel()).reshape(f, k, 3)
    ok = np.linalg.norm(ankles - hip[:, None], axis=-1) <= limit
    first = np.where(ok.any(axis=1), np.argmax(ok, axis=1), k - 1)
    chosen = cands[np.arange(f), first]
    return np.where(pitch > 0, pitch, chosen)


def foot_track(body: Body, g: Gait, pelvis: Pelvis, t: np.ndarray, side: int, placement: Pelvis | None = None) -> FootTrack:
    """The ankle, foot angles and contacts of the left (``side`` = +1) or right (-1) foot at times ``t``.

    Footprints are placed for the ``placement`` pelvis (default ``pelvis``), so lowering the pelvis
    to reach them does not move them."""
    placement = placement or pelvis
    T = g.stride
    offset = 0.0 if side > 0 else 0.5
    name = "l" if side > 0 else "r"
    phase = t / T - offset
    k = np.floor(phase + 1e-9)
    u = phase - k
    forward_gait = abs(np.cos(g.direction)) > np.cos(np.radians(45.0))

    def plant(index):
        """Flat-foot ankle positions (F, 3) and yaws (F,) of footprints ``index``."""
        t_hs = (index + offset) * T
        t_mid = t_hs + g.duty * T / 2.0
        p, psi = path(g, t_mid)
        lateral_v = g.speed * np.sin(g.direction)
        half = g.step_width / 2.0 + abs(lateral_v) * T / 4.0
        # Side steps: the leading foot lands wide, the trailing foot closes in.
        shift = quat.rotate(heading(psi), np.array([side * half, 0.0, 0.0]))
        yaw = psi + side * g.toe_out
        zero = np.zeros((len(p), 3))
        e0 = stance_ankle(body, zero, yaw, np.full(len(p), g.heel_strike))
        if forward_gait and g.speed > 0.05:
            # The leading leg lands nearly straight: the ankle as far ahead of the hip as it reaches.
            hip = placement.hip(t_hs, name)
            ground_hs, psi_hs = path(g, t_hs)
            drop = hip[:, 1] - (body.ankle_height + e0[:, 1])
            ahead = np.sqrt(np.maximum((g.strike_reach * body.leg) ** 2 - drop ** 2, 0.0)) * np.sign(np.cos(g.direction))
            hip_ground = hip.copy()
            hip_ground[:, 1] = 0.0
            strike = hip_ground + quat.rotate(heading(psi_hs), np.array([0.0, 0.0, 1.0])) * ahead[:, None]
            flat = strike - e0
            # The footprint keeps its own side offset from the path, not the hip's.
            side_axis = quat.rotate(heading(psi), np.array([1.0, 0.0, 0.0]))
            across = np.sum((flat - p) * side_axis, axis=-1, keepdims=True)
            flat = flat - across * side_axis + shift
        else:
            e1 = stance_ankle(body, zero, yaw, np.full(len(p), -g.toe_off))
            centre = 0.5 * (e0 + e1)
            flat = p + shift - centre
        flat[:, 1] = body.ankle_height
        return flat, yaw, t_hs + g.duty * T

    flat0, yaw0, t_off0 = plant(k)
    flat1, yaw1, _ = plant(k + 1)
    stance = u < g.duty
    s = np.clip(u / g.duty, 0.0, 1.0)
    pitch_s = reach_pitch(body, pelvis, name, t, flat0, yaw0, foot_pitch_stance(g, s))
    ankle_s = stance_ankle(body, flat0, yaw0, pitch_s)
    toe_s = np.clip(-pitch_s, 0.0, np.radians(60.0))
    # Swing: from toe off of footprint k to heel strike of footprint k+1.
    w = np.clip((u - g.duty) / max(1.0 - g.duty, 1e-9), 0.0, 1.0)
    pitch_off = reach_pitch(body, pelvis, name, t_off0, flat0, yaw0, np.full(len(t), -g.toe_off))
    a0 = stance_ankle(body, flat0, yaw0, pitch_off)
    a1 = stance_ankle(body, flat1, yaw1, np.full(len(t), g.heel_strike))
    # The foot trails early in the swing (the knee folds) and reaches forward late.
    along = smooth(w ** (1.35 if g.run else 1.15))
    ankle_w = a0 + (a1 - a0) * along[:, None]
    lift = g.clearance * np.sin(np.pi * w ** (0.6 if g.run else 0.7))
    ankle_w[:, 1] += lift
    pitch_w = pitch_off + (g.heel_strike - pitch_off) * smooth(w ** 0.8)
    toe_w = np.clip(-pitch_off * (1.0 - smooth(w / 0.3)), 0.0, np.radians(60.0)) * 0.6
    yaw_w = yaw0 + (yaw1 - yaw0) * smooth(w)
    return FootTrack(np.where(stance[:, None], ankle_s, ankle_w), np.where(stance, yaw0, yaw_w),
                     np.where(stance, pitch_s, pitch_w), np.where(stance, toe_s, toe_w), stance)


def gait_motion(body: Body, g: Gait, name: str, cycles: int = 1) -> tuple[Motion, dict]:
    """A looping clip of ``cycles`` strides of gait ``g`` and facts about it (stance flags per foot)."""
    g = g.looped()
    n = g.frames * cycles
    t = np.arange(n + 1) / FPS
    phi = t / g.stride
    mid = g.duty / 2.0
    height = body.rest("base")[1] - g.extra_drop
    nominal = Pelvis(body, g, height)
    for _ in range(40):  # lower the pelvis only if the legs cannot reach their footprints
        pelvis = Pelvis(body, g, height)
        left = foot_track(body, g, pelvis, t, +1, nominal)
        right = foot_track(body, g, pelvis, t, -1, nominal)
        # Planted feet must be reached; a swinging foot beyond reach is simply pulled in by the IK.
        need = max(np.linalg.norm(foot.ankle - pelvis.hip(t, s), axis=-1)[foot.planted].max(initial=0.0)
                   for s, foot in (("l", left), ("r", right)))
        if need <= 0.99 * body.leg:
            break
        height -= 0.003
    root, g_base, psi = pelvis.at(t)
    face = heading(psi)
    hip_pos = {s: pelvis.hip(t, s) for s in "lr"}

    globals_ = {"base": g_base}
    rest_thigh = body.offset("l_knee")
    rest_shin = body.offset("l_ankle")
    for s, foot in (("l", left), ("r", right)):
        r_flat = heading(foot.yaw)
        pole = quat.rotate(r_flat, Z)
        g_thigh, g_shin, _ = two_bone(hip_pos[s], foot.ankle, body.thigh, body.shin, pole, rest_thigh, rest_shin, Z)
        g_foot = quat.multiply(r_flat, rot(X, -foot.pitch))
        globals_[f"{s}_hip"] = g_thigh
        globals_[f"{s}_knee"] = g_shin
        globals_[f"{s}_ankle"] = g_foot
        globals_[f"{s}_forefoot"] = quat.multiply(g_foot, rot(X, foot.toe))

    # Trunk: the thorax counter-rotates and sways toward the stance side; the head stays level.
    thorax = quat.multiply(face, quat.multiply(quat.multiply(
        rot(Y, g.trunk_rotation * np.cos(2.0 * np.pi * phi)),
        rot(Z, g.trunk_sway * np.cos(2.0 * np.pi * (phi - mid)) - pelvis.lean)), rot(X, g.trunk_lean)))
    spine = quat.multiply(quat.conjugate(g_base), thorax)
    part = power(spine, 1.0 / 3.0)
    g1 = quat.multiply(g_base, part)
    g2 = quat.multiply(g1, part)
    globals_.update(spine1=g1, spine2=g2, spine3=thorax)
    head = quat.multiply(face, rot(X, -g.head_pitch))
    neck = power(quat.multiply(quat.conjugate(thorax), head), 1.0 / 3.0)
    g4 = quat.multiply(thorax, neck)
    g5 = quat.multiply(g4, neck)
    globals_.update(spine4=g4, spine5=g5, skullbase=head)

    local = body.locals_from_globals(globals_, n + 1)
    arms(body, g, phi, local)
    motion = Motion(body.skeleton, FPS, local, root, name=name)
    facts = {"stance": np.stack((left.planted, right.planted), axis=1), "pelvis_height": height,
             "reach": need / body.leg}
    return motion, facts


def arms(body: Body, g: Gait, phi: np.ndarray, local: np.ndarray) -> None:
    """Write hanging, swinging arms into ``local`` (F, J, 4) in place (rotations relative to the chest)."""
    swing = g.arm_swing * np.cos(2.0 * np.pi * phi)  # + backward for the left arm at left heel strike
    for side, sign, arm_phase in (("l", 1.0, 1.0), ("r", -1.0, -1.0)):
        flex = -g.arm_forward + arm_phase * swing       # about +X: + moves the hand backward
        hang = rot(Z, -sign * (np.pi / 2.0 - g.arm_abduction))
        local[:, body.i(f"{side}_shoulder")] = quat.multiply(rot(X, flex), hang)
        forward = np.clip(-arm_phase * swing / max(g.arm_swing, 1e-9), -1.0, 1.0)
        bend = g.elbow + g.elbow_swing * 0.5 * (1.0 + forward)
        carry = rot(Z, sign * g.carrying_angle * 0.5)
        local[:, body.i(f"{side}_elbow")] = quat.multiply(rot(Y, -sign * bend), carry)
        local[:, body.i(f"{side}_wrist")] = rot(Z, -sign * np.radians(8.0) * np.ones_like(phi))
        curl = rot(Z, -sign * g.finger_curl * np.ones_like(phi))
        for finger in ("index", "middle", "ring", "pinky"):
            for k in (1, 2, 3):
                name = f"{side}_{finger}{k}"
                if name in body.skeleton.index:
                    local[:, body.i(name)] = curl
