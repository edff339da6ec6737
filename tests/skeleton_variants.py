"""Generated variants of a labelled skeleton, for testing mappers on skeletons they have never seen.

Each variant returns a new :class:`~infuse.Skeleton`, optional poses moved along with it, and the
label mapping translated to the variant's joint names (canonical name -> joint name or None, plus
the alternatives). Variants:

- ``meaningless``: every joint renamed ``j<k>`` in a shuffled order (hierarchy and geometry only);
- ``rotated_*`` / ``scaled_*``: the whole body turned (lying on its back as if Z were up, facing -Z,
  facing +X) or scaled to centimetres, decimetres or inches;
- ``extra_joints``: a twist joint inserted in each upper arm and thigh, a leaf twist joint beside
  each elbow, a prop under each hand, an IK target at the root and a ground root above the pelvis,
  all with meaningless names;
- ``reordered``: children listed in reverse order (joint indices change);
- ``everything``: all of the above at once.
"""
from __future__ import annotations

import numpy as np

from infuse import Skeleton
from infuse import quaternions as quat

UNIT_FACTORS = {"cm": 100.0, "dm": 10.0, "inch": 1.0 / 0.0254}
ROTATIONS = {
    "z_up": quat.from_axis_angle(np.array([1.0, 0.0, 0.0]), np.pi / 2),   # +Y (up) becomes +Z
    "facing_-z": quat.from_axis_angle(np.array([0.0, 1.0, 0.0]), np.pi),
    "facing_+x": quat.from_axis_angle(np.array([0.0, 1.0, 0.0]), np.pi / 2),
}


class Variant:
    """A skeleton, its poses (F, J, 3) or None, and its expected mapping."""

    def __init__(self, name: str, skeleton: Skeleton, poses, mapping: dict, alternatives: dict, rename: dict):
        self.name = name
        self.skeleton = skeleton
        self.poses = poses
        self.mapping = mapping
        self.alternatives = alternatives
        self.rename = rename  # original joint name -> name in the variant (added joints are not keys)

    def translate(self, names) -> list[str]:
        """Original joint names -> their names in the variant, plus every joint the variant added."""
        added = set(self.skeleton.names) - set(self.rename.values())
        return [self.rename[n] for n in names if n in self.rename] + sorted(added)


def _from_positions(names, parents, positions, end_parents=(), end_positions=None) -> Skeleton:
    """A skeleton with identity rest rotations whose rest pose has these global positions (end sites
    given by their parent joint index and global position)."""
    parents = np.asarray(parents)
    positions = np.asarray(positions, dtype=np.float64)
    offsets = positions - np.where(parents[:, None] >= 0, positions[np.maximum(parents, 0)], 0.0)
    end_parents = np.asarray(end_parents, dtype=np.int64)
    end_offsets = (np.zeros((0, 3)) if end_positions is None or not len(end_parents)
                   else np.asarray(end_positions) - positions[end_parents])
    return Skeleton(tuple(names), parents, offsets, quat.identity((len(names),)), end_parents, end_offsets)


def _end_sites(skeleton: Skeleton) -> tuple[list[str], np.ndarray]:
    """End sites as (parent joint names, global rest positions)."""
    return [skeleton.names[p] for p in skeleton.end_site_parents], skeleton.rest_end_site_positions


def _translate(label: dict, rename: dict) -> tuple[dict, dict]:
    mapping = {k: (rename[v] if v is not None else None) for k, v in label["mapping"].items()}
    alts = {k: [rename[a] if a is not None else None for a in vals if a is None or a in rename]
            for k, vals in (label.get("alternatives") or {}).items()}
    return mapping, alts


def _identity(names) -> dict:
    return {n: n for n in names}


def meaningless(skeleton: Skeleton, poses, label: dict, seed: int = 0) -> Variant:
    rng = np.random.default_rng(seed)
    order = rng.permutation(skeleton.num_joints)
    rename = {n: f"j{order[i]}" for i, n in enumerate(skeleton.names)}
    sk = Skeleton(tuple(rename[n] for n in skeleton.names), skeleton.parents, skeleton.rest_translations,
                  skeleton.rest_rotations, skeleton.end_site_parents, skeleton.end_site_offsets)
    mapping, alts = _translate(label, rename)
    return Variant("meaningless", sk, poses, mapping, alts, rename)


def transformed(skeleton: Skeleton, poses, label: dict, rotation: str | None = None, unit: str | None = None) -> Variant:
    rot = ROTATIONS[rotation] if rotation else quat.IDENTITY
    scale = UNIT_FACTORS[unit] if unit else 1.0
    pos = quat.rotate(rot, skeleton.rest_global_positions) * scale
    ends = quat.rotate(rot, skeleton.rest_end_site_positions) * scale if len(skeleton.end_site_parents) else None
    sk = _from_positions(skeleton.names, skeleton.parents, pos, skeleton.end_site_parents, ends)
    new_poses = None if poses is None else quat.rotate(rot, np.asarray(poses)) * scale
    mapping, alts = _translate(label, _identity(skeleton.names))
    return Variant(f"{'rotated_' + rotation if rotation else ''}{'scaled_' + unit if unit else ''}", sk, new_poses,
                   mapping, alts, _identity(skeleton.names))


def _insert(names, parents, pos, poses, child: int, fraction: float, name: str):
    """Insert a joint on the bone into ``child`` at ``fraction`` of its length (lists updated in place)."""
    p = parents[child]
    new = len(names)
    names.append(name)
    parents.append(p)
    pos.append(pos[p] + fraction * (pos[child] - pos[p]))
    if poses is not None:
        poses.append(poses[p] + fraction * (poses[child] - poses[p]))
    parents[child] = new
    return new


def _leaf(names, parents, pos, poses, parent: int, offset, name: str):
    names.append(name)
    parents.append(parent)
    pos.append(pos[parent] + offset)
    if poses is not None:
        poses.append(poses[parent] + offset)
    return len(names) - 1


def _topological(names, parents, pos, poses, reverse_children: bool = False):
    """Reorder joints so parents precede children (depth first), optionally children reversed."""
    n = len(names)
    kids = [[] for _ in range(n)]
    roots = []
    for j, p in enumerate(parents):
        (kids[p] if p >= 0 else roots).append(j)
    order = []
    stack = list(roots if reverse_children else reversed(roots))
    while stack:
        j = stack.pop()
        order.append(j)
        stack.extend(kids[j] if reverse_children else reversed(kids[j]))
    index = {old: new for new, old in enumerate(order)}
    new_names = [names[j] for j in order]
    new_parents = [index[parents[j]] if parents[j] >= 0 else -1 for j in order]
    new_pos = np.array([pos[j] for j in order])
    new_poses = None if poses is None else np.stack([poses[j] for j in order], axis=-2)
    return new_names, new_parents, new_pos, new_poses


def extra_joints(skeleton: Skeleton, poses, label: dict) -> Variant:
    """Twist, prop, IK and ground-root joints added with meaningless names."""
    names = list(skeleton.names)
    parents = [int(p) for p in skeleton.parents]
    pos = list(skeleton.rest_global_positions)
    pose_list = None if poses is None else list(np.moveaxis(np.asarray(poses), -2, 0))
    idx = skeleton.index
    m = label["mapping"]
    height = skeleton.height()
    counter = iter(range(10_000))
    for side in ("l", "r"):
        for upper, lower in (("shoulder", "elbow"), ("hip", "knee")):
            a, b = m.get(f"{side}_{upper}"), m.get(f"{side}_{lower}")
            if a in idx and b in idx and parents[idx[b]] == idx[a]:
                _insert(names, parents, pos, pose_list, idx[b], 0.5, f"x{next(counter)}")
        e, w = m.get(f"{side}_elbow"), m.get(f"{side}_wrist")
        if e in idx and w in idx and m.get(f"{side}_forearm") is None:
            # a twist joint beside the elbow, halfway down the forearm (UE style): the canonical forearm
            fa = _leaf(names, parents, pos, pose_list, idx[e], 0.5 * (pos[idx[w]] - pos[idx[e]]), f"x{next(counter)}")
            label = {**label, "mapping": {**label["mapping"], f"{side}_forearm": names[fa]}}
        if w in idx:
            _leaf(names, parents, pos, pose_list, idx[w], np.array([0.0, -0.02, 0.02]) * height, f"x{next(counter)}")
    base = m.get("base")
    if base in idx:
        b = idx[base]
        root = int(skeleton.roots[0])
        _leaf(names, parents, pos, pose_list, root, np.array([0.1, -pos[root][1] + 0.05 * height, 0.0]) - 0.0,
              f"x{next(counter)}")
        if parents[b] < 0:  # a ground root above the pelvis
            g = len(names)
            names.append(f"x{next(counter)}")
            parents.append(-1)
            ground = np.array([pos[b][0], pos[b][1] - 0.55 * height, pos[b][2]])
            pos.append(ground)
            if pose_list is not None:
                pose_list.append(pose_list[b] * np.array([1.0, 0.0, 1.0]))
            parents[b] = g
    names, parents, pos_arr, pose_arr = _topological(names, parents, pos, pose_list)
    sk = _with_end_sites(skeleton, names, parents, pos_arr)
    mapping, alts = _translate(label, _identity(names))
    return Variant("extra_joints", sk, pose_arr, mapping, alts, _identity(skeleton.names))


def _with_end_sites(original: Skeleton, names, parents, positions) -> Skeleton:
    end_names, end_pos = _end_sites(original)
    index = {n: i for i, n in enumerate(names)}
    return _from_positions(names, parents, positions, [index[n] for n in end_names], end_pos if end_names else None)


def reordered(skeleton: Skeleton, poses, label: dict) -> Variant:
    pose_list = None if poses is None else list(np.moveaxis(np.asarray(poses), -2, 0))
    names, parents, pos, pose_arr = _topological(list(skeleton.names), [int(p) for p in skeleton.parents],
                                                 list(skeleton.rest_global_positions), pose_list, reverse_children=True)
    sk = _with_end_sites(skeleton, names, parents, pos)
    mapping, alts = _translate(label, _identity(names))
    return Variant("reordered", sk, pose_arr, mapping, alts, _identity(skeleton.names))


def all_variants(skeleton: Skeleton, poses, label: dict) -> list[Variant]:
    """Every variant of one labelled skeleton (see the module docstring)."""
    out = [meaningless(skeleton, poses, label)]
    for rot in ROTATIONS:
        out.append(transformed(skeleton, poses, label, rotation=rot))
    for unit in UNIT_FACTORS:
        out.append(transformed(skeleton, poses, label, unit=unit))
    out.append(extra_joints(skeleton, poses, label))
    out.append(reordered(skeleton, poses, label))
    combo = extra_joints(skeleton, poses, label)
    combo = reordered(combo.skeleton, combo.poses, {"mapping": combo.mapping, "alternatives": combo.alternatives})
    combo = transformed(combo.skeleton, combo.poses, {"mapping": combo.mapping, "alternatives": combo.alternatives},
                        rotation="facing_+x", unit="inch")
    combo = meaningless(combo.skeleton, combo.poses, {"mapping": combo.mapping, "alternatives": combo.alternatives}, seed=1)
    combo.name = "everything"
    combo.rename = {n: combo.rename[n] for n in skeleton.names}
    out.append(combo)
    return out
