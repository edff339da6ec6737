"""Noisy takes low-passed before a pack is built from them, so cycles close and transitions play on poses, not noise.

Marker noise of about a degree on every joint and frame moves a foot by 1-3 cm a frame. The contact
detector low-passes the feet's paths just enough for that (:func:`infuse.contacts.smoothed`); but a
cycle closed between two noisy frames takes out their noise with the loop's gap, and transitions are
played as recorded, noise and all. A take whose feet show such noise (:func:`infuse.contacts.position_noise`)
has every joint's rotation, the root's translation and any joint translations low-passed over the window
the detector uses for that noise (:func:`infuse.contacts.smoothing_frames`: a local quadratic fit,
a Savitzky-Golay filter, over the fewest frames that keep the noise from moving a landing foot's speed by
more than a tenth); clean takes (one frame to either side, or noise below :data:`CLEAN_NOISE_LEGS`, which
the detector's own low-pass of the feet's paths takes care of) are left exactly as they are.
"""
from __future__ import annotations

import numpy as np

from .. import quaternions as quat
from ..contacts import LANDING_SPEED, NOISE_SPEED, Foot, leg_length, position_noise, smoothing_frames
from ..kinematics import forward_kinematics
from ..motion import Motion


#: Position noise of the feet (leg lengths, :func:`~infuse.contacts.position_noise`) below which a take is
#: clean whatever its frame rate: about 5 mm on an adult. The measure reads as noise a fast take's feet,
#: which are seldom at rest (Bandai dataset-1's dash: 0.0024, the 5th percentile reaching frames where the
#: feet still move) and a resampling's interpolation (0.0053 at most at 24 fps); clean takes measure up to
#: 0.0014 at 30 fps and above, a degree of rotation noise on every joint 0.0085-0.031.
CLEAN_NOISE_LEGS = 0.006


def noise_frames(motion: Motion, pair: tuple[Foot, Foot]) -> int:
    """Frames to either side over which ``motion``'s feet need low-passing (1: clean)."""
    points = [j for foot in pair for j in foot.points]
    _, pos = forward_kinematics(motion.skeleton, motion.local_rotations, motion.root_translations, motion.joint_translations)
    leg = leg_length(motion.skeleton, pair)
    noise = position_noise(pos[:, points])
    if noise < CLEAN_NOISE_LEGS * leg:
        return 1
    return smoothing_frames(noise, motion.fps, NOISE_SPEED * LANDING_SPEED * leg)


def low_passed(values: np.ndarray, half: int) -> np.ndarray:
    """(F, ...) ``values`` fitted by a quadratic over ``half`` frames to either side of each frame (fewer
    than 2 * ``half`` + 1 frames: as they are)."""
    from scipy.signal import savgol_filter

    if half < 2 or len(values) < 2 * half + 1:
        return np.array(values, dtype=np.float64)
    return savgol_filter(values, 2 * half + 1, 2, axis=0, mode="interp")


def denoised(motion: Motion, pair: tuple[Foot, Foot]) -> tuple[Motion, int]:
    """``motion`` low-passed where its feet are noisy (see the module doc), and the frames to either side
    it was low-passed over (1: left as it is)."""
    half = noise_frames(motion, pair)
    if half < 2 or motion.num_frames < 2 * half + 1:
        return motion, 1
    rot = quat.normalize(low_passed(quat.make_continuous(motion.local_rotations, axis=0), half))
    jt = None if motion.joint_translations is None else low_passed(motion.joint_translations, half)
    return motion.replace(local_rotations=rot, root_translations=low_passed(motion.root_translations, half),
                          joint_translations=jt), half
