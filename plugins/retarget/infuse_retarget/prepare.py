"""One skeleton made ready for retargeting: its mapping, default pose, alignment and leg height.

:func:`prepare` picks the default pose (the rest, or the most upright frame of a clip when the rest
is not a standing pose, set at rest: trunk, neck, head and shoulder girdle at their mean over the
clip, feet laid flat as they lie while planted), aligns it to the canonical T-pose
(:mod:`.alignment`) and measures the leg length the root translation is scaled by: the height of the hip joints above the soles along
the up axis (+Y), legs straightened as in the aligned pose, feet flat (the ankles' height above the
lowest point of the foot in a standing rest, or while planted in the clip).

``frame`` (J, 4) holds, per joint, ``A(c) · G_ref``: the joint's reference global rotation turned
by the alignment of the mapped joint that carries it. A canonical-frame world rotation ``D`` (the
paper's "standard rotation that complies with the default global frame", applied from the root)
gives the joint's global rotation ``D · frame``.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from infuse import contacts
from infuse import quaternions as quat
from infuse.canonical import ALL_NAMES
from infuse.errors import UnusableInputError
from infuse.kinematics import forward_kinematics
from infuse.motion import Motion
from infuse.skeleton import Skeleton

from .alignment import FEET, HELD, UPRIGHT_LIMIT_DEG, align, body_points, reference_frame, standing, upright_error
from .rig import Rig

#: Most frames of a clip examined when looking for a default pose.
POSE_SAMPLES = 240


@dataclass
class Prepared:
    """A skeleton ready to retarget from or to (see the module docstring).

    - ``rig``: the :class:`~.rig.Rig` (mapping, reference pose, position tree).
    - ``alignment``: canonical name -> (4,) world rotation onto the canonical T-pose.
    - ``frame``: (J, 4) ``A(carrier) · G_ref`` per joint; ``aligned``: (J, 3) positions in the
      aligned pose (reference root position).
    - ``leg_height``: metres, hip joints (their midpoint) above the soles, legs as aligned.
    - ``feet``: the two :class:`infuse.contacts.Foot`; ``pose_from``: "rest" or "frame N".
    """

    skeleton: Skeleton
    rig: Rig
    alignment: dict[str, np.ndarray]
    frame: np.ndarray
    aligned: np.ndarray
    leg_height: float
    feet: tuple
    pose_from: str

    @property
    def index(self) -> dict[str, int]:
        return self.rig.index


def _reference(skeleton: Skeleton, index: dict[str, int], motion: Motion | None):
    """(global rotations (J, 4), positions (J, 3), "rest" or "frame N", the clip's FK and contacts
    when the default pose comes from it (else ``None``), the ankles of the feet laid flat in it)."""
    rest_rot, rest_pos = skeleton.rest_global_rotations, skeleton.rest_global_positions
    if motion is None or motion.num_frames == 0 or upright_error(index, rest_pos) <= UPRIGHT_LIMIT_DEG:
        return rest_rot, rest_pos, "rest", None, ()
    picks = np.unique(np.linspace(0, motion.num_frames - 1, min(motion.num_frames, POSE_SAMPLES)).round().astype(int))
    g_rot, g_pos = forward_kinematics(skeleton, motion.local_rotations[picks], motion.root_translations[picks])
    k = reference_frame(index, g_pos)
    if upright_error(index, g_pos[k]) >= upright_error(index, rest_pos):
        return rest_rot, rest_pos, "rest", None, ()
    g_all, p_all = forward_kinematics(skeleton, motion.local_rotations, motion.root_translations, motion.joint_translations)
    clip = (g_all, p_all, contacts.foot_contacts(motion, index, fk=(g_all, p_all)))
    f = int(picks[k])
    root = motion.root_translations[f][None]
    joints = None if motion.joint_translations is None else motion.joint_translations[f][None]
    local = _held_at_mean(skeleton, index, motion.local_rotations[picks], k)
    local, flat = _flat_feet(skeleton, index, motion, local, forward_kinematics(skeleton, local[None], root, joints)[0][0], clip)
    g_rot, g_pos = forward_kinematics(skeleton, local[None], root, joints)
    return g_rot[0], g_pos[0], f"frame {f}", clip, flat


def _mean_rotation(q: np.ndarray, near: np.ndarray) -> np.ndarray:
    """(J, 4) mean of (F, J, 4) rotations, each taken in the hemisphere of ``near`` (J, 4)."""
    q = np.where(np.sum(q * near, axis=-1, keepdims=True) < 0.0, -q, q)
    return quat.normalize(q.mean(axis=0))


def _held_at_mean(skeleton: Skeleton, index: dict[str, int], local: np.ndarray, k: int) -> np.ndarray:
    """(J, 4) local rotations of frame ``k`` of ``local`` (F, J, 4), with the joints a held canonical
    joint carries (trunk, neck, head, shoulder girdle: :data:`~.alignment.HELD`) at their mean over
    the frames. A clip frame is a moment of a motion (a dash pumps the shoulders back and forth);
    the mean is the nearest the clip comes to the rest those joints have in a default pose."""
    mapped = {j: n for n, j in index.items()}
    carrier: list[str | None] = []
    for j, p in enumerate(skeleton.parents):
        carrier.append(mapped.get(j, carrier[p] if p >= 0 else None))
    held = np.array([c in HELD for c in carrier])
    out = np.array(local[k])
    out[held] = _mean_rotation(local[:, held], out[held])
    return out


def _flat_feet(skeleton: Skeleton, index: dict[str, int], motion: Motion, local: np.ndarray, glob: np.ndarray, clip):
    """Local rotations ``local`` (J, 4) of a clip frame (global rotations ``glob``) with each foot
    laid flat, and the canonical ankles of the feet laid so. The frame may catch a foot rolling or
    in the air, and a default pose stands on flat feet: flat is how the foot lies while planted in
    the clip (all its contact points down), the ankle tilted (not turned) until the direction that
    is then up in its frame is up, the joints below it at their mean rotations then. A foot never
    planted flat (a sprint on the balls of the feet) stays as the frame has it."""
    g_all, _, found = clip
    points = list(found.points)
    up = np.array([0.0, 1.0, 0.0])
    out = np.array(local)
    flat = []
    for foot, ankle_name in zip(contacts.feet(skeleton, index), FEET):
        planted = found.flags[:, [points.index(j) for j in foot.points]].all(axis=1)
        if not planted.any():
            continue
        flat.append(ankle_name)
        up_in_foot = quat.rotate(quat.conjugate(g_all[planted, foot.ankle]), up).mean(axis=0)
        ankle = glob[foot.ankle]
        laid = quat.multiply(quat.between(quat.rotate(ankle, up_in_foot), up), ankle)
        parent = skeleton.parents[foot.ankle]
        out[foot.ankle] = laid if parent < 0 else quat.normalize(quat.multiply(quat.conjugate(glob[parent]), laid))
        below = [j for j in foot.joints if j != foot.ankle]
        if below:
            out[below] = _mean_rotation(motion.local_rotations[planted][:, below], out[below])
    return out, tuple(flat)


def _ankle_height(skeleton, pair, rot, pos, clip) -> float:
    """Mean height of the ankles above the soles of flat feet, metres: measured in a standing rest,
    or while the ankles are planted in the clip the default pose came from."""
    if clip is None:
        lowest = contacts.lowest_points(skeleton, pair, rot[None], pos[None])[0]
        return float(np.mean([pos[f.ankle, 1] - low for f, low in zip(pair, lowest)]))
    _, g_pos, found = clip
    heights = []
    for k, foot in enumerate(pair):
        planted = found.flags[:, list(found.points).index(foot.ankle)]
        rel = g_pos[:, foot.ankle, 1] - found.lowest[:, k]
        heights.append(np.median(rel[planted]) if planted.any() else np.percentile(rel, 5.0))
    return float(max(np.mean(heights), 0.0))


def prepare(skeleton: Skeleton, index: dict[str, int], motion: Motion | None = None, file=None) -> Prepared:
    """Prepare ``skeleton`` whose canonical joints are ``index`` (name -> joint index).

    ``motion``: a clip on this skeleton, whose most upright frame serves as the default pose when
    the rest is not a standing pose. Raises :class:`UnusableInputError` for a mapping without a
    base, hips or spine, and for zero-length legs.
    """
    index = {n: index[n] for n in ALL_NAMES if n in index}
    if "base" not in index:
        raise UnusableInputError(file, "no base (pelvis) joint is mapped")
    try:
        body_points(index)
    except KeyError as exc:
        raise UnusableInputError(file, f"cannot find the body's axes: {exc.args[0]}") from None
    rot, pos, pose_from, clip, flat = _reference(skeleton, index, motion)
    rig = Rig(skeleton, index, rot, pos)
    pair = contacts.feet(skeleton, index, file=file)
    contacts.leg_length(skeleton, pair, pos, file=file)
    level = clip is None and standing(index, pos)
    alignment = align(index, pos, at_rest=level or clip is not None, level=level, flat_feet=FEET if level else flat)
    carriers = [rig.canonical_of.get(int(c)) for c in rig.carrier]
    frame = np.array([quat.multiply(alignment[n], rot[j]) if n is not None else rot[j] for j, n in enumerate(carriers)])
    roots = {int(r): pos[r][:, None] for r in skeleton.roots}
    at = rig.positions_of(frame[:, :, None], roots)
    aligned = np.stack([at[j][:, 0] for j in range(skeleton.num_joints)])
    hips = 0.5 * (aligned[index["l_hip"]] + aligned[index["r_hip"]])
    ankles = 0.5 * (aligned[pair[0].ankle] + aligned[pair[1].ankle])
    leg_height = float(hips[1] - ankles[1] + _ankle_height(skeleton, pair, rot, pos, clip))
    if not np.isfinite(leg_height) or leg_height < 1e-3 * max(skeleton.height(), 1e-9) or leg_height <= 1e-6:
        raise UnusableInputError(file, f"zero-length legs: the hips are {leg_height:.3g} m above the feet")
    return Prepared(skeleton, rig, alignment, frame, aligned, leg_height, pair, pose_from)

