"""Motion data transfer (paper, section 4.1): rotations through the canonical frame, root by leg length.

Both skeletons are aligned to the canonical T-pose (:mod:`.prepare`). A source joint's global
rotation ``G_s`` becomes a canonical-frame rotation ``D = G_s · (A_s · G_s,ref)⁻¹`` (the paper's
inverse re-orientation), and the target joint mapped to the same canonical name gets
``G_t = D · A_t · G_t,ref``. Taken locally this is the paper's ``q' = q_init · R_G⁻¹ · q · R_G``
with ``R_G = A_t · G_t,ref`` (see :mod:`.frames`); taken globally it needs no matching hierarchy in
between, which is what makes any-to-any work:

- a joint only one side has (a 5-joint spine against a 2-joint one, twist joints, a missing
  clavicle) follows the nearest joint both sides map; on a limb or spine chain it also takes its
  share of the twist between that joint and the next shared one, so twist joints share the
  rotation (the shoulder girdle is a chain of its own: a clavicle joint does not twist with the arm);
- a bone that spans joints the other side lacks turns as the source's span does when those joints
  bend it, so a 2-joint spine bends like a 5-joint one;
- a single clavicle faces a SmartBody pair (``l_sternoclavicular`` and ``l_acromioclavicular``; the
  first is found even when the mapping names only the second): it plays ``l_sternoclavicular``,
  the joint that turns the clavicle, so SmartBody reaches that shrug move it;
- joints above the base (ground roots) and joints no shared joint carries keep their default pose.

The root is placed by scaling the source's path by the leg-length ratio ``s``, measured where the
legs attach (the midpoint of the hip joints): horizontally about its first position, vertically
about the ground. The target base goes where that puts the target's own hip joints.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

from infuse import contacts
from infuse import quaternions as quat
from infuse.canonical import ALL_NAMES, canonical_joint
from infuse.errors import InputError, UnusableInputError, UsageError
from infuse.kinematics import forward_kinematics
from infuse.mesh import SkinnedMesh, sole_points
from infuse.motion import Motion
from infuse.skeleton import Skeleton

from . import cq
from .prepare import Prepared, prepare
from .rig import canonical_children, canonical_parent

#: Canonical names both skeletons must map.
REQUIRED = ("base", "l_hip", "l_knee", "l_ankle", "r_hip", "r_knee", "r_ankle")
#: Body groups whose joints form one chain for twist sharing.
FAMILY = {"torso": "axial", "neck": "axial", "head": "axial", "arm": "arm", "hand": "hand", "leg": "leg",
          "foot": "foot", "eye": "eye"}
#: Clavicle joints: the shoulder girdle, a chain of its own (it does not twist with the arm).
GIRDLE = ("l_sternoclavicular", "l_acromioclavicular", "r_sternoclavicular", "r_acromioclavicular")


def chain_family(name: str) -> str:
    """The chain a canonical joint shares twist along: axial, girdle, arm, hand, leg, foot or eye."""
    return "girdle" if name in GIRDLE else FAMILY[canonical_joint(name).group]


def infer_sternoclavicular(skeleton: Skeleton, index: dict[str, int]) -> dict[str, int]:
    """Name the sternal clavicle joint ``s_sternoclavicular`` where the mapping leaves it out: a
    single unmapped joint between the chest and a mapped ``s_acromioclavicular`` (SmartBody's
    skeletons; mapping rules send their lateral joint to ``s_acromioclavicular``)."""
    out = dict(index)
    mapped = set(index.values())
    for side in ("l", "r"):
        sc, ac = f"{side}_sternoclavicular", f"{side}_acromioclavicular"
        if ac not in index or sc in index:
            continue
        between = []
        j = int(skeleton.parents[index[ac]])
        while j >= 0 and j not in mapped:
            between.append(j)
            j = int(skeleton.parents[j])
        chest = canonical_parent(ac, index)
        if len(between) == 1 and chest is not None and j == index[chest]:
            out[sc] = between[0]
    return out


def correspond(source: dict[str, int], target: dict[str, int]) -> dict[str, str]:
    """Target canonical name -> the source canonical name that drives it, in table order.

    Names mapped on both sides drive themselves. A lone clavicle facing a SmartBody pair plays its
    sternal joint, the one that turns the clavicle: a target's only ``s_acromioclavicular`` follows
    the source's ``s_sternoclavicular``, and a source's only clavicle drives the target's
    ``s_sternoclavicular`` (the target's ``s_acromioclavicular`` then rides along).
    """
    pairs = {n: n for n in ALL_NAMES if n in source and n in target}
    for side in ("l", "r"):
        sc, ac = f"{side}_sternoclavicular", f"{side}_acromioclavicular"
        if ac in target and sc not in target and sc in source and ac in source:
            pairs[ac] = sc
        elif ac in source and sc not in source and sc in target and ac in target:
            pairs[sc] = ac
            del pairs[ac]
    return {n: pairs[n] for n in ALL_NAMES if n in pairs}


@dataclass
class Transferred:
    """The plain transfer of one clip, joint-major (see :mod:`.cq`): target global rotations
    (J, 4, F), the target base's path (3, F), the source's FK (Js, 4, F) / (Js, 3, F), the
    source's ground height (metres) and the frame rate."""

    rotations: np.ndarray
    base: np.ndarray
    source_rotations: np.ndarray
    source_positions: np.ndarray
    ground: float
    fps: float


class RetargetPlan:
    """Everything about a (source skeleton, target skeleton) pair that does not depend on the clip.

    Build it once and :meth:`transfer` many clips. ``*_mapping``: a
    :class:`~infuse.mapping.Mapping` or {canonical: joint name or index}. ``*_motion``: a clip on
    that skeleton whose most upright frame is the default pose when the rest is not a standing
    pose (Bandai's). ``*_file`` names the input in errors. ``target_meshes``: the target
    character's skinned meshes (:attr:`infuse.Asset.meshes`), which give a foot without a ball joint
    its heel and tip (:attr:`sole_points`).
    """

    def __init__(self, source_skeleton: Skeleton, source_mapping, target_skeleton: Skeleton, target_mapping, *,
                 source_motion: Motion | None = None, target_motion: Motion | None = None,
                 source_file=None, target_file=None, target_meshes: Sequence[SkinnedMesh] = ()):
        s_idx = contacts.joint_index(source_skeleton, source_mapping)
        t_idx = contacts.joint_index(target_skeleton, target_mapping)
        s_idx = infer_sternoclavicular(source_skeleton, s_idx)
        t_idx = infer_sternoclavicular(target_skeleton, t_idx)
        for which, idx, file in (("source", s_idx, source_file), ("target", t_idx, target_file)):
            missing = [n for n in REQUIRED if n not in idx]
            if missing:
                raise UnusableInputError(file, f"cannot retarget: the {which} mapping lacks {', '.join(missing)}")
        self.source: Prepared = prepare(source_skeleton, s_idx, source_motion, source_file)
        self.target: Prepared = prepare(target_skeleton, t_idx, target_motion, target_file)
        self.source_file = source_file
        #: Target canonical name -> source canonical name driving it (see :func:`correspond`).
        self.pairs = correspond(self.source.index, self.target.index)
        #: Target canonical names driven by the source.
        self.common = tuple(self.pairs)
        #: Target canonical name -> index of the source joint that drives it.
        self.source_joints = {t: self.source.index[s] for t, s in self.pairs.items()}
        #: Leg-length ratio, target over source.
        self.scale = self.target.leg_height / self.source.leg_height
        #: Per target foot, (2, 3) its heel and tip in its ankle's frame, from the mesh it carries
        #: (:func:`infuse.mesh.sole_points`), for a foot without a ball joint; else ``None``.
        self.sole_points = tuple(self._sole_points(foot, target_meshes) for foot in self.target.feet)
        self._build()

    def _sole_points(self, foot: contacts.Foot, meshes: Sequence[SkinnedMesh]) -> np.ndarray | None:
        """The heel and tip of a target foot from its mesh, posed as the reference pose; the foot
        heads square to the side-to-side axis its ankle carries (the canonical +X)."""
        if foot.ball is not None or not meshes:
            return None
        rig, tgt = self.target.rig, self.target
        lateral = quat.rotate(quat.multiply(rig.rotations[foot.ankle], quat.conjugate(tgt.frame[foot.ankle])),
                              np.array([1.0, 0.0, 0.0]))
        forward = np.cross(lateral, np.array([0.0, 1.0, 0.0]))
        return sole_points(meshes, rig.rotations, rig.positions, foot.joints, foot.ankle, forward)

    # -- structure ---------------------------------------------------------------------------------
    def _build(self) -> None:
        self._drivers()
        self._direction_fixes()
        self._followers()
        self._root()
        self._moving_joints()

    def _drivers(self) -> None:
        """Which shared canonical joint drives each target joint (``driver``), and the driven joints."""
        src, tgt = self.source, self.target
        parents = tgt.skeleton.parents
        common = set(self.common)
        driver: list[str | None] = [None] * len(parents)
        for j in range(len(parents)):
            own = tgt.rig.canonical_of.get(j)
            if own in common:
                driver[j] = own
            elif parents[j] >= 0:
                driver[j] = driver[parents[j]]
        #: (J,) canonical name whose motion drives each target joint (None: holds its default pose).
        self.driver = tuple(driver)
        driven = [j for j in range(len(parents)) if tgt.rig.canonical_of.get(j) in common]
        self._driven = np.array(driven, dtype=np.int64)
        self._driven_source = np.array([src.index[self.pairs[tgt.rig.canonical_of[j]]] for j in driven], dtype=np.int64)
        self._driven_offset = quat.multiply(quat.conjugate(src.frame[self._driven_source]), tgt.frame[self._driven])[:, :, None]

    def _direction_fixes(self) -> None:
        """Bones with one shared child: the target bone turns with the source's span to that child.

        Where the source has joints the target lacks between the two, the span bends with them
        while the target's single bone would only follow the span's start: the target bone takes
        the swing from the span's direction carried rigidly by its start (its aligned shape) to
        its actual direction. Between joints mapped on both sides with nothing in between the
        swing is nil; the target keeps its own build either way.
        """
        src, tgt = self.source, self.target
        kids = canonical_children(self.common)
        fix = []
        for name in self.common:
            if name == "base" or len(kids[name]) != 1:
                continue
            child = kids[name][0]
            s_joint, s_child = src.index[self.pairs[name]], src.index[self.pairs[child]]
            span = src.aligned[s_child] - src.aligned[s_joint]
            if np.linalg.norm(span) < 1e-6 or np.linalg.norm(tgt.aligned[tgt.index[child]] - tgt.aligned[tgt.index[name]]) < 1e-6:
                continue
            if s_joint == src.rig.position_parent[s_child]:
                continue  # nothing in between: the span is rigid
            b = quat.rotate(quat.conjugate(src.frame[s_joint]), span)  # the aligned span, in the source joint's frame
            fix.append((s_joint, s_child, tgt.index[name], b))
        self._fix_src = np.array([f[0] for f in fix], dtype=np.int64)
        self._fix_child = np.array([f[1] for f in fix], dtype=np.int64)
        self._fix_tgt = np.array([f[2] for f in fix], dtype=np.int64)
        self._fix_vec = np.array([f[3] for f in fix]).reshape(-1, 3, 1)

    def _followers(self) -> None:
        """Joints carried by a driven joint above them: rigidly, or taking a share of the twist to
        the one driven joint below them on the same limb or spine chain."""
        tgt = self.target
        parents = tgt.skeleton.parents
        j_count = len(parents)
        driven = set(self._driven.tolist())
        next_driven: list[set[int]] = [set() for _ in range(j_count)]
        for j in range(j_count - 1, -1, -1):
            if parents[j] >= 0:
                next_driven[parents[j]] |= {j} if j in driven else next_driven[j]
        ref = tgt.rig.positions
        seg = np.array([np.linalg.norm(ref[j] - ref[p]) if p >= 0 else 0.0 for j, p in enumerate(parents)])
        rigid, twisted = [], []
        for j in range(j_count):
            if self.driver[j] is None or j in driven:
                continue
            a = tgt.index[self.driver[j]]
            if len(next_driven[j]) == 1:
                d = next(iter(next_driven[j]))
                same_chain = chain_family(self.driver[j]) == chain_family(tgt.rig.canonical_of[d])
                total = _path_length(parents, seg, a, d)
                axis = tgt.aligned[d] - tgt.aligned[a]
                if same_chain and total > 1e-9 and np.linalg.norm(axis) > 1e-9:
                    twisted.append((j, a, d, _path_length(parents, seg, a, j) / total, axis / np.linalg.norm(axis)))
                    continue
            rigid.append((j, a))
        self._rigid = np.array([r[0] for r in rigid], dtype=np.int64)
        self._rigid_driver = np.array([r[1] for r in rigid], dtype=np.int64)
        self._rigid_offset = quat.multiply(quat.conjugate(tgt.frame[self._rigid_driver]), tgt.frame[self._rigid]).reshape(-1, 4, 1)
        self._tw = np.array([t[0] for t in twisted], dtype=np.int64)
        self._tw_a = np.array([t[1] for t in twisted], dtype=np.int64)
        self._tw_d = np.array([t[2] for t in twisted], dtype=np.int64)
        self._tw_fraction = np.array([t[3] for t in twisted]).reshape(-1, 1)
        self._tw_axis = np.array([t[4] for t in twisted]).reshape(-1, 3, 1)
        self._tw_frame = tgt.frame[self._tw].reshape(-1, 4, 1)
        self._tw_a_frame_inv = quat.conjugate(tgt.frame[self._tw_a]).reshape(-1, 4, 1)
        self._tw_d_frame_inv = quat.conjugate(tgt.frame[self._tw_d]).reshape(-1, 4, 1)
        self._static = np.array([j for j in range(j_count) if self.driver[j] is None], dtype=np.int64)

    def _root(self) -> None:
        """The base's top root carries the translation; joints between hold their default pose."""
        tgt = self.target
        parents = tgt.skeleton.parents
        base = tgt.index["base"]
        top = base
        while parents[top] >= 0:
            top = parents[top]
        self._top_root = int(top)
        at = tgt.rig.positions_of(tgt.rig.rotations[:, :, None], {top: np.zeros((3, 1))}, joints=[base])
        self._base_offset = at[base][:, 0]
        self._detached = tuple(tgt.rig.detached)

    def _moving_joints(self) -> None:
        """A joint carried rigidly with its parent (both by the same driven joint, or both holding
        their default pose) keeps its reference local rotation: only the others are computed, and
        global rotations only where positions are asked for (legs, arms, feet, detached joints and
        the paths to them) or a computed local rotation needs them."""
        tgt = self.target
        sk = tgt.skeleton
        parents = sk.parents
        j_count = len(parents)
        group = np.full(j_count, -1, dtype=np.int64)
        group[self._driven] = self._driven
        group[self._rigid] = self._rigid_driver
        group[self._tw] = self._tw
        own = np.where(parents >= 0, group[np.maximum(parents, 0)], -1)
        varying = (group != own) & ~((parents < 0) & (group == -1))
        self._varying = np.nonzero(varying & (parents >= 0))[0]
        self._varying_roots = np.nonzero(varying & (parents < 0))[0]
        ref = tgt.rig.rotations
        fixed_local = np.array(ref)
        child = parents >= 0
        fixed_local[child] = quat.multiply(quat.conjugate(ref[parents[child]]), ref[child])
        self._fixed = np.nonzero(~varying)[0]
        self._fixed_local = fixed_local[self._fixed][:, :, None]
        seeds = set(self._varying.tolist()) | {int(parents[j]) for j in self._varying} | set(self._detached)
        seeds |= {int(parents[j]) for j in self._detached if parents[j] >= 0}
        for foot in tgt.feet:
            seeds |= set(foot.joints) | {int(sk.end_site_parents[e]) for e in foot.end_sites}
        seeds |= {tgt.index[n] for n in tgt.index if n.endswith(("_shoulder", "_elbow", "_wrist", "_hip", "_knee")) or n == "base"}
        needed = np.zeros(j_count, dtype=bool)
        for j in seeds:
            while j >= 0 and not needed[j]:
                needed[j] = True
                j = int(tgt.rig.position_parent[j])
        keep = needed[self._rigid]
        self._rigid, self._rigid_driver, self._rigid_offset = self._rigid[keep], self._rigid_driver[keep], self._rigid_offset[keep]
        self._static = self._static[needed[self._static]]
        #: (J,) True for joints whose global rotation :meth:`transfer` computes.
        self.computed = np.zeros(j_count, dtype=bool)
        for arr in (self._driven, self._rigid, self._tw, self._static):
            self.computed[arr] = True

    # -- per clip ----------------------------------------------------------------------------------
    def check_source(self, motion: Motion) -> None:
        sk = self.source.skeleton
        if motion.skeleton is not sk and (motion.skeleton.names != sk.names or not np.array_equal(motion.skeleton.parents, sk.parents)):
            raise UsageError("the clip is not on the skeleton this retarget plan was built for")
        if motion.num_frames == 0:
            raise UnusableInputError(self.source_file, f"clip {motion.name!r} has no frames")

    def transfer(self, motion: Motion, fk=None) -> Transferred:
        """The plain transfer of ``motion`` (on the source skeleton): target global rotations and base path.

        ``fk``: the source clip's joint-major FK, ``(rotations (Js, 4, F), positions (Js, 3, F))``,
        if already computed. Arrays in the result are joint-major too (see :mod:`.cq`).
        """
        self.check_source(motion)
        tgt = self.target
        if fk is None:
            fk = forward_kinematics(motion.skeleton, motion.local_rotations, motion.root_translations,
                                    motion.joint_translations, joint_major=True)
        gs, ps = fk
        frames = motion.num_frames
        g = np.empty((tgt.skeleton.num_joints, 4, frames))
        g[self._driven] = cq.mul(gs[self._driven_source], self._driven_offset)
        if len(self._fix_tgt):
            current = cq.rotate(gs[self._fix_src], self._fix_vec)
            wanted = ps[self._fix_child] - ps[self._fix_src]
            g[self._fix_tgt] = cq.mul(cq.between(current, wanted), g[self._fix_tgt])
        if len(self._rigid):
            g[self._rigid] = cq.mul(g[self._rigid_driver], self._rigid_offset)
        if len(self._tw):
            d_a = cq.mul(g[self._tw_a], self._tw_a_frame_inv)  # canonical-frame D of the driver
            d_d = cq.mul(g[self._tw_d], self._tw_d_frame_inv)
            share = cq.twist_power(cq.mul(cq.conj(d_a), d_d), self._tw_axis, self._tw_fraction)
            g[self._tw] = cq.mul(d_a, cq.mul(share, self._tw_frame))
        if len(self._static):
            g[self._static] = tgt.rig.rotations[self._static][:, :, None]
        src = self.source.index
        lowest = contacts.lowest_points(self.source.skeleton, self.source.feet, gs.transpose(2, 0, 1), ps.transpose(2, 0, 1))
        ground = contacts.estimate_ground(lowest)
        src_hips = 0.5 * (ps[src["l_hip"]] + ps[src["r_hip"]])
        hips = np.empty_like(src_hips)
        hips[[0, 2]] = src_hips[[0, 2], :1] + self.scale * (src_hips[[0, 2]] - src_hips[[0, 2], :1])
        hips[1] = ground + self.scale * (src_hips[1] - ground)
        legs = [tgt.index["l_hip"], tgt.index["r_hip"], tgt.index["base"]]
        at = tgt.rig.positions_of(g, {self._top_root: np.zeros((3, 1))}, legs)
        base = hips - (0.5 * (at[legs[0]] + at[legs[1]]) - at[legs[2]])
        return Transferred(g, base, gs, ps, ground, motion.fps)

    def canonical_delta(self, rotations: np.ndarray, name: str) -> np.ndarray:
        """(4, F) canonical-frame rotation ``D`` of target joint ``name`` from global ``rotations`` (J, 4, F)."""
        j = self.target.index[name]
        return cq.mul(rotations[j], quat.conjugate(self.target.frame[j])[:, None])

    def root_positions(self, base: np.ndarray) -> dict[int, np.ndarray]:
        """{top root joint: (3, F)} placing the target base on ``base`` (3, F)."""
        return {self._top_root: base - self._base_offset[:, None]}

    def positions(self, state: Transferred, joints=None) -> dict[int, np.ndarray]:
        """Target global positions {joint: (3, F)} of ``joints`` (default all) for a transferred state."""
        return self.target.rig.positions_of(state.rotations, self.root_positions(state.base), joints)

    def to_motion(self, state: Transferred, like: Motion) -> Motion:
        """The target :class:`Motion` for global ``state`` (fps, name and sync points from ``like``)."""
        sk = self.target.skeleton
        g = state.rotations
        frames = g.shape[-1]
        parents = sk.parents
        local = np.empty_like(g)
        local[self._fixed] = self._fixed_local
        local[self._varying_roots] = g[self._varying_roots]
        local[self._varying] = cq.mul_inv(g[parents[self._varying]], g[self._varying])
        moving = np.concatenate((self._varying_roots, self._varying))
        local[moving] = cq.make_continuous(local[moving])
        roots = self.root_positions(state.base)
        joint_translations = None
        if self._top_root == 0:
            root_translations = roots[0].T
        else:
            root_translations = np.broadcast_to(sk.rest_translations[0], (frames, 3))
        if self._top_root != 0 or self._detached:
            joint_translations = np.broadcast_to(sk.rest_translations, (frames,) + sk.rest_translations.shape).copy()
            joint_translations[:, self._top_root] = roots[self._top_root].T
            if self._detached:
                need = set(self._detached) | {int(parents[j]) for j in self._detached if parents[j] >= 0}
                pos = self.target.rig.positions_of(g, roots, sorted(need))
                for j in self._detached:
                    p = parents[j]
                    offset = pos[j] if p < 0 else cq.rotate(cq.conj(g[p]), pos[j] - pos[p])
                    joint_translations[:, j] = np.broadcast_to(offset, (3, frames)).T
        try:
            return Motion(sk, like.fps, local.transpose(2, 0, 1), root_translations, joint_translations, name=like.name,
                          sync_points=dict(like.sync_points))
        except InputError as exc:  # NaN from a degenerate rig, not from the file
            raise UnusableInputError(self.source_file, f"retargeting produced non-finite values ({exc.problem})") from None


def _path_length(parents: np.ndarray, seg: np.ndarray, ancestor: int, j: int) -> float:
    total = 0.0
    while j != ancestor and j >= 0:
        total += seg[j]
        j = parents[j]
    return total
