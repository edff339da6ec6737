"""The foot-contact component: contact flags with hysteresis, heel and ball phases, plant positions,
pinning goals over frames, anchors, the heel's rise about a pinned ball, and the two-bone IK in world
turns that enforces the goals."""
from __future__ import annotations

import numpy as np

from infuse import footing
from infuse import quaternions as quat
from infuse.contacts import FootContacts, contact_phases, contact_runs, detect, hysteresis, position_noise, smoothed
from infuse.kinematics import forward_kinematics
from infuse.runtime import limb_ik
from infuse.skeleton import Skeleton

RNG = np.random.default_rng(11)


def _norm(v: np.ndarray) -> np.ndarray:
    return np.sqrt(np.sum(v * v, axis=0))


def test_hysteresis_lands_on_the_tight_threshold_and_lifts_on_the_loose_one():
    enter = np.array([0, 0, 1, 0, 0, 0, 1, 0, 0], bool)[:, None]
    stay = np.array([1, 1, 1, 1, 1, 0, 1, 1, 0], bool)[:, None]
    assert hysteresis(enter, stay)[:, 0].tolist() == [False, False, True, True, True, False, True, True, False]


def test_release_keeps_a_point_hovering_at_the_threshold_down():
    fps, leg = 30.0, 1.0
    frames = 60
    # Down, rising slowly to hover just over the landing height (6 cm) for a second, then up and away.
    y = np.concatenate((np.zeros(10), np.linspace(0.0, 0.062, 6)[1:], 0.062 + 0.003 * np.sin(np.arange(30)),
                        np.linspace(0.1, 0.4, 15)))
    points = np.stack((np.zeros(frames), y, np.zeros(frames)), axis=1)[:, None]
    tight = detect(points, fps, leg, ground=0.0, release=1.0)[:, 0]
    loose = detect(points, fps, leg, ground=0.0, release=1.25)[:, 0]
    # Without it the point lets go as it first passes 6 cm and lands again wherever it dips under.
    assert tight[:14].all() and not tight[14] and tight[15:45].any() and not tight[15:45].all()
    assert loose[:44].all() and not loose[46:].any()


def _walking_foot(fps: float, seconds: float = 4.4, period_s: float = 1.1, stance_s: float = 0.65) -> np.ndarray:
    """(F, 1, 3) a foot stepping 1.4 m every ``period_s`` (smooth swings 12 cm high), metres."""
    t = np.arange(int(round(seconds * fps))) / fps
    phase = np.clip((t % period_s - stance_s) / (period_s - stance_s), 0.0, 1.0)  # 0 in stance, 0..1 in swing
    x = 1.4 * (np.floor(t / period_s) + 0.5 * (1.0 - np.cos(np.pi * phase)))
    y = 0.12 * np.sin(np.pi * phase)
    return np.stack((x, y, np.zeros_like(t)), axis=1)[:, None]


def test_contacts_hold_on_noisy_positions_at_any_frame_rate():
    """1.5 cm of noise per axis and frame (what 1 degree of rotation noise on every joint does to a
    foot) finds the stances of the clean foot, each edge within 0.07 s, at 24 to 120 fps; a foot
    standing still with that noise stays down; clean positions are left as they are."""
    leg = 0.9
    for fps in (24.0, 30.0, 60.0, 120.0):
        clean = _walking_foot(fps)
        noisy = clean + RNG.normal(0.0, 0.015, clean.shape)
        assert abs(position_noise(noisy) - 0.015) < 0.003, fps
        np.testing.assert_array_equal(smoothed(clean, fps, 0.02)[0], clean)
        truth = contact_runs(detect(clean, fps, leg, ground=0.0))
        found = contact_runs(detect(noisy, fps, leg, ground=0.0))
        assert len(found) == len(truth) == 4, (fps, truth, found)
        edges = np.abs(np.array([r[1:] for r in found]) - np.array([r[1:] for r in truth]))
        assert edges.max() <= 0.07 * fps, (fps, truth, found)
        still = np.zeros_like(clean) + RNG.normal(0.0, 0.015, clean.shape)
        assert detect(still, fps, leg, ground=0.0).all(), fps


def test_heel_and_ball_phases_of_a_rolling_foot():
    # A stance: heel strike (ball 3 cm up), foot flat, heel off (ankle rising), toe off.
    frames, leg = 40, 0.9
    ankle = np.full(frames, 0.08)
    ball = np.full(frames, 0.02)
    ball[:8] = np.linspace(0.05, 0.02, 8)
    ankle[25:] = 0.08 + np.linspace(0.0, 0.06, 15)
    positions = np.zeros((frames, 4, 3))
    positions[:, 0, 1], positions[:, 1, 1] = ankle, ball
    positions[:, 2, 1], positions[:, 3, 1] = 0.3, 0.3  # the other foot in the air
    flags = np.zeros((frames, 4), bool)
    flags[:36, :2] = True
    found = FootContacts(np.arange(4), np.array([0, 0, 1, 1]), flags, 0.0, leg, np.zeros((frames, 2)))
    phases = contact_phases(found, positions)
    heel, down = phases[:, 0, 0], phases[:, 0, 1]
    assert heel[:25].all() and not heel[27:].any()
    assert not down[:5].any() and down[8:36].all() and not down[36:].any()
    assert not phases[:, 1].any()


def test_pinned_goals_hold_still_and_glide_between_contacts():
    frames = 120
    flags = np.zeros(frames, dtype=bool)
    flags[10:40] = flags[70:100] = True
    ball_flags = np.zeros(frames, dtype=bool)
    ball_flags[20:50] = ball_flags[80:110] = True
    # A foot that slides a little while planted and swings 4 cm a frame in between.
    step = np.where(flags | ball_flags, 0.001, 0.04)
    path = np.stack((0.003 * np.sin(np.arange(frames) / 3), 0.08 + np.where(flags, 0.0, 0.05), np.cumsum(step)))
    path += RNG.normal(scale=0.001, size=path.shape)
    ball = path + np.array([[0.0], [-0.06], [0.138]])
    ankle_goal, ball_goal = footing.pinned(path, flags, 0.08, ball, ball_flags, 0.02, 0.15, blend_frames=4)
    assert ball_goal is not None
    for a, b in ((10, 40), (70, 100)):
        assert np.ptp(ankle_goal[:, a:b], axis=1).max() < 1e-12 and np.allclose(ankle_goal[1, a:b], 0.08)
    for a, b in ((20, 50), (80, 110)):
        assert np.ptp(ball_goal[:, a:b], axis=1).max() < 1e-12 and np.allclose(ball_goal[1, a:b], 0.02)
    both = flags & ball_flags
    assert np.allclose(_norm(ankle_goal[:, both] - ball_goal[:, both]), 0.15)
    assert np.allclose(_norm(ankle_goal[:, ball_flags] - ball_goal[:, ball_flags]), 0.15)
    # No pops: no frame moves much further than the swing does.
    assert _norm(np.diff(ankle_goal, axis=1)).max() < 2.0 * _norm(np.diff(path, axis=1)).max()
    assert _norm(np.diff(ball_goal, axis=1)).max() < 2.0 * _norm(np.diff(ball, axis=1)).max()


def test_plant_positions_and_heights():
    path = RNG.normal(size=(3, 20))
    flags = np.zeros(20, bool)
    flags[4:9] = True
    pins = footing.plant_positions(path, flags, 0.05)
    assert np.allclose(pins[[0, 2], 4:9], path[[0, 2], 4:9].mean(axis=1, keepdims=True)) and np.allclose(pins[1, 4:9], 0.05)
    assert np.array_equal(pins[:, ~flags], path[:, ~flags])
    heights = np.linspace(0.0, 1.0, 20)
    assert footing.planted_height(heights, flags) == np.median(heights[4:9])
    assert footing.planted_height(heights, np.zeros(20, bool)) == np.percentile(heights, 5.0)


def test_anchors_follow_the_more_planted_point():
    heel = np.array([[0.0, 0.0], [1.0, 1.0], [0.6, 0.6], [0.2, 0.2]])
    ball = np.array([[0.3, 0.3], [0.0, 0.0], [0.9, 0.9], [0.8, 0.8]])
    out = footing.anchors(heel, ball, np.array([True, False]))
    assert out[:, 0].tolist() == [footing.FREE, footing.ANKLE, footing.BALL, footing.BALL]
    assert out[:, 1].tolist() == [footing.FREE, footing.ANKLE, footing.ANKLE, footing.ANKLE]


def test_heel_rises_about_the_ball_only_as_far_as_the_leg_needs():
    frames = 40
    hip = np.tile([0.0, 0.8, 0.0], (frames, 1))
    knee = hip + [0.0, -0.42, 0.02]
    ankle = knee + [0.0, -0.42, -0.02]
    leg = np.stack((hip, knee, ankle), axis=1)
    ball_goal = np.stack((np.zeros(frames), np.zeros(frames), np.linspace(0.42, 0.7, frames)), axis=-1)
    ankle_goal = ball_goal + [0.0, 0.06, -0.13]
    rotation = np.tile([0.0, 0.0, 0.0, 1.0], (frames, 1))
    out, rise = footing.heel_rise(rotation, leg, ankle_goal, ball_goal)
    length = footing.REACH * 2.0 * np.hypot(0.42, 0.02)
    near = np.linalg.norm(ankle_goal - hip, axis=-1) <= length
    assert np.allclose(out[near], ankle_goal[near]) and not rise[near].any()
    # Farther, the ankle turns about the ball (its distance from it kept) by whole degrees.
    assert np.allclose(np.linalg.norm(out - ball_goal, axis=-1), np.linalg.norm(ankle_goal - ball_goal, axis=-1))
    back = quat.rotate(quat.from_rotvec(-rise), out - ball_goal)
    assert np.allclose(back, ankle_goal - ball_goal, atol=1e-9)
    degrees = np.degrees(np.linalg.norm(rise, axis=-1))
    assert np.allclose(degrees, np.round(degrees)) and (degrees[~near] >= 1.0).all()

    def distance(turn_deg: np.ndarray) -> np.ndarray:
        """Each frame's ankle distance from the hip with the heel risen ``turn_deg`` about the ball."""
        turn = rise / np.maximum(np.linalg.norm(rise, axis=-1, keepdims=True), 1e-12) * np.radians(turn_deg)[:, None]
        return np.linalg.norm(ball_goal + quat.rotate(quat.from_rotvec(turn), ankle_goal - ball_goal) - hip, axis=-1)

    reach = distance(degrees)
    within = ~near & (reach <= length + 1e-9)
    beyond = ~near & ~within
    assert within.sum() >= 3 and beyond.sum() > 3
    # Within reach by the smallest rise that gets there; beyond it by the rise past which a further
    # degree brings the ankle toward the hip by less than RISE_GAIN of the arc it travels.
    assert (distance(degrees - 1.0)[within] > length).all()
    arc_m = footing.RISE_GAIN * np.linalg.norm(ankle_goal - ball_goal, axis=-1) * np.radians(1.0)

    def cost(turn_deg: np.ndarray) -> np.ndarray:
        return np.maximum(distance(turn_deg) - length, 0.0) + arc_m * turn_deg

    assert (cost(degrees - 1.0)[beyond] >= cost(degrees)[beyond] - 1e-12).all()
    assert (cost(np.minimum(degrees + 1.0, 60.0))[beyond] >= cost(degrees)[beyond] - 1e-12).all()
    # Continuous as the ball moves 7 mm a frame away from the hip: at most 4 degrees a frame, where the
    # smallest reaching rise went 17, 24, 30 degrees as its arc's closest point passed out of reach.
    assert np.abs(np.diff(degrees)).max() <= 4.0 + 1e-9, degrees


def _limb(frames: int, bend: float = 0.4) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    root = np.zeros((frames, 3))
    middle = np.tile([0.0, -0.45, 0.0], (frames, 1))
    end = middle + [0.0, -0.44 * np.cos(bend), -0.44 * np.sin(bend)]
    return root, middle, end


def test_only_feet_on_their_ball_have_their_heel_risen():
    frames = 12
    hip = np.tile([0.0, 0.8, 0.0], (frames, 1))
    knee = hip + [0.0, -0.42, 0.02]
    leg = np.stack((hip, knee, knee + [0.0, -0.42, -0.02]), axis=1)
    ball_goal = np.stack((np.zeros(frames), np.zeros(frames), np.linspace(0.56, 0.7, frames)), axis=-1)
    ankle_goal = ball_goal + [0.0, 0.06, -0.13]  # all beyond reach: every heel on its ball rises
    rotation = np.tile([0.0, 0.0, 0.0, 1.0], (frames, 1))
    on_ball = np.arange(frames) % 3 != 0
    out, rise = footing.heel_rise(rotation, leg, ankle_goal, ball_goal, on_ball=on_ball)
    whole, whole_rise = footing.heel_rise(rotation, leg, ankle_goal, ball_goal)
    assert (np.linalg.norm(whole_rise, axis=-1) > 0.0).all()
    assert np.array_equal(out[on_ball], whole[on_ball]) and np.array_equal(rise[on_ball], whole_rise[on_ball])
    assert np.array_equal(out[~on_ball], ankle_goal[~on_ball]) and not rise[~on_ball].any()


def test_goals_beyond_reach_are_drawn_in_smoothly_no_nearer_than_the_animated_ankle():
    frames = 201
    hip = np.tile([0.0, 0.9, 0.0], (frames, 1))
    knee = hip + [0.0, -0.4, 0.12]
    ankle = knee + [0.0, -0.4, -0.12]  # the animated ankle 0.8 m from the hip: 0.958 of the leg's length
    leg = np.stack((hip, knee, ankle), axis=1)
    length = 2.0 * np.hypot(0.4, 0.12)
    direction = np.array([0.0, -0.8, 0.6])
    share = np.linspace(0.9, 1.1, frames)  # goals from 0.9 to 1.1 of the length away, one direction
    goal = hip + share[:, None] * length * direction
    out = footing.within_reach(goal, leg)
    away = np.linalg.norm(out - hip, axis=-1) / length
    assert np.allclose(np.cross(out - hip, direction), 0.0)  # along the line from the hip
    inside = share <= footing.SOFT_REACH
    assert np.allclose(out[inside], goal[inside]) and (away[~inside] < share[~inside]).all()
    assert (away <= footing.REACH + 1e-12).all() and away[-1] > footing.REACH - 1e-3
    # Continuous and never turning back: no step larger than the goal's own.
    steps = np.diff(away)
    assert (steps >= 0.0).all() and (steps <= np.diff(share) + 1e-12).all()
    # An animated ankle farther than REACH is the bound: nearer goals stay, farther ones are held at it.
    half = length / 2.0
    straight = np.stack((hip, hip + [0.0, -0.997 * half, half * np.sqrt(1.0 - 0.997**2)], hip + [0.0, -0.997 * length, 0.0]), axis=1)
    away = np.linalg.norm(footing.within_reach(goal, straight) - hip, axis=-1) / length
    assert np.allclose(away, np.minimum(share, 0.997))


def test_turn_limb_meets_reachable_goals_as_solve_limb_does():
    frames = 400
    root, middle, end = _limb(frames)
    direction = RNG.normal(size=(frames, 3))
    direction[:, 1] = -np.abs(direction[:, 1]) - 0.5
    goal = direction / np.linalg.norm(direction, axis=1, keepdims=True) * RNG.uniform(0.15, 0.88, size=(frames, 1))
    axis, flexion = limb_ik.hinge_axes(root, middle, end, np.tile([1.0, 0.0, 0.0], (frames, 1)))
    assert np.allclose(axis, [1.0, 0.0, 0.0]) and np.allclose(flexion, 0.4)
    solution = limb_ik.turn_limb(root, middle, end, goal, axis, flexion)
    assert solution.reachable.all() and solution.residual.max() < 1e-9
    knee = root + quat.rotate(solution.root, middle - root)
    assert np.allclose(np.linalg.norm(knee - root, axis=1), 0.45) and np.allclose(np.linalg.norm(solution.end - knee, axis=1), 0.44)
    # The same solution as the IK on local rotations: a hip, knee and ankle chain under a pelvis.
    skeleton = Skeleton(["pelvis", "hip", "knee", "ankle"], np.array([-1, 0, 1, 2]),
                        np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 0.0], middle[0], end[0] - middle[0]]), quat.identity((4,)))
    local = quat.identity((frames, 4))
    base = np.zeros((frames, 3))  # the pelvis, and the hip on it, at the origin
    left = limb_ik.solve_limb(skeleton, local, base, None, (1, 2, 3), goal)
    _, positions = forward_kinematics(skeleton, local, base)
    assert left.max() < 1e-9
    assert np.allclose(positions[:, 2], knee, atol=1e-9) and np.allclose(positions[:, 3], solution.end, atol=1e-9)
    # A goal where the end already is moves nothing.
    still = limb_ik.turn_limb(root, middle, end, end, axis, flexion)
    assert np.allclose(still.root, [0.0, 0.0, 0.0, 1.0], atol=1e-9) and np.allclose(still.end, end, atol=1e-9)


def test_turn_limb_stretches_toward_unreachable_goals_without_hyperextending():
    frames = 50
    root, middle, end = _limb(frames)
    goal = np.tile([0.3, -1.2, 0.4], (frames, 1))
    axis, flexion = limb_ik.hinge_axes(root, middle, end, np.tile([1.0, 0.0, 0.0], (frames, 1)))
    solution = limb_ik.turn_limb(root, middle, end, goal, axis, flexion, min_flexion=np.radians(1.0))
    reach = np.linalg.norm(solution.end - root, axis=1)
    straight = np.sqrt(0.45 ** 2 + 0.44 ** 2 + 2 * 0.45 * 0.44 * np.cos(np.radians(1.0)))
    assert not solution.reachable.any() and np.allclose(reach, straight, atol=1e-6)
    pointing = np.sum((solution.end - root) * (goal - root), axis=1) / (reach * np.linalg.norm(goal - root, axis=1))
    assert np.all(pointing > 1 - 1e-9)
