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
- ``convention_*``: the labelled joints renamed into another naming convention (Mixamo with its
  namespace, Unreal, Blender ``.L``/``.R``), the other joints keep their names;
- ``prefixed``: every name behind a namespace and a studio prefix (``Char01:rig_``);
- ``a_pose`` / ``t_pose`` / ``arms_down``: the arms turned about the shoulders in the body's
  frontal plane to 45 degrees below the horizontal, to the horizontal or to 80 degrees below it
  (the rest pose changes, the motion does not);
- ``rest_rotations``: random local rest rotations with the same joint positions;
- ``named_helpers``: zero-length roll joints after each upper arm, forearm, thigh and shin
  (MotionBuilder style, named ``<joint>Roll``), a named IK target and pole per hand and foot;
- ``no_fingers`` / ``no_clavicles`` / ``no_neck``: those joints removed (children re-parented);
- ``no_toes``: the toe joints removed, each foot ending in an end site where its toes' tip was;
- ``mirrored_names``: every left joint takes the name of its right counterpart and vice versa
  (geometry must decide the sides);
- ``cartoon`` / ``cartoon_arms_down``: cartoon proportions (arms 1.35 times as long, legs 0.65
  times, the head 1.8 times as big); the second also with the arms hanging 85 degrees down (the hands reach
  below the feet), lying as if Z were up and facing +X;
- ``everything``: extra joints, reordered, turned, rescaled and renamed at once.

:func:`non_humanoid_variants` makes bodies a mapper must refuse from the same skeletons: ``no_legs``
(both legs and what hangs from them removed: a flying head or trunk with arms) and ``no_arms``
(both arms removed: legs and a trunk).
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

    def __init__(self, name: str, skeleton: Skeleton, poses, mapping: dict, alternatives: dict, rename: dict,
                 humanoid: bool = True):
        self.name = name
        self.humanoid = humanoid  # False: a body without two legs and two arms, to be refused
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


#: Canonical name -> joint name in other conventions ("{s}"/"{S}"/"{Side}": side letter, capital, word).
CONVENTIONS: dict[str, dict[str, str]] = {
    "mixamo": {"base": "mixamorig:Hips", "spine1": "mixamorig:Spine", "spine2": "mixamorig:Spine1",
               "spine3": "mixamorig:Spine2", "spine4": "mixamorig:Neck", "spine5": "mixamorig:Neck1",
               "skullbase": "mixamorig:Head", "eyeball": "mixamorig:{Side}Eye",
               "acromioclavicular": "mixamorig:{Side}Shoulder", "shoulder": "mixamorig:{Side}Arm",
               "elbow": "mixamorig:{Side}ForeArm", "forearm": "mixamorig:{Side}ForeArmTwist",
               "wrist": "mixamorig:{Side}Hand", "finger": "mixamorig:{Side}Hand{Finger}{k}",
               "hip": "mixamorig:{Side}UpLeg", "knee": "mixamorig:{Side}Leg", "ankle": "mixamorig:{Side}Foot",
               "forefoot": "mixamorig:{Side}ToeBase", "toe": "mixamorig:{Side}Toe_End"},
    "unreal": {"base": "pelvis", "spine1": "spine_01", "spine2": "spine_02", "spine3": "spine_03",
               "spine4": "neck_01", "spine5": "neck_02", "skullbase": "head", "eyeball": "eye_{s}",
               "acromioclavicular": "clavicle_{s}", "shoulder": "upperarm_{s}", "elbow": "lowerarm_{s}",
               "forearm": "lowerarm_twist_01_{s}", "wrist": "hand_{s}", "finger": "{finger}_0{k}_{s}",
               "hip": "thigh_{s}", "knee": "calf_{s}", "ankle": "foot_{s}", "forefoot": "ball_{s}",
               "toe": "toe_end_{s}"},
    "blender": {"base": "hips", "spine1": "spine", "spine2": "spine.001", "spine3": "chest", "spine4": "neck",
                "spine5": "neck.001", "skullbase": "head", "eyeball": "eye.{S}", "acromioclavicular": "shoulder.{S}",
                "shoulder": "upper_arm.{S}", "elbow": "forearm.{S}", "forearm": "forearm_twist.{S}",
                "wrist": "hand.{S}", "finger": "f_{finger}.0{k}.{S}", "hip": "thigh.{S}", "knee": "shin.{S}",
                "ankle": "foot.{S}", "forefoot": "toe.{S}", "toe": "toe_end.{S}"},
}
FINGERS = ("thumb", "index", "middle", "ring", "pinky")


def _convention_name(table: dict, canonical: str) -> str:
    if canonical in table:
        return table[canonical]
    if canonical.startswith("eyeball_"):
        side = canonical[len("eyeball_"):]
        return table["eyeball"].format(s=side[0], S=side[0].upper(), Side=side.capitalize())
    side, rest = canonical.split("_", 1)
    fields = {"s": side, "S": side.upper(), "Side": "Left" if side == "l" else "Right"}
    if rest[:-1] in FINGERS:
        return table["finger"].format(finger=rest[:-1], Finger=rest[:-1].capitalize(), k=rest[-1], **fields)
    return table[rest].format(**fields)


def _renamed(skeleton: Skeleton, poses, label: dict, rename: dict, name: str) -> Variant:
    sk = Skeleton(tuple(rename[n] for n in skeleton.names), skeleton.parents, skeleton.rest_translations,
                  skeleton.rest_rotations, skeleton.end_site_parents, skeleton.end_site_offsets)
    mapping, alts = _translate(label, rename)
    return Variant(name, sk, poses, mapping, alts, rename)


def convention(skeleton: Skeleton, poses, label: dict, table: str) -> Variant:
    """The labelled joints renamed into another convention; the other joints keep their names
    (with a suffix when a new name is taken)."""
    conv = CONVENTIONS[table]
    rename = {v: _convention_name(conv, k) for k, v in label["mapping"].items() if v is not None}
    used = set(rename.values())
    for n in skeleton.names:
        if n not in rename:
            rename[n] = n if n not in used else f"{n}_extra"
    return _renamed(skeleton, poses, label, rename, f"convention_{table}")


def prefixed(skeleton: Skeleton, poses, label: dict) -> Variant:
    rename = {n: f"Char01:rig_{n}" for n in skeleton.names}
    return _renamed(skeleton, poses, label, rename, "prefixed")


def mirrored_names(skeleton: Skeleton, poses, label: dict) -> Variant:
    """Each labelled left joint takes its right counterpart's name and vice versa; the expected
    mapping follows the joints, not the names."""
    m = label["mapping"]
    rename = {n: n for n in skeleton.names}
    for k, v in m.items():
        other = "r_" + k[2:] if k.startswith("l_") else "eyeball_right" if k == "eyeball_left" else None
        if other and v is not None and m.get(other) is not None and m[other] != v:
            rename[v], rename[m[other]] = m[other], v
    return _renamed(skeleton, poses, label, rename, "mirrored_names")


def _body_axes(positions: np.ndarray, index: dict, m: dict) -> tuple[np.ndarray, np.ndarray] | None:
    """(up, left) unit vectors of a labelled body from its rest positions, or None."""
    need = ("base", "l_shoulder", "r_shoulder")
    if any(m.get(k) not in index for k in need):
        return None
    shoulders = positions[[index[m["l_shoulder"]], index[m["r_shoulder"]]]]
    left = shoulders[0] - shoulders[1]
    up = shoulders.mean(axis=0) - positions[index[m["base"]]]
    up = up - (up @ left) / max(left @ left, 1e-12) * left
    if np.linalg.norm(up) < 1e-9 or np.linalg.norm(left) < 1e-9:
        return None
    return up / np.linalg.norm(up), left / np.linalg.norm(left)


def _subtree(skeleton: Skeleton, j: int) -> list[int]:
    out, stack = [], [j]
    while stack:
        k = stack.pop()
        out.append(k)
        stack.extend(skeleton.children[k])
    return out


def arms_posed(skeleton: Skeleton, poses, label: dict, elevation_deg: float, name: str) -> Variant:
    """Each arm turned about its shoulder in the body's frontal plane until the shoulder-to-wrist line
    is ``elevation_deg`` above the horizontal (0: T-pose, -45: A-pose)."""
    pos = skeleton.rest_global_positions.copy()
    ends = skeleton.rest_end_site_positions.copy() if len(skeleton.end_site_parents) else None
    m, idx = label["mapping"], skeleton.index
    axes = _body_axes(pos, idx, m)
    if axes is not None:
        up, left = axes
        forward = np.cross(left, up)
        for side, outward in (("l", left), ("r", -left)):
            shoulder = idx[m[f"{side}_shoulder"]]
            hand = idx.get(m.get(f"{side}_wrist") or m.get(f"{side}_elbow"))
            if hand is None:
                continue
            d = pos[hand] - pos[shoulder]
            now = np.arctan2(d @ up, d @ outward)
            turn = np.radians(elevation_deg) - now
            # about +forward a positive angle raises the left arm and lowers the right one
            q = quat.from_axis_angle(forward, turn if side == "l" else -turn)
            moved = _subtree(skeleton, shoulder)
            pos[moved] = pos[shoulder] + quat.rotate(q, pos[moved] - pos[shoulder])
            if ends is not None:
                sel = np.isin(skeleton.end_site_parents, moved)
                ends[sel] = pos[shoulder] + quat.rotate(q, ends[sel] - pos[shoulder])
    sk = _from_positions(skeleton.names, skeleton.parents, pos, skeleton.end_site_parents, ends)
    mapping, alts = _translate(label, _identity(skeleton.names))
    return Variant(name, sk, poses, mapping, alts, _identity(skeleton.names))


def rest_rotations(skeleton: Skeleton, poses, label: dict, seed: int = 0) -> Variant:
    """Random local rest rotations; local offsets chosen so every joint keeps its rest position."""
    rng = np.random.default_rng(seed)
    n = skeleton.num_joints
    local = quat.normalize(rng.normal(size=(n, 4)))
    world = local.copy()
    parents = skeleton.parents
    for j in range(n):
        if parents[j] >= 0:
            world[j] = quat.multiply(world[parents[j]], local[j])
    pos = skeleton.rest_global_positions
    has_parent = parents >= 0
    offsets = pos.copy()
    offsets[has_parent] = quat.rotate(quat.conjugate(world[parents[has_parent]]),
                                      pos[has_parent] - pos[parents[has_parent]])
    end_offsets = skeleton.end_site_offsets
    if len(skeleton.end_site_parents):
        ep = skeleton.end_site_parents
        end_offsets = quat.rotate(quat.conjugate(world[ep]), skeleton.rest_end_site_positions - pos[ep])
    sk = Skeleton(skeleton.names, parents, offsets, local, skeleton.end_site_parents, end_offsets)
    mapping, alts = _translate(label, _identity(skeleton.names))
    return Variant("rest_rotations", sk, poses, mapping, alts, _identity(skeleton.names))


def named_helpers(skeleton: Skeleton, poses, label: dict) -> Variant:
    """Zero-length ``<joint>Roll`` joints right after each upper arm, forearm, thigh and shin, and a
    named IK target and pole for each hand and foot under the root."""
    names = list(skeleton.names)
    parents = [int(p) for p in skeleton.parents]
    pos = list(skeleton.rest_global_positions)
    pose_list = None if poses is None else list(np.moveaxis(np.asarray(poses), -2, 0))
    idx = skeleton.index
    m = label["mapping"]
    root = int(skeleton.roots[0])
    height = skeleton.height()
    alternatives = {k: list(v) for k, v in (label.get("alternatives") or {}).items()}
    for side in ("l", "r"):
        for upper, lower in (("shoulder", "elbow"), ("elbow", "wrist"), ("hip", "knee"), ("knee", "ankle")):
            a, b = m.get(f"{side}_{upper}"), m.get(f"{side}_{lower}")
            if a in idx and b in idx and parents[idx[b]] == idx[a]:
                _insert(names, parents, pos, pose_list, idx[b], 0.0, f"{a}Roll")
                if upper == "elbow" and m.get(f"{side}_forearm") is None:
                    # the first twist joint after the elbow is the canonical forearm (null accepted)
                    m = {**m, f"{side}_forearm": f"{a}Roll"}
                    alternatives[f"{side}_forearm"] = [None]
        for end in ("wrist", "ankle"):
            j = m.get(f"{side}_{end}")
            if j in idx:
                _leaf(names, parents, pos, pose_list, root, pos[idx[j]] - pos[root], f"{j}_IK_target")
                _leaf(names, parents, pos, pose_list, root, pos[idx[j]] - pos[root]
                      + np.array([0.0, 0.1, 0.3]) * height, f"{j}_IK_pole")
    names, parents, pos_arr, pose_arr = _topological(names, parents, pos, pose_list)
    sk = _with_end_sites(skeleton, names, parents, pos_arr)
    mapping, alts = _translate({"mapping": m, "alternatives": alternatives}, _identity(names))
    return Variant("named_helpers", sk, pose_arr, mapping, alts, _identity(skeleton.names))


def removed(skeleton: Skeleton, poses, label: dict, kind: str) -> Variant:
    """The fingers (with everything below them), the clavicles or the neck joints removed; the
    children of a removed joint hang from its parent."""
    m = label["mapping"]
    idx = skeleton.index
    drop: set[int] = set()
    if kind == "fingers":
        for k, j in m.items():
            if k[2:-1] in FINGERS and j in idx:
                drop.update(_subtree(skeleton, idx[j]))
    elif kind in LIMB_PARTS:  # the limb from its first long bone down, and IK-driven ends hanging elsewhere
        for k, j in m.items():
            if k[:2] in ("l_", "r_") and _part(k) in LIMB_PARTS[kind] and j in idx:
                drop.update(_subtree(skeleton, idx[j]))
    elif kind == "clavicles":  # every joint between the torso and each upper arm (both ends of a clavicle)
        trunk = {idx[m[k]] for k in ("base", "spine1", "spine2", "spine3", "spine4", "spine5") if m.get(k) in idx}
        for side in "lr":
            if m.get(f"{side}_shoulder") in idx:
                j = int(skeleton.parents[idx[m[f"{side}_shoulder"]]])
                while j >= 0 and j not in trunk:
                    drop.add(j)
                    j = int(skeleton.parents[j])
                if j < 0:  # no torso joint above the arm: keep the tree as it was
                    drop.clear()
                    break
    else:  # every joint between the chest and the head
        head, chest = idx.get(m.get("skullbase")), idx.get(m.get("spine3") or m.get("base"))
        path, j = [], int(skeleton.parents[head]) if head is not None else -1
        while j >= 0 and j != chest:
            path.append(j)
            j = int(skeleton.parents[j])
        if chest is not None and j == chest:
            drop.update(path)
    keep = [j for j in range(skeleton.num_joints) if j not in drop]
    new_index = {old: i for i, old in enumerate(keep)}
    pos = skeleton.rest_global_positions
    parents = []
    for j in keep:
        p = int(skeleton.parents[j])
        while p >= 0 and p not in new_index:
            p = int(skeleton.parents[p])
        parents.append(new_index[p] if p >= 0 else -1)
    kept_names = [skeleton.names[j] for j in keep]
    ends = [(int(e), q) for e, q in zip(skeleton.end_site_parents, skeleton.rest_end_site_positions) if e in new_index]
    sk = _from_positions(kept_names, parents, pos[keep], [new_index[e] for e, _ in ends],
                         np.array([q for _, q in ends]) if ends else None)
    new_poses = None if poses is None else np.asarray(poses)[..., keep, :]
    gone = {skeleton.names[j] for j in drop}
    expected = {"mapping": {k: (None if v in gone else v) for k, v in m.items()},
                "alternatives": {k: [a for a in vals if a not in gone]
                                 for k, vals in (label.get("alternatives") or {}).items()}}
    mapping, alts = _translate(expected, _identity(kept_names))
    rename = {n: n for n in kept_names}
    return Variant(f"no_{kind}", sk, new_poses, mapping, alts, rename, humanoid=kind not in LIMB_PARTS)


def toeless(skeleton: Skeleton, poses, label: dict) -> Variant:
    """The toes removed (each foot's forefoot or toe joint with everything below it), each foot
    ending instead in an end site at the removed point farthest from its ankle: a rigid foot, as
    rigs without toe joints have."""
    m = label["mapping"]
    idx = skeleton.index
    drop: set[int] = set()
    tips: list[tuple[int, np.ndarray]] = []
    ends = skeleton.rest_end_site_positions
    pos = skeleton.rest_global_positions
    for side in "lr":
        ankle = idx.get(m.get(f"{side}_ankle"))
        toe = idx.get(m.get(f"{side}_forefoot") or m.get(f"{side}_toe"))
        if ankle is None or toe is None:
            continue
        gone = _subtree(skeleton, toe)
        drop.update(gone)
        points = np.concatenate((pos[gone], ends[np.isin(skeleton.end_site_parents, gone)]))
        tips.append((ankle, points[np.argmax(np.linalg.norm(points - pos[ankle], axis=1))]))
    keep = [j for j in range(skeleton.num_joints) if j not in drop]
    new_index = {old: i for i, old in enumerate(keep)}
    parents = [new_index[int(skeleton.parents[j])] if skeleton.parents[j] >= 0 else -1 for j in keep]
    kept = [(int(e), q) for e, q in zip(skeleton.end_site_parents, ends) if e in new_index] + tips
    sk = _from_positions([skeleton.names[j] for j in keep], parents, pos[keep], [new_index[e] for e, _ in kept],
                         np.array([q for _, q in kept]) if kept else None)
    gone_names = {skeleton.names[j] for j in drop}
    expected = {"mapping": {k: (None if v in gone_names else v) for k, v in m.items()},
                "alternatives": {k: [a for a in vals if a not in gone_names]
                                 for k, vals in (label.get("alternatives") or {}).items()}}
    mapping, alts = _translate(expected, _identity(sk.names))
    new_poses = None if poses is None else np.asarray(poses)[..., keep, :]
    return Variant("no_toes", sk, new_poses, mapping, alts, {n: n for n in sk.names})


#: The canonical parts (after the side) of each limb, from its first long bone down.
LIMB_PARTS = {
    "legs": frozenset({"hip", "knee", "ankle", "forefoot", "toe"}),
    "arms": frozenset({"shoulder", "elbow", "forearm", "wrist"} | set(FINGERS)),
}


def _part(canonical: str) -> str:
    """``l_index2`` -> ``index``, ``r_knee`` -> ``knee``: the part of a sided canonical name."""
    rest = canonical[2:]
    return rest[:-1] if rest[:-1] in FINGERS else rest


def proportioned(skeleton: Skeleton, poses, label: dict, factors: dict[str, float], name: str) -> Variant:
    """Body parts scaled about their first joint: ``factors`` maps "arms", "legs" or "head" to a
    length factor. A limb is everything below its upper arm or thigh joint plus its labelled joints
    hanging elsewhere (IK-driven hands and feet); the head everything below the head joint. Poses
    are scaled the same way about the same joints in every frame."""
    m, idx = label["mapping"], skeleton.index
    pos = skeleton.rest_global_positions.copy()
    ends = skeleton.rest_end_site_positions.copy() if len(skeleton.end_site_parents) else None
    new_poses = None if poses is None else np.array(poses, dtype=np.float64, copy=True)
    groups = []  # (pivot joint, moved joints, factor)
    for part, factor in factors.items():
        if part == "head":
            if m.get("skullbase") in idx:
                head = idx[m["skullbase"]]
                groups.append((head, set(_subtree(skeleton, head)) - {head}, factor))
            continue
        first = "hip" if part == "legs" else "shoulder"
        for side in ("l", "r"):
            if m.get(f"{side}_{first}") not in idx:
                continue
            pivot = idx[m[f"{side}_{first}"]]
            moved = set(_subtree(skeleton, pivot))
            for k, j in m.items():
                if k.startswith(f"{side}_") and _part(k) in LIMB_PARTS[part] and j in idx:
                    moved.update(_subtree(skeleton, idx[j]))
            groups.append((pivot, moved - {pivot}, factor))
    for pivot, moved, factor in groups:
        sel = np.array(sorted(moved), dtype=np.int64)
        pos[sel] = pos[pivot] + factor * (pos[sel] - pos[pivot])
        if ends is not None:
            e = np.isin(skeleton.end_site_parents, sel)
            ends[e] = pos[pivot] + factor * (ends[e] - skeleton.rest_global_positions[pivot])
        if new_poses is not None:
            new_poses[..., sel, :] = new_poses[..., [pivot], :] + factor * (new_poses[..., sel, :]
                                                                            - new_poses[..., [pivot], :])
    sk = _from_positions(skeleton.names, skeleton.parents, pos, skeleton.end_site_parents, ends)
    mapping, alts = _translate(label, _identity(skeleton.names))
    return Variant(name, sk, new_poses, mapping, alts, _identity(skeleton.names))


CARTOON = {"arms": 1.35, "legs": 0.65, "head": 1.8}


def non_humanoid_variants(skeleton: Skeleton, poses, label: dict) -> list[Variant]:
    """Bodies without two legs and two arms made from one labelled humanoid skeleton: to be refused.
    Only limbs whose first two joints are labelled on both sides are removed (a label of a motion
    file that animates only the face has none)."""
    m = label["mapping"]
    firsts = {"legs": ("hip", "knee"), "arms": ("shoulder", "elbow")}
    return [removed(skeleton, poses, label, kind) for kind, parts in firsts.items()
            if all(m.get(f"{side}_{part}") in skeleton.index for side in "lr" for part in parts)]


def all_variants(skeleton: Skeleton, poses, label: dict) -> list[Variant]:
    """Every variant of one labelled skeleton (see the module docstring)."""
    out = [meaningless(skeleton, poses, label)]
    for rot in ROTATIONS:
        out.append(transformed(skeleton, poses, label, rotation=rot))
    for unit in UNIT_FACTORS:
        out.append(transformed(skeleton, poses, label, unit=unit))
    out.append(extra_joints(skeleton, poses, label))
    out.append(reordered(skeleton, poses, label))
    for table in CONVENTIONS:
        out.append(convention(skeleton, poses, label, table))
    out.append(prefixed(skeleton, poses, label))
    out.append(arms_posed(skeleton, poses, label, -45.0, "a_pose"))
    out.append(arms_posed(skeleton, poses, label, 0.0, "t_pose"))
    out.append(arms_posed(skeleton, poses, label, -80.0, "arms_down"))
    out.append(rest_rotations(skeleton, poses, label))
    out.append(named_helpers(skeleton, poses, label))
    for kind in ("fingers", "clavicles", "neck"):
        out.append(removed(skeleton, poses, label, kind))
    out.append(mirrored_names(skeleton, poses, label))
    out.append(proportioned(skeleton, poses, label, CARTOON, "cartoon"))
    cartoon = proportioned(skeleton, poses, label, CARTOON, "cartoon")
    down = arms_posed(cartoon.skeleton, cartoon.poses, label, -85.0, "cartoon_arms_down")
    for rot in ("z_up", "facing_+x"):
        down = transformed(down.skeleton, down.poses, label, rotation=rot)
    down.name = "cartoon_arms_down"
    out.append(down)
    combo = extra_joints(skeleton, poses, label)
    combo = reordered(combo.skeleton, combo.poses, {"mapping": combo.mapping, "alternatives": combo.alternatives})
    combo = transformed(combo.skeleton, combo.poses, {"mapping": combo.mapping, "alternatives": combo.alternatives},
                        rotation="facing_+x", unit="inch")
    combo = meaningless(combo.skeleton, combo.poses, {"mapping": combo.mapping, "alternatives": combo.alternatives}, seed=1)
    combo.name = "everything"
    combo.rename = {n: combo.rename[n] for n in skeleton.names}
    out.append(combo)
    return out
