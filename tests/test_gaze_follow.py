"""The gaze smoothing step gives bit-identical paths on its scalar (few characters) and array paths."""
import numpy as np
import pytest

from infuse_gaze import solver


@pytest.mark.parametrize("characters", [1, 3])
def test_scalar_and_array_follow_agree_exactly(characters, monkeypatch):
    rng = np.random.default_rng(characters)
    desired = rng.normal(size=(characters, 240, 2))
    smoothing = rng.uniform(0.05, 1.0, size=(characters, 240))
    max_step = rng.uniform(0.005, 0.2, size=(characters, 240))
    state = rng.normal(size=(characters, 2))
    scalar = solver.follow(desired, smoothing, max_step, state)
    monkeypatch.setattr(solver, "SCALAR_FOLLOW_MAX_CHARACTERS", 0)
    array = solver.follow(desired, smoothing, max_step, state)
    assert np.array_equal(scalar[0], array[0]) and np.array_equal(scalar[1], array[1])
    steps = np.linalg.norm(np.diff(np.concatenate((state[:, None], scalar[1]), axis=1), axis=1), axis=-1)
    assert np.all(steps <= max_step + 1e-12)  # the speed limit holds
