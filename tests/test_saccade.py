"""Saccades: 10,000 draws of the model against its published distributions (KS tests), and the output
motion of a real character following the schedule, pausing while it speaks."""
from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from infuse import quaternions as quat
from infuse.runtime import Runtime
from infuse.runtime.swing import swing_angles
from infuse_saccade import MODES, Saccades, magnitude_cdf
from infuse_saccade.model import (
    DIRECTION_PERCENT, DURATION_BASE_S, DURATION_PER_DEG_S, FRAMES_PER_S, MIN_INTERVAL_FRAMES, SaccadeSchedule,
    direction_cdf,
)

from runtime_characters import corpus_character

SAMPLES = 10_000
ALPHA = 0.001  # a correct generator fails one of these tests about once in a thousand runs per test


@pytest.fixture(scope="module", params=sorted(MODES))
def schedule(request):
    return request.param, SaccadeSchedule(MODES[request.param], seed=(7, len(request.param))).sample(SAMPLES)


def test_magnitudes_follow_the_model(schedule):
    mode, s = schedule
    limit = MODES[mode].max_magnitude_deg
    a = s.magnitudes[:SAMPLES]
    assert a.min() >= -6.9 * np.log(15.0 / 15.7) - 1e-9 and a.max() <= limit
    # The clamp puts every draw above the limit on it: its share is P(f < 15.7 exp(-limit / 6.9)).
    assert np.mean(a == limit) == pytest.approx(15.7 * np.exp(-limit / 6.9) / 15.0, abs=0.01)
    below = a[a < limit]
    cdf = lambda x: magnitude_cdf(x, np.inf) / magnitude_cdf(limit - 1e-12, np.inf)  # noqa: E731
    assert stats.kstest(below, cdf).pvalue > ALPHA


def test_directions_follow_the_published_bins(schedule):
    _, s = schedule
    d = s.directions[:SAMPLES]
    shifted = np.where(d >= 337.5, d - 360.0, d)  # measured from the right bin's lower edge
    assert stats.kstest(shifted, direction_cdf).pvalue > ALPHA
    counts = np.histogram(shifted, bins=np.arange(-22.5, 360.0, 45.0))[0]
    expected = SAMPLES * DIRECTION_PERCENT / DIRECTION_PERCENT.sum()
    assert stats.chisquare(counts, expected).pvalue > ALPHA


def test_intervals_follow_the_gaussians_of_each_gaze_state(schedule):
    mode, s = schedule
    m = MODES[mode]
    mutual = s.mutual[:SAMPLES]
    assert stats.binomtest(int(mutual.sum()), SAMPLES, m.mutual_fraction).pvalue > ALPHA
    frames = s.intervals[:SAMPLES] * FRAMES_PER_S
    for state, (mean, spread) in ((True, m.mutual_frames), (False, m.away_frames)):
        x = frames[mutual == state]
        law = stats.truncnorm((MIN_INTERVAL_FRAMES - mean) / spread, np.inf, loc=mean, scale=spread)
        assert stats.kstest(x, law.cdf).pvalue > ALPHA, (mode, state)
    assert np.allclose(np.diff(s.times[:SAMPLES]), s.intervals[:SAMPLES - 1])


def test_durations_grow_with_amplitude(schedule):
    mode, s = schedule
    limit = MODES[mode].max_magnitude_deg
    assert np.allclose(s.durations, DURATION_BASE_S + DURATION_PER_DEG_S * s.amplitudes)
    # A saccade from mutual gaze to gaze away moves by the drawn magnitude: D = 25 ms + 2.4 ms/deg * A.
    from_mutual = np.concatenate(([True], s.mutual[:-1])) & ~s.mutual
    d = s.durations[from_mutual]
    assert len(d) > 1000 and np.allclose(d, DURATION_BASE_S + DURATION_PER_DEG_S * s.magnitudes[from_mutual])
    below = d[d < DURATION_BASE_S + DURATION_PER_DEG_S * limit - 1e-12]
    cdf = lambda x: magnitude_cdf((x - DURATION_BASE_S) / DURATION_PER_DEG_S, np.inf) / magnitude_cdf(limit - 1e-12, np.inf)  # noqa: E731
    assert stats.kstest(below, cdf).pvalue > ALPHA


def test_seeded_schedules_repeat():
    a = Saccades("talk", seed=3).schedule("brad").sample(100)
    b = Saccades("talk", seed=3).schedule("brad").sample(100)
    c = Saccades("talk", seed=3).schedule("rachel").sample(100)
    assert np.array_equal(a.times[:100], b.times[:100]) and not np.array_equal(a.times[:100], c.times[:100])


def eye_offsets_deg(rt, name):
    """(F, 2, 2) heading and pitch in degrees of each eye's turn from rest, in its aligned frame."""
    rig = rt.rig(name)
    eyes = [rig.joint("eyeball_left"), rig.joint("eyeball_right")]
    local = rt.motion(name).local_rotations[:, eyes]
    a = rig.aligned[eyes]
    turn = quat.multiply(quat.conjugate(rig.skeleton.rest_rotations[eyes]), local)
    h, p, _ = swing_angles(quat.multiply(quat.conjugate(a), quat.multiply(turn, a)))
    return np.degrees(np.stack((h, p), axis=-1))


def test_the_output_follows_the_schedule_and_pauses_for_speech():
    rt = Runtime(fps=30)
    rt.add_character(corpus_character("utah"), name="utah")
    saccades = Saccades("talk", seed=11)
    rt.activate("utah", saccades, 0.0, blend_in_s=0.0)
    rt.add_speech("utah", 20.0, 25.0)
    rt.run(40.0)
    eyes = eye_offsets_deg(rt, "utah")
    s = saccades.schedule("utah")
    s.until(40.0)
    fps_times = np.arange(len(eyes)) / 30.0
    checked = 0
    for k in range(len(s.times) - 1):
        settled = s.times[k] + s.durations[k] + 0.05
        if settled >= s.times[k + 1] or settled > 39.9 or 20.0 <= s.times[k] < 27.0 or 20.0 <= s.times[k + 1] < 27.0:
            continue
        f = int(np.ceil(settled * 30.0))
        if fps_times[f] >= s.times[k + 1]:
            continue
        assert np.allclose(eyes[f, 0], s.offsets[k], atol=0.05) and np.allclose(eyes[f, 1], s.offsets[k], atol=0.05)
        checked += 1
    assert checked >= 10
    assert np.any(np.abs(eyes[:600]) > 1.0)  # saccades before the speech
    speaking = (fps_times >= 20.2) & (fps_times < 27.0)  # back on the gaze direction, until 2 s after speech
    assert np.abs(eyes[speaking]).max() < 1e-6
    events_after = s.times[(s.times >= 27.0) & (s.times < 39.0)]
    assert len(events_after) and np.abs(eyes[fps_times > events_after[0] + 0.2]).max() > 0.5


def test_a_character_without_eyes_is_reported_once():
    rt = Runtime(fps=30)
    rt.add_character(corpus_character("xbot"), name="xbot")
    rt.activate("xbot", Saccades("listen"), 0.0)
    rt.activate("xbot", Saccades("think"), 1.0)
    rt.run(2.0)
    assert [n for n in rt.notes if "saccade" in n[1]] == [("xbot", "has no eyes: saccades are not shown")]


def test_bml_saccade_finish_stops_the_running_saccades():
    from infuse.bml import Scheduler

    rt = Runtime(fps=30)
    rt.add_character(corpus_character("utah"), name="utah")
    scheduler = Scheduler()
    scheduler.submit('<act><bml id="b1"><saccade mode="listen"/></bml></act>', at=0.0, character="utah")
    scheduler.submit('<act><bml id="b2"><saccade finish="true"/></bml></act>', at=2.0, character="utah")
    played = [rt.realize(a) for a in scheduler.activations("utah")]
    assert played[1] is None and played[0].end_s == pytest.approx(2.0 + played[0].blend_out_s)


def test_offsets_of_saccades_that_are_over_are_kept_as_worked_out():
    """Block after block, the eyes' offsets of saccades whose way is over are taken as the last block left
    them: the same, bit for bit, as worked out again, for saccades in progress, over, of no duration and none
    yet, in blocks of one frame and of several."""
    from infuse_saccade.controller import SaccadeState, _Over

    rows = [(0.10, 0.05, 3.0, -2.0, 1.0, 0.5), (0.0, 0.0, 1.5, 0.25, 0.0, 0.0), (-np.inf, 1.0, 0.0, 0.0, 0.0, 0.0),
            (0.32, 0.031, -4.0, 1.0, 3.0, -2.0)]
    for frames in (1, 4):
        over, kept = _Over(), 0
        for start in np.arange(0.0, 0.6, frames / 60.0):
            held = [tuple(row) for row in rows]
            times = np.repeat((start + np.arange(frames) / 60.0)[None], len(rows), axis=0)
            got = over.path(held, times)
            kept += not got.flags.writeable
            assert np.array_equal(got, SaccadeState.path(np.array(held), times))
        assert kept > 0
