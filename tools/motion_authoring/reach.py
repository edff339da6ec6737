"""Procedural reaches and grasps on the canonical skeleton, standing.

A reach starts from the standing pose (arms hanging), moves the wrist along a gently arched path
(minimum-jerk timing) to a target, holds it, and ends. The trunk leans and turns a little toward far
targets; the arm is solved by two-bone IK with the elbow down and out; the fingers open on the way.
Targets are given in the body frame (metres, +X the character's left, +Z forward, the ground at y = 0).
"""
from __future__ import annotations

import numpy as np

from infuse import quaternions as quat
from infuse.kinematics import forward_kinematics
from infuse.motion import Motion

from .body import X, Y, Z, Body, power, rot, smooth, two_bone
from .gait import FPS

FINGERS = ("index", "middle", "ring", "pinky")


def set_fingers(body: Body, local: np.ndarray, side: str, curl) -> None:
    """Curl the four fingers (radians per joint, (F,)) and the thumb of one hand, in place."""
    sign = 1.0 if side == "l" else -1.0
    curl = np.asarray(curl, dtype=np.float64)
    for finger in FINGERS:
        for k in (1, 2, 3):
            name = f"{side}_{finger}{k}"
            if name in body.skeleton.index:
                local[:, body.i(name)] = rot(Z, -sign * curl * (0.8 if k == 1 else 1.0))
    for k in (1, 2, 3):
        name = f"{side}_thumb{k}"
        if name in body.skeleton.index:
            local[:, body.i(name)] = rot(Y, sign * curl * 0.5)


def reach_motion(body: Body, stand: Motion, side: str, target: np.ndarray, name: str,
                 reach_s: float = 0.9, hold_s: float = 0.3) -> Motion:
    """A reach of hand ``side`` ("l"/"r") to ``target`` (3,) from the first frame of ``stand``."""
    n = int(round((reach_s + hold_s) * FPS))
    t = np.arange(n + 1) / FPS
    u = smooth(np.clip(t / reach_s, 0.0, 1.0))
    local = np.repeat(stand.local_rotations[:1], n + 1, axis=0).copy()
    root = np.repeat(stand.root_translations[:1], n + 1, axis=0)
    sk = body.skeleton
    sign = 1.0 if side == "l" else -1.0
    shoulder_rest = forward_kinematics(sk, local[:1], root[:1])[1][0, body.i(f"{side}_shoulder")]
    to = target - shoulder_rest
    dist = np.linalg.norm(to)
    # The trunk turns toward the target's side and leans toward far or low targets.
    azimuth = np.arctan2(to[0], max(to[2], 0.05))
    lean = np.radians(6.0) * np.clip((dist - 0.3) / 0.2, 0.0, 1.0) + np.radians(10.0) * np.clip((1.1 - target[1]) / 0.3, 0.0, 1.0)
    twist = 0.35 * azimuth
    trunk = quat.multiply(rot(Y, twist * u), rot(X, lean * u))
    part = power(trunk, 1.0 / 3.0)
    for j in ("spine1", "spine2", "spine3"):
        local[:, body.i(j)] = quat.multiply(local[:, body.i(j)], part)
    counter = power(quat.conjugate(trunk), 0.5)  # keep the head looking ahead-ish
    for j in ("spine4", "skullbase"):
        local[:, body.i(j)] = quat.multiply(local[:, body.i(j)], counter)
    g_rot, g_pos = forward_kinematics(sk, local, root)
    s_i, e_i, w_i = body.i(f"{side}_shoulder"), body.i(f"{side}_elbow"), body.i(f"{side}_wrist")
    start = g_pos[0, w_i]
    # The wrist's path: from where it hangs, arched forward and up, to the target.
    path = start + (target - start) * u[:, None]
    arch = np.sin(np.pi * u)[:, None] * np.array([0.0, 0.05, 0.08])
    goal = np.where((t < reach_s)[:, None], path + arch, target)
    shoulder = g_pos[:, s_i]
    rest_upper = body.offset(f"{side}_elbow")
    rest_lower = body.offset(f"{side}_forearm") + body.offset(f"{side}_wrist")
    # The elbow points down, out and back; at rest (the T-pose) it bends toward -Z.
    pole = np.broadcast_to(np.array([sign * 0.5, -1.0, -0.4]), goal.shape)
    g_upper, g_lower, _ = two_bone(shoulder, goal, float(np.linalg.norm(rest_upper)), float(np.linalg.norm(rest_lower)),
                                   pole, rest_upper, rest_lower, -Z, max_reach=0.995)
    parent = g_rot[:, sk.parents[s_i]]
    local[:, s_i] = quat.multiply(quat.conjugate(parent), g_upper)
    local[:, e_i] = quat.multiply(quat.conjugate(g_upper), g_lower)
    local[:, body.i(f"{side}_forearm")] = quat.identity((n + 1,))
    local[:, w_i] = rot(Z, -sign * np.radians(10.0) * (1.0 - u))  # the hand straightens as it reaches
    set_fingers(body, local, side, np.radians(15.0) * (1.0 - u) + np.radians(5.0) * u)
    return Motion(sk, FPS, quat.normalize(local), root, name=name)


def grasp_motion(body: Body, stand: Motion, side: str, name: str, close_s: float = 0.5) -> Motion:
    """The hand of ``side`` closing from open to a grasp over ``close_s`` seconds (arms as in ``stand``)."""
    n = int(round(close_s * FPS))
    t = np.arange(n + 1) / FPS
    local = np.repeat(stand.local_rotations[:1], n + 1, axis=0).copy()
    root = np.repeat(stand.root_translations[:1], n + 1, axis=0)
    set_fingers(body, local, side, np.radians(5.0) + np.radians(65.0) * smooth(t / close_s))
    return Motion(body.skeleton, FPS, quat.normalize(local), root, name=name)


def reach_targets(body: Body, side: str) -> list[tuple[str, np.ndarray]]:
    """A grid of named targets around the body for hand ``side``: 4 directions (across, ahead, toward
    the side, out to the side) x 3 heights x 2 distances from the shoulder."""
    sign = 1.0 if side == "l" else -1.0
    shoulder = body.rest(f"{side}_shoulder")
    out = []
    for az_name, az in (("across", -35.0), ("ahead", 0.0), ("side", 35.0), ("out", 70.0)):
        for el_name, el in (("low", -45.0), ("mid", -15.0), ("high", 20.0)):
            for r_name, r in (("near", 0.34), ("far", 0.47)):
                a, e = np.radians(az), np.radians(el)
                direction = np.array([sign * np.sin(a) * np.cos(e), np.sin(e), np.cos(a) * np.cos(e)])
                out.append((f"reach_{'left' if side == 'l' else 'right'}_{az_name}_{el_name}_{r_name}", shoulder + r * direction))
    return out
