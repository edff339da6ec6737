"""Two-joint limb IK, vectorized over frames: the end of the foot-contact component (the legs get to
the goals of :mod:`infuse.footing`), and arms that take things.

The limb is three joints a (hip, shoulder), b (knee, elbow), c (ankle, wrist). The bend at b is set
by the law of cosines so that c lies as far from a as the goal, a swings in the limb's plane so that
c keeps its direction from a, then a turns by the shortest arc that brings c onto the goal. Two
entry points give that one solution:

- :func:`solve_limb` works on a character's local rotations (F, J, 4), joints anywhere in the
  hierarchy (twist joints between them are carried along), the bend staying in the limb's current
  plane (with a ``pole``: on the pole's side, and in the pole's plane when the limb is within a few
  degrees of straight), the end joint keeping its global rotation.
- :func:`turn_limb` works on world positions and returns world turns of the limb's two segments,
  for callers that keep their own pose (the retargeter), bending about a hinge axis they give
  (:func:`hinge_axes`) and never straightening a limb past a least flexion.

**Carried ends.** Some rigs built for IK hang the end joint outside its limb (a foot hanging from the
root, not from the shin): the joint is then *carried* by the end of the middle joint's bone, the point
where it sits at rest in b's frame (:func:`carried_offsets`). :func:`solve_limb` brings that point to
the goal and places the end joint there by its own local translation, its global rotation kept or
set as for any limb; :func:`carry_ends` puts such joints back on their bones' ends in any pose.

Positions are metres; quaternions (x, y, z, w).
"""
from __future__ import annotations

import weakref
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from .. import quaternions as quat
from ..skeleton import Skeleton
from .pose import chain_fk


# Small vector helpers over (..., 3) arrays: numpy's generic cross and norm, and einsum's broadcasting
# iterator, cost more than the arithmetic; sums over the last axis run as one matrix-vector product.
# Gathers go through the arrays' take with index arrays made once: numpy's fancy indexing, and np.take
# with an index list, cost several times more on small arrays.
_NEXT, _AFTER = np.array([1, 2, 0]), np.array([2, 0, 1])
_CROSSED_FIRST, _CROSSED_SECOND = np.array([2, 2, 0]), np.array([3, 0, 1])  # a->c x a->goal, a->c x a->b, a->b x b->c
_A_B_A = np.array([0, 1, 0])
_ONES = np.ones(3)


def _dot(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    product = u * v
    return (product.reshape(-1, 3) @ _ONES).reshape(product.shape[:-1])


def _norm(v: np.ndarray) -> np.ndarray:
    return np.sqrt(_dot(v, v))


def _cross(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    u, v = np.asarray(u), np.asarray(v)
    return u.take(_NEXT, -1) * v.take(_AFTER, -1) - u.take(_AFTER, -1) * v.take(_NEXT, -1)


def _any(flags: np.ndarray) -> bool:
    """Whether any of ``flags`` is set: counted, as numpy's any() costs several times more on a few values."""
    return bool(np.count_nonzero(flags))


def _all(flags: np.ndarray) -> bool:
    """Whether all of ``flags`` are set (see :func:`_any`)."""
    return bool(np.count_nonzero(flags) == np.size(flags))


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.maximum(_norm(v), 1e-12)[..., None]


def _arccos(cosine: np.ndarray) -> np.ndarray:
    return np.arccos(np.minimum(np.maximum(cosine, -1.0), 1.0))


#: Sines of the bend at b below which a limb with a pole bends in the pole's plane, and from which in its
#: own (between, the two blended; :func:`_pole_plane`): about 1.1 and 3.4 degrees.
POLE_PLANE_SINE = (0.02, 0.06)
#: Margin (metres) inside a limb's span for a goal to count as reachable (:func:`turn_limb`).
REACH_MARGIN = 5e-4
#: Each skeleton's carried-end offsets by limb (:func:`carried_offset`), for as long as the skeleton lives.
_CARRIED: weakref.WeakKeyDictionary[Skeleton, dict[tuple[int, int, int], np.ndarray | None]] = weakref.WeakKeyDictionary()


def hangs_below(skeleton, joint: int, ancestor: int) -> bool:
    """Whether ``joint`` hangs, at any depth, below ``ancestor``."""
    parents = skeleton.parents
    j = int(parents[joint])
    while j >= 0:
        if j == ancestor:
            return True
        j = int(parents[j])
    return False


def is_carried(skeleton, limb) -> bool:
    """Whether the end c of ``limb`` (a, b, c) hangs outside it: below neither a nor b, and a not below c."""
    a, b, c = (int(j) for j in limb)
    return not (hangs_below(skeleton, c, a) or hangs_below(skeleton, a, c) or a == c)


def carried_offset(skeleton, limb) -> np.ndarray | None:
    """Where the end c of ``limb`` (a, b, c) is carried when it hangs outside its limb: (3,) metres, c's
    rest position in b's rest frame (the end of b's bone as the rig has it); None when c hangs below b.

    Raises ValueError when c hangs below a but not below b, or a hangs below c: turning the limb
    would move the joint c hangs from."""
    a, b, c = (int(j) for j in limb)
    known = _CARRIED.setdefault(skeleton, {})
    key = (a, b, c)
    if key not in known:
        if hangs_below(skeleton, c, b):
            known[key] = None
        elif not is_carried(skeleton, key):
            names = skeleton.names
            raise ValueError(f"joint {names[c]!r} hangs neither below {names[b]!r} nor outside the limb from {names[a]!r}")
        else:
            rest_rot, rest_pos = skeleton.rest_global_rotations, skeleton.rest_global_positions
            known[key] = quat.rotate(quat.conjugate(rest_rot[b]), rest_pos[c] - rest_pos[b])
    return known[key]


def carry_ends(skeleton, local_rotations: np.ndarray, root_translations: np.ndarray, joint_translations: np.ndarray | None,
               limbs) -> None:
    """Put the carried end of each limb (a, b, c) of ``limbs`` (K, 3) on the end of b's bone
    (:func:`carried_offset`), in place: c's local translation in ``joint_translations`` (F, J, 3) is set,
    its rotation left as it is (its global rotation does not change). Limbs whose end hangs below b are
    left (``joint_translations`` may then be None). A blend of poses (rotations interpolated, the end's
    translation averaged) leaves a carried end off its bone; this puts it back where a foot hanging
    from its shin would be."""
    limbs = np.asarray(limbs, dtype=np.int64).reshape(-1, 3)
    found = [(k, o) for k, o in enumerate(carried_offset(skeleton, limb) for limb in limbs) if o is not None]
    if found:
        kept = [k for k, _ in found]
        if joint_translations is None or not joint_translations.flags.writeable:
            raise ValueError(f"joint {skeleton.names[limbs[kept[0], 2]]!r} hangs outside its limb: placing it needs "
                             f"writable joint translations (F, J, 3), which the caller keeps")
        _place_carried(skeleton, local_rotations, root_translations, joint_translations, limbs[kept, 1], limbs[kept, 2],
                       np.stack([o for _, o in found]))


def _place_carried(skeleton, local_rotations, root_translations, joint_translations, middles, ends,
                   offsets) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Set the local translations of carried ``ends`` (K,) so each sits at its ``offsets`` (K, 3) in its
    middle joint's frame (``middles`` (K,)); returns their positions (F, K, 3), the global rotations
    (F, K, 4) of the joints they hang from (the identity for a root) and of the middle joints."""
    holders = skeleton.parents[ends]
    hung = holders >= 0
    g_rot, g_pos = chain_fk(skeleton, local_rotations, root_translations, joint_translations,
                            np.concatenate((middles, np.where(hung, holders, middles))))
    k = len(middles)
    places = g_pos[:, :k] + quat.rotate(g_rot[:, :k], offsets)
    holder_rot = np.where(hung[:, None], g_rot[:, k:], quat.IDENTITY)
    holder_pos = np.where(hung[:, None], g_pos[:, k:], 0.0)
    joint_translations[:, ends] = quat.rotate(quat.conjugate(holder_rot), places - holder_pos)
    return places, holder_rot, g_rot[:, :k]


@dataclass(frozen=True)
class LimbTurns:
    """World turns that solve a two-bone limb (:func:`turn_limb`), and how close its end came.

    ``root`` (F, 4): the turn about joint a of everything below a; ``middle`` (F, 4): the turn of
    everything below b instead (it includes ``root``); ``end`` (F, 3): where c ends up;
    ``residual`` (F,): its distance from the goal, metres; ``reachable`` (F,): whether the goal lay
    inside the limb's span by at least :data:`REACH_MARGIN`.
    """

    root: np.ndarray
    middle: np.ndarray
    end: np.ndarray
    residual: np.ndarray
    reachable: np.ndarray


def hinge_axes(root: np.ndarray, middle: np.ndarray, end: np.ndarray,
               reference: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Hinge axes (F, 3) and flexions (F,, radians) of two-bone limbs a, b, c at ``root``, ``middle``
    and ``end`` (F, 3).

    A clearly bent limb bends about its own plane's normal; a nearly straight one about
    ``reference`` (F, 3) (e.g. the canonical hinge the joint carries), made perpendicular to the
    upper bone; in between the two are blended. The normal's sign follows the reference, so the
    flexion is positive for a limb bent the natural way. The axes are perpendicular to the upper bone.
    """
    u = _unit(middle - root)
    v = _unit(end - middle)
    n = _cross(u, v)
    sin_bend = _norm(n)
    ref = _unit(reference - _dot(reference, u)[..., None] * u)
    n = np.where((_dot(n, ref) < 0.0)[..., None], -n, n) / np.maximum(sin_bend, 1e-12)[..., None]
    w = np.clip((sin_bend - 0.03) / 0.07, 0.0, 1.0)
    w = (w * w * (3.0 - 2.0 * w))[..., None]
    axis = _unit(w * n + (1.0 - w) * ref)
    return axis, np.arctan2(_dot(axis, _cross(u, v)), _dot(u, v))


def turn_limb(root: np.ndarray, middle: np.ndarray, end: np.ndarray, goal: np.ndarray, hinge: np.ndarray,
              flexion: np.ndarray, min_flexion: float = 0.0) -> LimbTurns:
    """Bring the end c of limbs a, b, c at ``root``, ``middle``, ``end`` (F, 3) to ``goal`` (F, 3).

    b bends about ``hinge`` (F, 3, unit, perpendicular to a->b; :func:`hinge_axes`) from its
    ``flexion`` (F,, radians) to the flexion the goal's distance from a needs, a swings about the
    hinge so that c keeps its direction from a, then a turns by the shortest arc that points c at
    the goal: the limb moves only as much as the goal needs (as :func:`solve_limb` does). The hinge
    never straightens past ``min_flexion`` radians (no hyperextension), but a limb already
    straighter is not made to bend; a goal out of its span is moved onto the reachable shell, so the
    limb stretches toward it.
    """
    upper, lower = middle - root, end - middle
    a, b = _norm(upper), _norm(lower)
    straightest = np.maximum(np.minimum(flexion, min_flexion), 0.0)
    far = np.sqrt(a * a + b * b + 2.0 * a * b * np.cos(straightest)) * (1.0 - 1e-6)
    near = np.abs(a - b) * (1.0 + 1e-6)
    offset = goal - root
    dist = _norm(offset)
    reachable = (dist <= far - REACH_MARGIN) & (dist >= near + REACH_MARGIN)
    span = np.clip(dist, near, far)
    # Turning the lower bone by t about the hinge h (perpendicular to the upper bone u) gives
    # u . lower(t) = A cos t + B sin t with A = u . lower and B = u . (h x lower); the distance
    # from a to c fixes u . lower(t), so t = atan2(B, A) + arccos(...) (the branch that bends the
    # natural way, the law of cosines when h is the limb plane's normal).
    along = _dot(upper, lower)
    across = _dot(upper, _cross(hinge, lower))
    size = np.maximum(np.hypot(along, across), 1e-12)
    wanted = 0.5 * (span * span - a * a - b * b)
    bend = np.arctan2(across, along) + _arccos(wanted / size)
    bend = np.maximum(bend, np.minimum(0.0, min_flexion - flexion))
    q_bend = quat.from_axis_angle(hinge, bend)
    bent = upper + quat.rotate(q_bend, lower)
    line = end - root
    target = np.where((dist > 1e-12)[..., None], offset, line)
    q_root = quat.multiply(quat.between(line, target), quat.between(bent, line))
    new_end = root + quat.rotate(q_root, bent)
    return LimbTurns(q_root, quat.multiply(q_root, q_bend), new_end, _norm(goal - new_end), reachable)


def solve_limb(skeleton, local_rotations: np.ndarray, root_translations: np.ndarray, joint_translations,
               joints, goal: np.ndarray, weight=None, pole: np.ndarray | None = None,
               keep_end: bool = True, end_rotation: np.ndarray | None = None, chains=None,
               distance: bool = True) -> np.ndarray | None:
    """Rotate joints a and b of ``joints`` so that c gets to ``goal`` (F, 3); writes ``local_rotations``
    (F, J, 4) in place and returns the distance (F,) left to the goal (0 when within its span), or None
    with ``distance=False`` (c's new position is then not computed).

    ``weight`` (F,) in [0, 1] blends from the current pose to the solved one; ``pole`` (F, 3) or (3,)
    is the side the limb bends to (a knee's forward): a limb bent away from it (a knee a little past
    straight, as blends and takes leave them) is bent on the pole's side, the mirror image, and a limb
    within a few degrees of straight in the plane through the pole (:func:`_pole_plane`); a limb
    clearly bent toward it bends on in its own plane. The end joint c keeps its global rotation
    when ``keep_end``, or takes the global rotation ``end_rotation`` (F, 4) when given.

    Several limbs that do not hang from one another (left and right legs) are solved in one call
    with ``joints`` a sequence of K (a, b, c) triples: ``goal`` (F, K, 3), ``weight`` (F,) or (F, K),
    ``pole`` (3,), (F, 3) or (F, K, 3), ``end_rotation`` (F, K, 4); the distances are then (F, K).

    ``chains``: the global rotations (F, [K,] R, 4) and positions (F, [K,] R, 3) of a, b, c and, when
    a has a parent, that parent (R = 4), when the caller has them already (else one FK finds them).

    A carried end (:func:`carried_offset`) is brought to the goal as the end of b's bone, then placed
    there on every frame, whatever ``weight``, by its local translation, written in ``joint_translations``
    (F, J, 3), which must then be given, writable, and kept with the rotations.
    """
    return _solve(skeleton, local_rotations, root_translations, joint_translations, joints, goal, weight, pole, keep_end,
                  end_rotation, chains, distance, False)[0]


def solve_limb_ends(skeleton, local_rotations: np.ndarray, root_translations: np.ndarray, joint_translations,
                    joints, goal: np.ndarray, weight=None, pole: np.ndarray | None = None,
                    keep_end: bool = True, end_rotation: np.ndarray | None = None, chains=None,
                    distance: bool = True) -> tuple[np.ndarray | None, np.ndarray | None, np.ndarray | None]:
    """:func:`solve_limb`, returning with the distance (or None) where the limbs' ends c are now: the global
    rotations (F, [K,] 4) of c's parents and c's positions (F, [K,] 3), as a forward kinematics of the
    solved pose gives them (the rotations composed in the same order), so a caller that goes on below c
    needs none. Both are None for carried ends and for limbs solved apart."""
    return _solve(skeleton, local_rotations, root_translations, joint_translations, joints, goal, weight, pole, keep_end,
                  end_rotation, chains, distance, True)


@dataclass(frozen=True)
class LimbSolve:
    """The arguments of one :func:`solve_limb_ends` call, for :func:`solve_limb_ends_together` (see there)."""

    skeleton: Skeleton
    local_rotations: np.ndarray
    root_translations: np.ndarray
    joint_translations: np.ndarray | None
    joints: object
    goal: np.ndarray
    weight: object = None
    pole: np.ndarray | None = None
    keep_end: bool = True
    end_rotation: np.ndarray | None = None
    chains: tuple | None = None
    distance: bool = True


def solve_limb_ends_together(solves) -> list[tuple[np.ndarray | None, np.ndarray | None, np.ndarray | None]]:
    """:func:`solve_limb_ends` of each of ``solves`` (:class:`LimbSolve`: several poses, each its own
    arrays, of one skeleton or of several), each result as solving it alone gives it, in their order.
    The arithmetic of the limbs solved together (as many in each, none solved apart, all with a pole
    or all without) runs once over their frames stacked: on a block's few frames it costs about as
    much for all as for one."""
    setups = [_set_up(s.skeleton, s.local_rotations, s.root_translations, s.joint_translations, s.joints, s.goal, s.pole,
                      s.chains) for s in solves]
    bends: list[np.ndarray | None] = [None] * len(solves)
    alike: dict[tuple, list[_Setup]] = {}
    at: dict[int, int] = {}  # each set-up's solve, by the set-up's id
    for i, setup in enumerate(setups):
        if setup is not None:
            alike.setdefault((setup.several, setup.A.shape[1:], setup.pole is None), []).append(setup)
            at[id(setup)] = i
    for parts in alike.values():
        if len(parts) == 1:
            continue
        A, B, C, T, ab_rot, old = (np.concatenate([getattr(u, name) for u in parts]) for name in ("A", "B", "C", "T", "ab_rot", "old"))
        poles = [u.pole for u in parts if u.pole is not None]  # all or none (alike)
        pole = np.concatenate([np.broadcast_to(p, u.A.shape) for p, u in zip(poles, parts)]) if poles else None
        rows = _bend(A, B, C, T, ab_rot, pole, old)
        for u, a, e in zip(parts, *_bounds([len(u.A) for u in parts])):
            bends[at[id(u)]] = rows[a:e]
    out = []
    for s, setup, bent in zip(solves, setups, bends):
        if setup is None:
            out.append(_solve(s.skeleton, s.local_rotations, s.root_translations, s.joint_translations, s.joints, s.goal, s.weight,
                              s.pole, s.keep_end, s.end_rotation, s.chains, s.distance, True))
            continue
        new = _bend(setup.A, setup.B, setup.C, setup.T, setup.ab_rot, setup.pole, setup.old) if bent is None else bent
        out.append(_finish(s.skeleton, s.local_rotations, s.root_translations, s.joint_translations, setup, new, s.weight,
                           s.keep_end, s.end_rotation, s.distance, True))
    return out


def _bounds(counts: list[int]) -> tuple[list[int], list[int]]:
    """The first and past-the-last rows of parts of ``counts`` rows stacked in order."""
    ends = np.cumsum(counts).tolist()
    return [0, *ends[:-1]], ends


class _Setup(NamedTuple):
    """One solve's limbs as :func:`_bend` and :func:`_finish` take them: the plan, the goal ``T`` (F, [K,] 3),
    the global rotations ``g_rot`` (F, [K,] R, 4) of a, b, c (and a's parent), the places ``A``, ``B``, ``C``
    (F, [K,] 3) of a, b and c (a carried c: the end of b's bone), a's and b's global rotations ``ab_rot``
    (F, [K,] 2, 4) and local ones ``old`` (a copy), the pole as the limbs' arrays broadcast it or None,
    and the carried ends' offsets (K, 3) or None."""

    plan: _LimbPlan
    several: bool
    T: np.ndarray
    g_rot: np.ndarray
    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    ab_rot: np.ndarray
    old: np.ndarray
    pole: np.ndarray | None
    carried_at: np.ndarray | None


def _solve(skeleton, local_rotations, root_translations, joint_translations, joints, goal, weight, pole, keep_end,
           end_rotation, chains, distance: bool, ends: bool) -> tuple[np.ndarray | None, np.ndarray | None, np.ndarray | None]:
    """:func:`solve_limb`'s work: the distance (or None) and, with ``ends``, the ends' parent rotations and
    positions (:func:`solve_limb_ends`)."""
    setup = _set_up(skeleton, local_rotations, root_translations, joint_translations, joints, goal, pole, chains)
    if setup is None:  # solved apart
        plan = _limb_plan(skeleton, joints)
        T = np.asarray(goal, dtype=np.float64)
        left = [solve_limb(skeleton, local_rotations, root_translations, joint_translations, tuple(limb), T[:, k],
                           _column(weight, k, 2), _column(pole, k, 3), keep_end, _column(end_rotation, k, 3),
                           None if chains is None else tuple(c[:, k] for c in chains), distance)
                for k, limb in enumerate(plan.limbs)]
        return (np.stack([d for d in left if d is not None], axis=1) if distance else None), None, None
    bent = _bend(setup.A, setup.B, setup.C, setup.T, setup.ab_rot, setup.pole, setup.old)
    return _finish(skeleton, local_rotations, root_translations, joint_translations, setup, bent, weight, keep_end, end_rotation,
                   distance, ends)


def _set_up(skeleton, local_rotations, root_translations, joint_translations, joints, goal, pole, chains) -> _Setup | None:
    """The :class:`_Setup` of one solve (see :func:`solve_limb` for the arguments); None for limbs solved apart."""
    plan = _limb_plan(skeleton, joints)
    limbs, several, parents, offsets = plan.limbs, plan.several, plan.parents, plan.offsets
    if plan.apart:
        return None
    T = np.asarray(goal, dtype=np.float64)
    if chains is None:  # one FK for every limb; arrays keep a limb axis only when there are several
        rows = np.column_stack((limbs, parents)) if plan.all_hung else limbs  # (K, R)
        g_rot, g_pos = chain_fk(skeleton, local_rotations, root_translations, joint_translations, rows.ravel())
        shape = (len(g_rot),) + (rows.shape if several else rows.shape[1:])
        g_rot, g_pos = g_rot.reshape(shape + (4,)), g_pos.reshape(shape + (3,))
    else:
        g_rot, g_pos = chains
    A, B, C = g_pos[..., 0, :], g_pos[..., 1, :], g_pos[..., 2, :]
    carried_at = None
    if plan.all_carried:
        if joint_translations is None or not joint_translations.flags.writeable:
            raise ValueError(f"joint {skeleton.names[limbs[0, 2]]!r} hangs outside its limb: placing it needs "
                             f"writable joint translations (F, J, 3), which the caller keeps")
        carried_at = np.stack(offsets)  # (K, 3)
        C = B + quat.rotate(g_rot[..., 1, :], carried_at if several else carried_at[0])
    pole_at = None
    if pole is not None:  # as the limbs' arrays broadcast it
        pole = np.asarray(pole, dtype=np.float64)
        pole_at = pole[:, None] if several and pole.ndim == 2 else pole
    columns = limbs if several else limbs[0]
    # a's and b's local rotations before the solve: a copy (F, [K,] 2, 4)
    return _Setup(plan, several, T, g_rot, A, B, C, g_rot[..., :2, :], local_rotations.take(columns[..., :2], 1), pole_at,
                  carried_at)


def _bend(A, B, C, T, ab_rot, pole, old) -> np.ndarray:
    """New local rotations (F, [K,] 2, 4) of limbs' joints a and b (local ones ``old``, global ones ``ab_rot``
    (F, [K,] 2, 4)) at ``A`` and ``B`` (F, [K,] 3) that bring c at ``C`` to ``T`` (F, [K,] 3), bending toward
    ``pole`` (broadcast to them) or None (see :func:`solve_limb`): frame by frame and limb by limb."""
    # The sides a->b, b->c, a->c and a->goal (4, F, [K,] 3) and their lengths.
    sides = np.empty((4,) + A.shape)
    for k, (end, start) in enumerate(((B, A), (C, B), (C, A), (T, A))):
        np.subtract(end, start, out=sides[k])
    lengths = _norm(sides)
    lab, lcb, lca, lta = lengths
    lat = np.minimum(np.maximum(lta, np.abs(lab - lcb) + 1e-6), (lab + lcb) * (1.0 - 1e-6))
    # a->c x a->goal (toward the goal), a->c x a->b (the bend's normal) and a->b x b->c, their lengths.
    ca = sides[2]
    first, second = sides.take(_CROSSED_FIRST, 0), sides.take(_CROSSED_SECOND, 0)
    crossed = _cross(first, second)
    axes, cross_norms = crossed[:2], _norm(crossed)
    axis_norms = cross_norms[:2]
    # The angles of the goal off a->c at a, at a (to b) and at b (between b->a and b->c) now, from
    # their sines and cosines: an arccos of a cosine near 1 would turn its last bit into some 1e-8
    # radians (a goal on the animated end would move the limb by 1e-8 m). The angles at a and b once
    # solved, by the law of cosines (the limb kept off straight, where arccos is well conditioned).
    dots = _dot(first, second)
    dots[2] *= -1.0
    ac_at_0, ac_ab_0, ba_bc_0 = np.arctan2(cross_norms, dots)
    lab2, lcb2, lat2 = lab * lab, lcb * lcb, lat * lat
    ac_ab_1, ba_bc_1 = _arccos((lcb2 - lab2 - lat2) / (-2.0 * lab * lat)), _arccos((lat2 - lab2 - lcb2) / (-2.0 * lab * lcb))
    small = axis_norms[0] < 1e-12
    flat = axis_norms[1] < 1e-6 * np.maximum(lab * lcb, 1e-12)
    toward = None
    if pole is not None:  # a->c x pole: the normal of the plane that bends the limb toward the pole
        toward = _cross(ca, pole)  # broadcast by the products
    if _any(flat) or _any(small):
        axis1, axis0 = axes
        if _any(flat):  # a straight limb bends toward the pole, else toward the goal
            if toward is not None:
                fallback = toward
            else:
                other = _cross(ca, np.array([0.0, 1.0, 0.0]))
                fallback = np.where(small[..., None], other, axis1)
            axis0 = np.where(flat[..., None], fallback, axis0)
        axis0 = _unit(axis0)
        axis1 = _unit(np.where(small[..., None], axis0, axis1))  # the goal on the line a->c: no turn toward it
    else:
        axis1, axis0 = axes / np.maximum(axis_norms, 1e-12)[..., None]
    # The turns of a (bend, then toward the goal) and of b (bend) as local rotations: one rotate.
    inverse = quat.conjugate(ab_rot.take(_A_B_A, -2))  # a's, b's, a's: (F, [K,] 3, 4)
    # Stacked by assignment: np.stack costs more than the copies on a block's few frames.
    local_axes, angles = np.empty(inverse.shape[:-1] + (3,)), np.empty(inverse.shape[:-1])
    local_axes[..., 0, :], local_axes[..., 1, :], local_axes[..., 2, :] = axis0, axis0, axis1
    angles[..., 0], angles[..., 1], angles[..., 2] = ac_ab_1 - ac_ab_0, ba_bc_1 - ba_bc_0, ac_at_0
    turns = quat.from_axis_angle(quat.rotate(inverse, local_axes), angles)
    if toward is not None:
        plane = _pole_plane(axis0, toward, cross_norms[2] / np.maximum(lab * lcb, 1e-12))
        moved = ~flat & (_dot(plane, axis0) < 1.0 - 1e-12)
        if _any(moved):  # bent in the plane the pole sides, not in its own
            turns[moved, :2] = _replaned(axis0[moved], plane[moved], ac_ab_0[moved], ac_ab_1[moved], ba_bc_0[moved],
                                         ba_bc_1[moved], inverse[moved, :2])
    r0, r1, r2 = turns[..., 0, :], turns[..., 1, :], turns[..., 2, :]
    # a bends in the limb's plane first (c stays on the line a->c), then turns that line onto the goal;
    # turning first would bend about a normal the turn has moved (off the goal unless the plane holds it).
    both = np.empty(old.shape)
    both[..., 0, :], both[..., 1, :] = quat.multiply(r2, r0), r1
    return quat.multiply(old, both)


def _finish(skeleton, local_rotations, root_translations, joint_translations, setup: _Setup, new: np.ndarray, weight, keep_end,
            end_rotation, distance: bool, ends: bool) -> tuple[np.ndarray | None, np.ndarray | None, np.ndarray | None]:
    """Write the solved rotations ``new`` (:func:`_bend`), blended from ``setup.old`` by ``weight``, into
    ``local_rotations`` and place the ends (see :func:`solve_limb`); the distance and ends as :func:`_solve`."""
    plan, several, T, g_rot, A, old, carried_at = setup.plan, setup.several, setup.T, setup.g_rot, setup.A, setup.old, setup.carried_at
    limbs = plan.limbs
    parent_rot = g_rot[..., 3, :] if plan.all_hung else None
    columns = limbs if several else limbs[0]
    if weight is not None:  # both joints in one interpolation
        w = np.minimum(np.maximum(np.asarray(weight, dtype=np.float64), 0.0), 1.0)
        w = (w[:, None] if several and w.ndim == 1 else w)[..., None]
        solved = w == 1.0
        if not _all(solved):  # solved or left as they are frame by frame (no interpolation), else blended
            new = np.where(solved[..., None], new, old) if _all(solved | (w == 0.0)) else quat.slerp(old, new, w)
    local_rotations[:, columns[..., :2]] = new
    if plan.all_carried:
        places, holders, middles = _place_carried(skeleton, local_rotations, root_translations, joint_translations,
                                                  limbs[:, 1], limbs[:, 2], carried_at)
        if end_rotation is not None or not keep_end:  # c hangs from a joint the limb does not turn
            if end_rotation is None:  # turned as b turned
                end_rotation = quat.multiply(quat.multiply(middles if several else middles[:, 0],
                                                           quat.conjugate(g_rot[..., 1, :])), g_rot[..., 2, :])
            end_rotation = np.asarray(end_rotation, dtype=np.float64)
            local_rotations[:, limbs[:, 2]] = quat.multiply(quat.conjugate(holders),
                                                            end_rotation if several else end_rotation[:, None])
        return (_norm((places if several else places[:, 0]) - T) if distance else None), None, None
    # Down from a's parent (which did not move) to c again: c's new parent rotation and position.
    rotation = new[..., 0, :] if parent_rot is None else quat.multiply(parent_rot, new[..., 0, :])
    paths = plan.paths
    assert paths is not None  # every limb solved here has its path (none is carried or solved apart)
    position = A if distance or ends else None
    if not several:
        position, rotation = _down(skeleton, local_rotations, joint_translations, paths[0], position, rotation)
    elif plan.steps is not None:  # all limbs step down together
        position, rotation = _down(skeleton, local_rotations, joint_translations, plan.steps, position, rotation)
    else:
        down = [_down(skeleton, local_rotations, joint_translations, p, None if position is None else position[:, i],
                      rotation[:, i]) for i, p in enumerate(paths)]
        position = np.stack([e[0] for e in down], axis=1) if position is not None else None
        rotation = np.stack([e[1] for e in down], axis=1)
    if keep_end or end_rotation is not None:
        target = g_rot[..., 2, :] if end_rotation is None else end_rotation
        local_rotations[:, columns[..., 2]] = quat.multiply(quat.conjugate(rotation), target)
    return (_norm(position - T) if distance and position is not None else None), (rotation if ends else None), \
        (position if ends else None)


def _pole_plane(normal: np.ndarray, toward: np.ndarray, sin_bend: np.ndarray) -> np.ndarray:
    """(..., 3) unit normals of the planes limbs with a pole bend in: their own ``normal`` (..., 3, unit,
    a->c x a->b), reflected onto the pole's side where it bends away from the pole (a knee bent
    backward: the far branch), and turned toward ``toward`` (..., 3, a->c x pole) as the limb comes
    straight (``sin_bend`` (...) the sine of its bend at b, from :data:`POLE_PLANE_SINE`): the plane
    of a limb within a few degrees of straight is noise, and so is the side a blend leaves it bent to."""
    lo, hi = POLE_PLANE_SINE
    if _all(sin_bend >= hi) and _all(_dot(normal, toward) >= 0.0):  # all bent enough, to the pole's side: their own
        return _unit(normal)
    p = _unit(toward)
    n = normal - 2.0 * np.minimum(_dot(normal, p), 0.0)[..., None] * p
    w = np.minimum(np.maximum((sin_bend - lo) / (hi - lo), 0.0), 1.0)
    w = (w * w * (3.0 - 2.0 * w))[..., None]
    return _unit(w * n + (1.0 - w) * p)


def _replaned(normal, plane, ac_ab_0, ac_ab_1, ba_bc_0, ba_bc_1, inverse) -> np.ndarray:
    """(N, 2, 4) local turns of a and b that straighten limbs bent in the plane of ``normal`` (N, 3) and
    bend them in the plane of ``plane`` (N, 3) to the solved angles: at a between a->c and a->b
    (``ac_ab_0`` now, ``ac_ab_1`` solved), at b between b->a and b->c (``ba_bc_*``), radians; c ends on
    the line a->c as with the limb's own plane. ``inverse`` (N, 2, 4): a's and b's global rotations
    conjugated (world turns to local ones)."""
    to_line = quat.from_axis_angle(normal, -ac_ab_0)
    at_a = quat.multiply(quat.from_axis_angle(plane, ac_ab_1), to_line)
    # b's turn in the frame before a turns: straighten about the old normal, bend about the new one
    # as it lies before a's turn.
    before = quat.rotate(quat.conjugate(to_line), plane)
    at_b = quat.multiply(quat.from_axis_angle(before, ba_bc_1 - np.pi), quat.from_axis_angle(normal, np.pi - ba_bc_0))
    world = np.stack((at_a, at_b), axis=-2)
    return quat.multiply(quat.multiply(inverse, world), quat.conjugate(inverse))


@dataclass(frozen=True)
class _LimbPlan:
    """What :func:`solve_limb` needs of its limbs on one skeleton, worked out once (a walk solves the same
    legs every block): ``limbs`` (K, 3), ``several`` (given as K triples), ``parents`` (K,) a's parents
    and ``hung`` (K,) whether a has one, ``offsets`` (K,) each carried end's offset or None and ``carried``
    (K,) whether it has one; ``paths`` (K,) the joints below a down to c, and ``steps`` (S, K) the same
    side by side when every path is as long (else None); no paths for carried ends or limbs solved apart;
    ``all_hung``, ``all_carried``: every a has a parent, every end is carried; ``apart``: the limbs are
    solved one by one (some are hung or carried and others not)."""

    limbs: np.ndarray
    several: bool
    parents: np.ndarray
    hung: np.ndarray
    offsets: list
    carried: np.ndarray
    paths: list | None
    steps: np.ndarray | None
    all_hung: bool
    all_carried: bool
    apart: bool


_PLANS: weakref.WeakKeyDictionary[Skeleton, dict[tuple, _LimbPlan]] = weakref.WeakKeyDictionary()


def _limb_plan(skeleton, joints) -> _LimbPlan:
    """The :class:`_LimbPlan` of ``joints`` (an (a, b, c) triple or K of them) on ``skeleton``, kept for
    the skeleton (raising as :func:`carried_offset` does for a limb that cannot be turned)."""
    limbs = np.asarray(joints, dtype=np.int64)
    key = (limbs.ndim, *limbs.ravel().tolist())
    known = _PLANS.setdefault(skeleton, {})
    plan = known.get(key)
    if plan is None:
        several = limbs.ndim == 2
        limbs = limbs.reshape(-1, 3)  # (K, 3)
        parents = skeleton.parents[limbs[:, 0]]
        hung = parents >= 0
        offsets = [carried_offset(skeleton, limb) for limb in limbs]
        carried = np.array([o is not None for o in offsets])
        paths = steps = None
        if not carried.any() and (hung.all() or not hung.any()):
            paths = [_path_below(skeleton, a, c) for a, _, c in limbs]
            if len({len(p) for p in paths}) == 1:
                steps = np.array(paths).T
        for shared in (limbs, parents, hung, carried):
            shared.flags.writeable = False
        all_hung, all_carried = bool(hung.all()), bool(carried.all())
        apart = (bool(hung.any()) and not all_hung) or (bool(carried.any()) and not all_carried)
        plan = known[key] = _LimbPlan(limbs, several, parents, hung, offsets, carried, paths, steps, all_hung, all_carried, apart)
    return plan


def _down(skeleton, local_rotations, joint_translations, steps, position, rotation):
    """Positions (F, [K,] 3) of the limbs' ends and their parents' global rotations (F, [K,] 4),
    stepping down ``steps`` (S, [K]) joints from the positions (None: not followed) and global
    rotations above them."""
    for i, js in enumerate(steps):
        if position is not None:
            offset = skeleton.rest_translations[js] if joint_translations is None else joint_translations[:, js]
            position = position + quat.rotate(rotation, offset)
        if i < len(steps) - 1:
            rotation = quat.multiply(rotation, local_rotations[:, js])
    return position, rotation


def _column(values, k: int, ndim: int):
    """Limb ``k``'s part of a per-limb argument: None, shared by every limb, or ``ndim``-dimensional
    with the limb axis second."""
    if values is None:
        return None
    values = np.asarray(values, dtype=np.float64)
    return values[:, k] if values.ndim == ndim else values


def _path_below(skeleton, top: int, bottom: int) -> list[int]:
    """The joints from just below ``top`` down to ``bottom`` (a descendant of ``top``), in order."""
    path = []
    j = int(bottom)
    while j != top:
        if j < 0:
            raise ValueError(f"joint {bottom} is not below joint {top}")
        path.append(j)
        j = int(skeleton.parents[j])
    return path[::-1]
