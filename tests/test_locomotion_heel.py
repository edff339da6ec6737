"""A landed heel holds the sole under it while the foot rolls down to flat (the leg's pinning)."""
from __future__ import annotations

import numpy as np
import pytest

import infuse
from infuse.contacts import foot_contacts, sole_positions
from infuse.runtime import Runtime

from corpus_data import corpus_file, require_corpus

infuse_locomotion = pytest.importorskip("infuse_locomotion")


@pytest.fixture(scope="module")
def xbot():
    require_corpus()
    return infuse.load(corpus_file("runxaway-models/Xbot.glb"))


def rolls(asset, pack: str, speed: float) -> tuple[np.ndarray, np.ndarray]:
    """A straight walk's frames in which a foot pitches by more than 2 degrees with the sole under its
    heel within 1 cm of that point's lowest at both ends: the sole's horizontal step (m) in each, and
    each foot's count of them."""
    rt = Runtime(fps=30)
    c = rt.add_character(infuse.Character("x", asset))
    rt.activate(c, infuse_locomotion.Locomotion(pack, speed=speed, max_accel=50.0), 0.0)
    rt.run(4.0)
    m = rt.motion(c)
    g_rot, g_pos = infuse.motion_fk(m)
    found = foot_contacts(m, rt.rig(c).mapping, fk=(g_rot, g_pos))
    sole = sole_positions(found, g_pos[:, found.points])
    steps, counts = [], []
    for k in (0, 1):
        heel_col, ball_col = np.nonzero(found.foot_of_point == k)[0][:2]
        heel = sole[:, heel_col]
        lever = g_pos[:, found.points[ball_col]] - g_pos[:, found.points[heel_col]]
        dip = np.degrees(np.arcsin(-lever[:, 1] / np.linalg.norm(lever, axis=-1)))
        low = heel[:, 1] - heel[:, 1].min() < 0.01
        rolling = low[1:] & low[:-1] & (np.abs(np.diff(dip)) > 2.0)
        steps.append(np.linalg.norm(np.diff(heel[:, [0, 2]], axis=0), axis=-1)[rolling])
        counts.append(int(rolling.sum()))
    return np.concatenate(steps), np.array(counts)


@pytest.mark.parametrize("pack", ["locomotion-male", "locomotion-female"])
def test_a_landed_heel_holds_its_sole_while_the_foot_rolls_down(xbot, pack):
    """The blend's foot lands turned up and pitches down to flat by several degrees a frame; the sole
    under the heel stays (measured at most 0.27 mm a frame; 0.44-1.23 cm while the pinning held the
    ankle, the foot turning about it)."""
    found = [rolls(xbot, pack, v) for v in (0.8, 1.2)]
    steps = np.concatenate([s for s, _ in found])
    assert sum(int(n.sum()) for _, n in found) >= 6, found  # the rolls are there to measure
    assert steps.max() < 0.002, steps
