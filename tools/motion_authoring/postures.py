"""Procedural standing and seated postures on the canonical skeleton, each a looping idle.

A posture is a stance of the whole body: the pelvis over the feet (the weight on both legs or on
one, the free side's hip lower and its knee bent), the trunk upright or leaning (the hips going back
as the trunk leans forward, the head keeping the gaze ahead), and the arms hanging or placed:
crossed on the chest, hands on the hips, behind the back or clasped in front. A seated posture sits
on a seat of the body's own knee height: the hip joints at the knees' height, the thighs level on the
seat, the shins upright and the feet flat; its hands rest on the thighs or the lap. Every posture,
standing or seated, has its feet on the same footprints, so any two blend with the feet planted (from
standing to seated the hips go down and back).

Its idle, over one loop of :data:`LOOP_S` seconds: a slow weight shift from side to side, a smaller
sway forward and back and a slight turn of the pelvis, the trunk and head following a little. No
breathing: the breathing controller adds it on top. Legs by two-bone IK onto the footprints; placed
arms by two-bone IK onto wrist places given in the chest's or the pelvis's frame (so they follow the
trunk) or in the thigh's (so a hand lies on it), the hand turned to a finger direction and palm normal,
the forearm taking the hand's twist about itself. Arm places are written for the left arm (+X out to
the hand's side, +Y up, +Z forward; in a thigh's frame +Z runs from the hip to the knee and +Y is up
off the thigh); the right arm mirrors them unless given its own.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from infuse import quaternions as quat
from infuse.kinematics import forward_kinematics
from infuse.motion import Motion

from .body import X, Y, Z, Body, frame_rotation, power, rot, two_bone
from .gait import FPS, Gait, arms
from .gestures import SHAPES, _set_fingers, _twist

#: Seconds of one idle loop (the first and last frames are the same pose).
LOOP_S = 8.0
#: Half the distance between the ankles, metres, and the feet's toe-out, radians.
FOOT_HALF_WIDTH_M = 0.11
TOE_OUT = np.radians(7.0)
#: How far the pelvis moves over a leg that takes the whole weight, metres, and how far its free side drops (roll).
WEIGHT_SHIFT_M = 0.05
WEIGHT_ROLL = np.radians(4.0)
#: Idle amplitudes: side-to-side and forward-back pelvis sway (metres), pelvis turn (radians).
SWAY_SIDE_M = 0.012
SWAY_FORWARD_M = 0.005
SWAY_TURN = np.radians(1.2)
#: The longest a standing leg may be, leg lengths (the knee never locks fully straight).
LEG_REACH = 0.985
#: A seated pelvis's tilt back (radians) and its idle turn's share of a standing one's.
SEATED_TILT = np.radians(-10.0)
SEATED_TURN = 0.3
#: A seated trunk's idle sway from side to side (radians; half as much forward and back): the pelvis stays on the seat.
SEATED_SWAY = np.radians(4.5)
#: The lexeme every seated posture carries (the first seated posture is BML 1.0's ``SITTING`` stance alone).
SEATED = "SEATED"


@dataclass(frozen=True)
class ArmPlace:
    """Where one hand rests: ``wrist`` (3,) metres from the ``frame`` joint (``"chest"``: spine3,
    ``"pelvis"``: base, ``"thigh"``: the arm's side's hip joint, +Z toward its knee), in that frame and
    left-arm coordinates; the hand's ``fingers``
    direction and ``palm`` normal in the same frame; ``elbow`` the direction the elbow bends toward;
    ``shape`` a finger shape of :data:`~.gestures.SHAPES`."""

    frame: str
    wrist: tuple
    fingers: tuple
    palm: tuple
    elbow: tuple
    shape: str = "relaxed"


@dataclass(frozen=True)
class PostureSpec:
    """A posture: ``weight`` on the legs (-1 all on the right, +1 all on the left), the trunk's ``lean``
    (radians, + forward), the ``arms`` (side ``"l"``/``"r"`` -> :class:`ArmPlace`; a side left out
    hangs), the ``sway`` scale of its idle, whether it is ``seated`` and the BML ``lexemes`` it realizes."""

    name: str
    lexemes: tuple
    weight: float = 0.0
    lean: float = 0.0
    arms: dict = field(default_factory=dict)
    sway: float = 1.0
    seated: bool = False


def _both(place: ArmPlace) -> dict:
    return {"l": place, "r": place}


#: The postures of the pack. BML 1.0 names a posture by a stance and pose lexemes; the lexemes here are
#: those names, SmartBody's and other realizers' words for the same stances.
SPECS = (
    PostureSpec("neutral", ("NEUTRAL", "STANDING", "STAND", "IDLE", "ARMS_NEUTRAL", "LEGS_NEUTRAL", "ARMS_DOWN",
                            "REST", "NEUTRALPOSITION", "DEFAULT")),
    PostureSpec("weight_left", ("WEIGHT_LEFT", "WEIGHT_ON_LEFT_LEG", "LEFT_LEG", "STAND_LEFT", "HIP_SHIFT_LEFT",
                                "CONTRAPPOSTO_LEFT", "CONTRAPPOSTO"), weight=1.0, sway=0.5),
    PostureSpec("weight_right", ("WEIGHT_RIGHT", "WEIGHT_ON_RIGHT_LEG", "RIGHT_LEG", "STAND_RIGHT", "HIP_SHIFT_RIGHT",
                                 "CONTRAPPOSTO_RIGHT"), weight=-1.0, sway=0.5),
    PostureSpec("arms_crossed", ("ARMS_CROSSED", "CROSSED_ARMS", "ARMS_FOLDED", "FOLDED_ARMS", "CROSS_ARMS", "ARMSCROSSED",
                                 "LISTENING", "LISTEN"),
                arms={"l": ArmPlace("chest", (-0.05, -0.02, 0.28), (-1.0, -0.25, -0.45), (0.0, 0.0, -1.0), (0.6, -1.0, 0.35)),
                      "r": ArmPlace("chest", (-0.05, -0.095, 0.245), (-1.0, 0.05, -0.55), (0.0, 0.4, -1.0), (0.6, -1.0, 0.3))}),
    PostureSpec("hands_on_hips", ("HANDS_ON_HIP", "HANDS_ON_HIPS", "ARMS_AKIMBO", "AKIMBO", "HANDS_HIPS", "HIPS"),
                arms=_both(ArmPlace("pelvis", (0.265, 0.13, -0.04), (-0.2, -0.5, 0.8), (-1.0, 0.0, 0.0), (1.0, -0.05, -0.45),
                                    "open"))),
    PostureSpec("hands_behind_back", ("HANDS_BEHIND_BACK", "ARMS_BEHIND_BACK", "HANDS_BEHIND", "BEHIND_BACK", "HANDS_BACK"),
                arms={"l": ArmPlace("pelvis", (0.05, 0.1, -0.16), (-0.7, -0.7, -0.05), (0.0, 0.0, 1.0), (0.9, -0.2, -0.5)),
                      "r": ArmPlace("pelvis", (0.03, 0.065, -0.15), (-0.5, -0.85, 0.0), (0.0, 0.0, -1.0), (0.9, -0.2, -0.5))}),
    PostureSpec("hands_clasped", ("HANDS_CLASPED", "HANDS_TOGETHER", "CLASPED_HANDS", "HANDS_FOLDED", "HANDS_IN_FRONT",
                                  "HANDSTOGETHER", "CLASPED"),
                arms={"l": ArmPlace("pelvis", (0.07, 0.05, 0.225), (-0.6, -0.75, 0.1), (0.0, 0.0, -1.0), (0.7, -1.0, -0.25)),
                      "r": ArmPlace("pelvis", (0.055, 0.065, 0.255), (-0.65, -0.7, 0.1), (0.0, 0.0, -1.0), (0.7, -1.0, -0.25))}),
    PostureSpec("leaning_forward", ("LEANING_FORWARD", "LEAN_FORWARD", "LEANING_IN", "LEAN_IN", "FORWARD", "BENT_FORWARD",
                                    "INTERESTED"), lean=np.radians(14.0), sway=0.7),
    PostureSpec("leaning_back", ("LEANING_BACKWARD", "LEANING_BACK", "LEAN_BACK", "LEAN_BACKWARD", "BACKWARD", "RECLINE",
                                 "BODYRECLINE", "RECLINED"), lean=np.radians(-9.0), sway=0.7),
    # Seated: a standing posture's lexeme names the seated posture like it when the stance is SITTING.
    PostureSpec("sitting", ("SITTING", SEATED, "SIT", "SITTING_UPRIGHT", "SIT_UPRIGHT", "SEATED_UPRIGHT", "HANDS_ON_THIGHS",
                            "HANDS_ON_KNEES", "NEUTRAL", "ARMS_NEUTRAL", "REST", "IDLE", "DEFAULT"), sway=0.5, seated=True,
                arms=_both(ArmPlace("thigh", (0.005, 0.12, 0.2), (-0.1, 0.0, 1.0), (0.0, -1.0, 0.0), (0.6, -0.3, -1.0), "open"))),
    PostureSpec("sitting_hands_on_lap", ("HANDS_ON_LAP", "HANDS_IN_LAP", SEATED, "LAP", "REST_LAP", "UNDERTABLE",
                                         "UNDER_TABLE", "HANDS_UNDER_TABLE", "HANDS_CLASPED", "HANDS_TOGETHER", "HANDS_FOLDED",
                                         "HANDS_IN_FRONT"), sway=0.5, seated=True,
                arms=_both(ArmPlace("thigh", (-0.035, 0.1, 0.22), (-0.45, -0.05, 0.9), (0.0, -1.0, 0.0), (0.7, -0.3, -1.0), "open"))),
    PostureSpec("sitting_leaning_forward", ("SITTING_LEANING_FORWARD", SEATED, "SIT_LEANING_FORWARD", "SEATED_LEANING_FORWARD",
                                            "FOREARMS_ON_THIGHS", "ELBOWS_ON_KNEES", "SITTING_FORWARD", "LEANING_FORWARD",
                                            "LEAN_FORWARD", "LEANING_IN", "LEAN_IN", "FORWARD", "INTERESTED"),
                lean=np.radians(68.0), sway=0.6, seated=True,
                arms=_both(ArmPlace("thigh", (-0.03, 0.14, 0.5), (-0.45, -0.55, 0.7), (0.2, -1.0, 0.0), (0.6, -0.6, -1.2)))),
)


def _mirror(v: np.ndarray, side: str) -> np.ndarray:
    """Left-arm coordinates (..., 3) to ``side``'s: the right arm's +X is the body's -X."""
    v = np.asarray(v, dtype=np.float64)
    return v if side == "l" else v * np.array([-1.0, 1.0, 1.0])


def footprints(body: Body) -> dict[str, tuple[np.ndarray, float]]:
    """Each foot's flat ankle position (3,) and yaw (radians) on the ground: the same for every posture."""
    z = body.rest("l_ankle")[2] - 0.02
    return {s: (np.array([sign * FOOT_HALF_WIDTH_M, body.ankle_height, z]), sign * TOE_OUT)
            for s, sign in (("l", 1.0), ("r", -1.0))}


def _pelvis(spec: PostureSpec, t: np.ndarray, height: float) -> tuple[np.ndarray, np.ndarray]:
    """Pelvis positions (F, 3) and global rotations (F, 4) of ``spec`` at times ``t`` (seconds)."""
    w = 2.0 * np.pi * t / LOOP_S
    side = spec.weight * WEIGHT_SHIFT_M + spec.sway * SWAY_SIDE_M * np.sin(w)
    forward = -0.2 * spec.lean + spec.sway * SWAY_FORWARD_M * np.sin(2.0 * w + 0.9)
    # The hip over the loaded leg rises; the pelvis drops to the free side, and follows the sway a little.
    roll = spec.weight * WEIGHT_ROLL + 0.5 * WEIGHT_ROLL * (side - spec.weight * WEIGHT_SHIFT_M) / WEIGHT_SHIFT_M
    turn = spec.sway * SWAY_TURN * np.sin(w + 2.1)
    tilt = 0.35 * spec.lean + np.radians(3.0)
    pos = np.stack((side, np.full_like(t, height), forward), axis=-1)
    return pos, quat.multiply(quat.multiply(rot(Y, turn), rot(Z, roll)), rot(X, np.full_like(t, tilt)))


def _seated_pelvis(body: Body, spec: PostureSpec, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A seated pelvis's positions (F, 3) and global rotations (F, 4) at times ``t`` (seconds): the hip joints
    at the knees' height (the shins upright over the footprints, the thighs level on the seat), tilted back
    by :data:`SEATED_TILT` and forward with the trunk's lean, turning a little with the idle."""
    w = 2.0 * np.pi * t / LOOP_S
    ankle = footprints(body)["l"][0]
    hips = np.array([0.0, ankle[1] + body.shin, ankle[2] - body.thigh])
    turn = SEATED_TURN * spec.sway * SWAY_TURN * np.sin(w + 2.1)
    base_rot = quat.multiply(rot(Y, turn), rot(X, np.full_like(t, SEATED_TILT + 0.35 * spec.lean)))
    rest_hips = 0.5 * (body.rest("l_hip") + body.rest("r_hip")) - body.rest("base")
    return hips - quat.rotate(base_rot, rest_hips), base_rot


def _legs(body: Body, base_pos: np.ndarray, base_rot: np.ndarray, globals_: dict) -> float:
    """Leg global rotations onto the footprints, written into ``globals_``; returns the longest hip-to-ankle
    distance over the leg's length."""
    need = 0.0
    for s, (ankle, yaw) in footprints(body).items():
        hip = base_pos + quat.rotate(base_rot, body.rest(f"{s}_hip") - body.rest("base"))
        goal = np.broadcast_to(ankle, hip.shape)
        need = max(need, float(np.linalg.norm(goal - hip, axis=-1).max()) / body.leg)
        r_flat = rot(Y, np.full(len(hip), yaw))
        g_thigh, g_shin, _ = two_bone(hip, goal, body.thigh, body.shin, quat.rotate(r_flat, Z), body.offset("l_knee"),
                                      body.offset("l_ankle"), Z)
        globals_.update({f"{s}_hip": g_thigh, f"{s}_knee": g_shin, f"{s}_ankle": r_flat, f"{s}_forefoot": r_flat})
    return need


def _trunk(spec: PostureSpec, t: np.ndarray, base_rot: np.ndarray, globals_: dict) -> None:
    """Spine, neck and head global rotations into ``globals_``: the thorax leans by ``spec.lean``, counters
    the pelvis's roll and sways a little (seated, by :data:`SEATED_SWAY`); the head turns back most of the
    lean to look ahead."""
    w = 2.0 * np.pi * t / LOOP_S
    roll = -0.7 * spec.weight * WEIGHT_ROLL + spec.sway * np.radians(0.6) * np.sin(3.0 * w + 0.4)
    twist = -0.5 * spec.sway * SWAY_TURN * np.sin(w + 2.1)
    pitch = np.full_like(t, spec.lean)
    if spec.seated:
        roll = roll + spec.sway * SEATED_SWAY * np.sin(w)
        pitch = pitch + 0.5 * spec.sway * SEATED_SWAY * np.sin(2.0 * w + 0.9)
    thorax = quat.multiply(quat.multiply(rot(Y, twist), rot(Z, roll)), rot(X, pitch))
    part = power(quat.multiply(quat.conjugate(base_rot), thorax), 1.0 / 3.0)
    g1 = quat.multiply(base_rot, part)
    g2 = quat.multiply(g1, part)
    head = rot(X, np.full_like(t, 0.3 * spec.lean + np.radians(2.0)))
    neck = power(quat.multiply(quat.conjugate(thorax), head), 1.0 / 3.0)
    g4 = quat.multiply(thorax, neck)
    g5 = quat.multiply(g4, neck)
    globals_.update(spine1=g1, spine2=g2, spine3=thorax, spine4=g4, spine5=g5, skullbase=head)


def _place_arm(body: Body, local: np.ndarray, root: np.ndarray, side: str, place: ArmPlace) -> None:
    """Solve arm ``side`` onto ``place`` in ``local`` (F, J, 4), in place: two-bone IK to the wrist, the
    hand turned as given, the forearm taking the hand's twist about it, the fingers shaped."""
    sk = body.skeleton
    g_rot, g_pos = forward_kinematics(sk, local, root)
    if place.frame == "thigh":
        hip, knee = g_pos[:, body.i(f"{side}_hip")], g_pos[:, body.i(f"{side}_knee")]
        along = (knee - hip) / np.linalg.norm(knee - hip, axis=-1, keepdims=True)
        across = quat.rotate(g_rot[:, body.i("base")], X)
        across = across - np.sum(across * along, axis=-1, keepdims=True) * along
        across /= np.linalg.norm(across, axis=-1, keepdims=True)
        origin = hip
        r_frame = quat.from_matrix(np.stack((across, np.cross(along, across), along), axis=-1))
    else:
        frame = body.i("spine3" if place.frame == "chest" else "base")
        origin, r_frame = g_pos[:, frame], g_rot[:, frame]
    wrist = origin + quat.rotate(r_frame, _mirror(place.wrist, side))
    pole = quat.rotate(r_frame, _mirror(place.elbow, side))
    s_i, e_i, f_i, w_i = (body.i(f"{side}_{j}") for j in ("shoulder", "elbow", "forearm", "wrist"))
    rest_upper = body.offset(f"{side}_elbow")
    rest_lower = body.offset(f"{side}_forearm") + body.offset(f"{side}_wrist")
    g_upper, g_lower, _ = two_bone(g_pos[:, s_i], wrist, float(np.linalg.norm(rest_upper)), float(np.linalg.norm(rest_lower)),
                                   pole, rest_upper, rest_lower, -Z, max_reach=0.995)
    fingers = quat.rotate(r_frame, _mirror(place.fingers, side))
    palm = quat.rotate(r_frame, _mirror(place.palm, side))
    g_hand = frame_rotation(body.offset(f"{side}_middle1"), -Y, fingers, palm)
    relative = quat.multiply(quat.conjugate(g_lower), g_hand)  # the hand in the forearm's frame
    twist = _twist(relative, rest_lower / np.linalg.norm(rest_lower))
    local[:, s_i] = quat.multiply(quat.conjugate(g_rot[:, sk.parents[s_i]]), g_upper)
    local[:, e_i] = quat.multiply(quat.conjugate(g_upper), g_lower)
    local[:, f_i] = twist
    local[:, w_i] = quat.multiply(quat.conjugate(twist), relative)
    _set_fingers(body, local, side, np.broadcast_to(np.asarray(SHAPES[place.shape]), (len(local), 5)))


def posture_motion(body: Body, spec: PostureSpec, name: str | None = None) -> Motion:
    """The looping idle of ``spec``: :data:`LOOP_S` seconds at :data:`~.gait.FPS`, last frame = first."""
    n = int(round(LOOP_S * FPS))
    t = np.arange(n + 1) / FPS
    height = body.rest("base")[1] - 0.012
    for _ in range(60):  # lower the pelvis until both legs reach their footprints with the knees unlocked
        base_pos, base_rot = _seated_pelvis(body, spec, t) if spec.seated else _pelvis(spec, t, height)
        globals_ = {"base": base_rot}
        if _legs(body, base_pos, base_rot, globals_) <= LEG_REACH:
            break
        height -= 0.002
    _trunk(spec, t, base_rot, globals_)
    local = body.locals_from_globals(globals_, n + 1)
    # Hanging arms hang plumb: the shoulders take back the trunk's lean.
    arms(body, Gait(arm_swing=0.0, arm_forward=np.radians(3.0) + spec.lean, arm_abduction=np.radians(9.0),
                    elbow=np.radians(14.0), finger_curl=np.radians(18.0)), t / LOOP_S, local)
    for side, place in spec.arms.items():
        _place_arm(body, local, base_pos, side, place)
    return Motion(body.skeleton, FPS, quat.normalize(local), base_pos, name=name or spec.name)


def posture_clips(body: Body) -> list[tuple[PostureSpec, Motion]]:
    """Every posture's looping idle, named by the posture."""
    return [(spec, posture_motion(body, spec)) for spec in SPECS]
