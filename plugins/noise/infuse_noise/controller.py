"""Noise: named joints turn by smooth random amounts, as SmartBody's ``<sbm:noise>`` (its Perlin noise).

Each joint's turn is a rotation vector (radians, in the joint's local frame) whose three components
follow independent 1-D gradient noise of time: one random gradient per lattice point, lattice points
``1 / frequency_hz`` seconds apart, a quintic fade between them. A component is 0 on the lattice
points and reaches about ``scale`` between them: ``scale`` is the size of the turn about each axis
(SmartBody adds ``scale`` times a noise within ±1/2 to each vector component of the joint's quaternion,
which is half the rotation vector: turns of up to about ``scale`` radians too) and ``frequency_hz`` how
often it changes direction. The turn is added to whatever plays below. A new noise on a character
replaces its last (SmartBody keeps one set of noisy joints).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from infuse import quaternions as quat
from infuse.bml.model import CANNOT_CREATE_BEHAVIOR
from infuse.errors import MissingJointsError, UsageError
from infuse.runtime import Controller, Layer, Mode
from infuse.stage import end_s

#: Random gradients per noise table (the lattice repeats after this many cells).
TABLE_SIZE = 256


def gradient_noise(u: np.ndarray, gradients: np.ndarray) -> np.ndarray:
    """1-D gradient noise at lattice coordinates ``u`` (F, *S): 0 on integers, at most about 1 in size.
    ``gradients`` (*S, N): each series' slopes in [-1, 1] at the lattice points (repeating after N)."""
    u = np.asarray(u, dtype=np.float64)
    cell = np.floor(u)
    f = u - cell
    size = gradients.shape[-1]
    table = np.broadcast_to(gradients, u.shape + (size,))
    i = cell.astype(np.int64) % size
    g0 = np.take_along_axis(table, i[..., None], axis=-1)[..., 0]
    g1 = np.take_along_axis(table, ((i + 1) % size)[..., None], axis=-1)[..., 0]
    fade = f * f * f * (f * (6.0 * f - 15.0) + 10.0)
    return 2.0 * (g0 * f + fade * (g1 * (f - 1.0) - g0 * f))


@dataclass(frozen=True, eq=False)
class NoiseBinding:
    """A noise bound to one character: the ``joints`` (K,) it turns, each component's random slopes
    ``gradients`` (K, 3, :data:`TABLE_SIZE`) and where on its lattice each starts, ``offsets`` (K, 3) cells."""

    joints: np.ndarray
    gradients: np.ndarray
    offsets: np.ndarray


class Noise(Controller):
    """Turn ``joints`` (canonical names or the character's own, case ignored) by noise of size ``scale``
    (radians) changing about ``frequency_hz`` times a second; ``seed`` makes it repeatable."""

    kind = "noise"
    layer = Layer.POSTURE
    mode = Mode.ADDITIVE
    blend_in_s = 0.3
    blend_out_s = 0.3

    def __init__(self, joints, scale: float = 0.02, frequency_hz: float = 0.05, seed: int = 0):
        joints = [str(j) for j in ([joints] if isinstance(joints, str) else joints)]
        if not joints:
            raise UsageError("noise names no joint")
        if not (np.isfinite(scale) and 0.0 <= scale <= np.pi / 2):
            raise UsageError(f"noise scale must lie in [0, pi/2] radians, got {scale}")
        if not (np.isfinite(frequency_hz) and 0.0 < frequency_hz <= 50.0):
            raise UsageError(f"noise frequency must lie in (0, 50] Hz, got {frequency_hz}")
        self.joints, self.scale, self.frequency_hz, self.seed = joints, float(scale), float(frequency_hz), int(seed)

    def describe(self) -> str:
        return f"noise ({' '.join(self.joints)})"

    def bind(self, rig, report) -> NoiseBinding:
        own = {n.lower(): i for i, n in enumerate(rig.skeleton.names)}
        found: list[int] = []
        missing: list[str] = []
        for name in self.joints:
            j = rig.joint(name)
            j = own.get(name.lower()) if j is None else j
            if j is None:
                missing.append(name)
            else:
                found.append(j)
        if not found:
            raise MissingJointsError(rig.name, f"noise: none of the joints {', '.join(self.joints)} is in the skeleton "
                                               "or mapped")
        if missing:
            report(f"noise: no joint {', '.join(missing)}; the others move")
        rng = np.random.default_rng(self.seed)
        return NoiseBinding(joints=np.array(sorted(set(found)), dtype=np.int64),
                            gradients=rng.uniform(-1.0, 1.0, (len(set(found)), 3, TABLE_SIZE)),
                            offsets=rng.uniform(0.0, TABLE_SIZE, (len(set(found)), 3)))

    def evaluate_one(self, job, block) -> None:
        b: NoiseBinding = job.binding
        u = job.local_times[:, None, None] * self.frequency_hz + b.offsets[None]  # (F, K, 3) lattice coordinates
        rotvec = self.scale * gradient_noise(u, b.gradients)  # (F, K, 3) radians
        job.pose.set_rotations(b.joints, quat.from_rotvec(rotvec), job.weight, job.mode)


def noise_from_bml(parameters: dict, runtime, character: str, activation=None) -> Noise:
    """``<sbm:noise joints frequency scale>``: the joints, the noise's frequency (Hz) and size (radians)."""
    return Noise(parameters.get("joints") or (), scale=float(parameters.get("scale", 0.02)),
                 frequency_hz=float(parameters.get("frequency_hz", 0.05)))


def realize_noise(activation, stage):
    """A noise replaces the character's noise before it (SmartBody keeps one set of noisy joints)."""
    for activity in stage.activities(activation.character):
        if isinstance(activity.controller, Noise) and (activity.end_s is None or activity.end_s > activation.start):
            stage.runtime.stop(activity, activation.start)
    try:
        controller = noise_from_bml(activation.parameters, stage.runtime, activation.character, activation)
    except UsageError as exc:
        stage.warn(activation, CANNOT_CREATE_BEHAVIOR, f"<{activation.element}> cannot be shown: {exc}")
        return None
    return stage.activate(activation, controller, end_s(activation))
