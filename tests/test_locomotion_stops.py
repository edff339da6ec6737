"""A walk paces its last strides so its stop clip begins on time (at the clip's gait phase, with as far
to go as the clip travels), measured on the output with FK: SmartBody's MaleLocomotion set on Xbot, whose
stop (1.16 m from 1.28 m/s) fits a stride of 1.4 m at a fixed cadence only when the walk happens to line up."""
from __future__ import annotations

import numpy as np
import pytest

import infuse
from infuse.contacts import foot_contacts
from infuse.runtime import Runtime, controller

from corpus_data import corpus_file, require_corpus
from pack_support import smartbody_space

infuse_locomotion = pytest.importorskip("infuse_locomotion")
transitions = infuse_locomotion.transitions
FPS = 30
DISTANCES = np.arange(3.5, 6.01, 0.25)


@pytest.fixture(scope="module")
def xbot():
    require_corpus()
    return infuse.load(corpus_file("runxaway-models/Xbot.glb"))


@pytest.fixture(scope="module")
def space(xbot, tmp_path_factory):
    return smartbody_space(xbot, "MaleLocomotion", tmp_path_factory.mktemp("packs"))


def test_walks_of_any_length_end_with_the_stop_clip_on_their_target(xbot, space, monkeypatch):
    """Walks 3.5 to 6 m straight ahead at 1.3 m/s: every one stops with the clip (4 of 11 did at a fixed
    cadence, 10 paced at the speed it had while it was still speeding up), stands on its target, and its
    strides stay within the pacing's bounds."""
    stopped: dict[float, float] = {}  # target distance -> where the stop clip begins (z, m)
    original = transitions.stop_placement

    def record(clip, fps, x, z, target):
        stopped[round(float(target[1]), 2)] = float(z)
        return original(clip, fps, x, z, target)

    monkeypatch.setattr(transitions, "stop_placement", record)
    rt = Runtime(fps=FPS)
    names = []
    for d in DISTANCES:
        names.append(rt.add_character(infuse.Character(f"x{d}", xbot)))
        rt.activate(names[-1], controller("locomotion", pack=space, speed=1.3, target=(0.0, float(d))), 0.0)
    rt.run(10.0)
    assert len(stopped) == len(DISTANCES)
    walking: list[float] = []
    for d, name in zip(DISTANCES, names):
        rig = rt.rig(name)
        _, pos = infuse.motion_fk(rt.motion(name))
        pelvis = pos[:, rig.joint("base")][:, [0, 2]]
        assert np.linalg.norm(pelvis[-15:].mean(axis=0) - (0.0, d)) < 0.05
        # Each foot's strides (landing to landing) of the walk: those landing before the stop clip begins
        # (its own shorter last steps left out), none from where a foot stood at the start (a half stride).
        found = foot_contacts(rt.motion(name), rig.mapping)
        begins = stopped.get(round(float(d), 2), np.inf)
        for k in (0, 1):
            column = int(np.flatnonzero(found.foot_of_point == k)[0])  # the ankle
            lands = np.flatnonzero(np.diff(found.flags[:, column].astype(np.int8)) == 1) + 1
            at = pos[lands, found.points[column]][:, [0, 2]]
            strides = np.linalg.norm(np.diff(at, axis=0), axis=-1)
            walking.extend(strides[(at[1:, 1] < begins) & (at[:-1, 1] > 0.3)].tolist())
    # Paced, the strides are at most a quarter shorter or longer than the walk's usual one.
    assert 0.75 < min(walking) / np.median(walking) and max(walking) / np.median(walking) < 1.25
