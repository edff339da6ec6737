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


def one_frame_blocks(monkeypatch, scalar_up_to: int) -> list[np.ndarray]:
    """Local rotations (F, J, 4) of three characters evaluated one frame per block: one looks at a
    moving point with a slow, locked-below head, one at the first one's face, one (without eyes) at
    the second one's face; groups turned on Python floats up to ``scalar_up_to`` characters."""
    from infuse.runtime import Runtime
    from infuse_gaze import Gaze

    from runtime_characters import synthetic_character

    monkeypatch.setattr(solver, "SCALAR_TURN_MAX_CHARACTERS", scalar_up_to)
    rt = Runtime(fps=30, block_frames=1)
    names = [rt.add_character(synthetic_character(), "a"), rt.add_character(synthetic_character(), "b", position=(1.0, 0.0, 2.0)),
             rt.add_character(synthetic_character(drop=("eyeball_left", "eyeball_right")), "c", position=(-1.5, 0.2, 1.0),
                              heading_deg=150.0)]
    rt.activate("a", Gaze(lambda t: np.stack((2.0 * np.sin(2.0 * t), 1.2 + 0.6 * np.cos(3.0 * t), 1.5 + 0 * t), axis=-1),
                          influence="WAIST", limits={"head": (30.0, 15.0, 0.0, 10.0)}, speed_deg_s={"cervical": 20.0}), 0.0)
    rt.activate("b", Gaze("a:face", influence="SHOULDER"), 0.1)
    rt.activate("c", Gaze("b:face", influence="WHOLE", offset_angle_deg=10.0, offset_direction="UPLEFT"), 0.2)
    rt.run(1.5)
    return [rt.motion(n).local_rotations for n in names]


def test_scalar_and_array_turns_agree(monkeypatch):
    """A block of one frame turns each group of a few characters on Python floats: the same frames as
    on arrays, to rounding (limits locked below, speed limits at work, faces, offsets, no eyes)."""
    scalar = one_frame_blocks(monkeypatch, 16)
    array = one_frame_blocks(monkeypatch, 0)
    for mine, theirs in zip(scalar, array):
        assert np.abs(mine - theirs).max() < 1e-12
        assert np.abs(mine[-1] - mine[0]).max() > 0.05  # it did turn
