"""Read a glTF 2.0 / VRM / VRMA file into an :class:`~infuse.asset.Asset` (json + numpy only).

Skeleton
    The joints of the file's skins (the union when there are several). A file without skins (VRM
    without skinning, VRMA, node animation) uses the VRM humanoid nodes and the nodes its animations
    move. Nodes lying between two joints become joints too, so the hierarchy stays connected. Joints
    are ordered depth first, the root with the most descendants first (joint 0). Names are node
    names (``node<i>`` for unnamed nodes, ``<name>_<i>`` for a repeated name).

Rest pose and frames
    The rest pose is the nodes' TRS (or decomposed ``matrix``), not the inverse bind matrices;
    ``meta["bind_pose"]`` says whether those agree. glTF is metres, +Y up and +Z forward by spec
    (``units_detected_by="file"``), which is the core frame. Non-joint nodes above the skeleton
    (an ``Armature`` with scale 0.01, a Z-up correction matrix...) are folded into each root's rest
    transform, and every node scale is folded into its descendants' translations, so the skeleton
    has no scale. A non-uniform scale is replaced by the mean of its axes, with a warning in
    ``Asset.warnings``. Overrides: ``units=`` (file units are then that unit, not metres),
    ``up_axis=`` (the file's up axis) and ``facing=`` (``"+Z"`` or ``"-Z"``, the file's front).
    VRM 0.x models face -Z (detected from the humanoid's left/right arms when present): they are
    turned 180° about +Y into the core frame, recorded as ``meta["facing"] = "-Z"`` and
    ``facing_turned``; every other file is taken to face +Z as the glTF spec says.

Animations
    One :class:`~infuse.motion.Motion` per glTF animation, resampled to a uniform rate: the keyframe
    rate when every key sits on one grid (12 to 240 fps), else 30 fps (``fps=`` overrides). STEP,
    LINEAR (slerp for rotations) and CUBICSPLINE are evaluated vectorized. Channels on the non-joint
    nodes above the skeleton become root motion; translation and scale channels on other joints
    become ``joint_translations``. Morph weight channels (and VRMA expression nodes) become the
    clip's ``morph_names`` / ``morph_weights`` (F, M), on its frames. An animation that moves no
    joint (morph weights alone) is a clip whose ``animated_joints`` is all false.

Other facts
    ``morph_targets``: mesh morph target names in file order, then the names of the VRM expressions
    that bind morph targets (``meta["vrm_expressions"]`` lists them all).
    ``humanoid``: for VRM files, {VRM humanoid bone name: joint name}.
    ``meta``: ``container``, ``generator``, ``extensions_used``, ``extensions_required``,
    ``compression``, ``skins``, ``folded_nodes``, ``bind_pose``, ``clips`` (per clip: animation index,
    fps and how it was found, interpolations, ignored channels), and for VRM files
    ``vrm_version`` and ``vrm_expressions``.
    ``payload``: a :class:`GltfPayload` with the whole parsed document, for the writer.
    ``meshes`` (decoded on first use): the skinned surfaces, see :mod:`infuse_gltf.mesh`.

Compressed data: Draco and most meshopt views hold mesh data, which the skeleton and clips never
touch (the mesh surfaces decode both, Draco with DracoPy: :mod:`infuse_gltf.draco`). meshopt views
the skeleton or clips need (inverse bind matrices, keyframes; ``ATTRIBUTES`` mode with the
``NONE``, ``EXPONENTIAL`` or ``QUATERNION`` filter) are decoded (:mod:`infuse_gltf.meshopt`);
anything else raises :class:`~infuse.errors.MissingFeatureError` naming the extension. Malformed
input raises :class:`~infuse.errors.InputError` with places such as ``nodes[12]`` or ``accessors[3]``.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from infuse import quaternions as quat
from infuse.asset import Asset
from infuse.conventions import UNIT_SCALES, UP_AXIS_ROTATIONS
from infuse.errors import InputError, MissingFeatureError, UnusableInputError, UsageError
from infuse.motion import Motion
from infuse.skeleton import Skeleton

from .accessors import AccessorReader, check_index, compression_extensions
from .container import GltfDocument, parse_file
from .graph import compose, global_matrices, node_graph, node_rest_trs, trs_matrices
from .mesh import MeshLoader
from .morph import mesh_target_names, unique_in_order
from .sampling import INTERPOLATIONS, detect_fps, frame_times, sample
from .vrm import VrmInfo, vrm_info

TRS_PATHS = ("translation", "rotation", "scale")
TURN_Y = np.array([0.0, 1.0, 0.0, 0.0])  # 180 degrees about +Y
#: Joint translations closer than this to the rest offsets (metres) are not kept as joint_translations.
STILL_M = 1e-6
#: ``node.extras`` key the writer sets on leaf nodes that hold a BVH-style end site.
END_SITE_MARK = "infuse_end_site"


@dataclass
class Rig:
    """Where the skeleton sits in the node graph, and how file values map to core values.

    - ``joint_nodes``: node index of each joint; ``parents``: joint parent indices.
    - ``above``: root joint index -> the non-joint ancestor nodes, outermost first.
    - ``core_from_file``: similarity ``(t, q, s)`` from the file's world frame to the core frame
      (unit scale, up axis, facing).
    - ``root_frames``: root joint index -> similarity of ``core_from_file`` ∘ the rest transform of
      its ancestors: a root's core transform is ``root_frames[r] ∘ (file translation, rotation)``.
    - ``parent_scales``: (J,) for a non-root joint, core metres per file unit of its translation
      (the product of its ancestors' scales).
    - ``end_sites``: ``(joint index, node index)`` of empty leaf nodes hanging from joints.
    """

    joint_nodes: tuple[int, ...]
    parents: np.ndarray
    names: tuple[str, ...]
    above: dict[int, tuple[int, ...]]
    core_from_file: tuple
    root_frames: dict = field(default_factory=dict)
    parent_scales: np.ndarray | None = None
    end_sites: tuple = ()


@dataclass
class SourceClip:
    """A clip as the reader produced it: the animation it came from and the objects it returned."""

    animation: int
    motion: Motion


@dataclass
class GltfPayload:
    """What the writer needs to write the character back: the document, the rig and the source clips."""

    document: GltfDocument
    rig: Rig
    skeleton: Skeleton
    clips: dict[str, SourceClip] = field(default_factory=dict)
    vrm: VrmInfo | None = None
    target_names: list = field(default_factory=list)


def read(path: str | Path, units: str | None = None, up_axis: str | None = None, facing: str | None = None,
         fps: float | None = None) -> Asset:
    """Read ``path`` (``.gltf``, ``.glb``, ``.vrm``, ``.vrma``) into an Asset in the core frame (see module doc)."""
    return asset_from_document(parse_file(path), units=units, up_axis=up_axis, facing=facing, fps=fps)


def _list(doc_json: dict, key: str, file) -> list:
    value = doc_json.get(key, [])
    if not isinstance(value, list):
        raise InputError(file, key, "is not an array")
    for i, item in enumerate(value):
        if not isinstance(item, dict):
            raise InputError(file, f"{key}[{i}]", "is not an object")
    return value


def asset_from_document(doc: GltfDocument, units=None, up_axis=None, facing=None, fps=None) -> Asset:
    """Build the Asset of a parsed document (see :func:`read` and the module doc)."""
    file = doc.path
    js = doc.json
    nodes = _list(js, "nodes", file)
    skins = _list(js, "skins", file)
    animations = _list(js, "animations", file)
    for key in ("meshes", "accessors", "bufferViews"):
        _list(js, key, file)
    if not nodes:
        raise UnusableInputError(file, "no nodes: the file holds no skeleton")
    graph = node_graph(nodes, file)
    rest_t, rest_r, rest_s = node_rest_trs(nodes, file)
    vrm = vrm_info(js, file)
    accessors = AccessorReader(doc)
    meta: dict = {
        "container": doc.container,
        "generator": (js.get("asset") or {}).get("generator"),
        "extensions_used": list(js.get("extensionsUsed") or []),
        "extensions_required": list(js.get("extensionsRequired") or []),
        "compression": compression_extensions(js),
        "skins": len(skins),
    }
    warnings: list[str] = []

    skin_joints = []
    for s, skin in enumerate(skins):
        joints = skin.get("joints")
        if not isinstance(joints, list) or not joints:
            raise InputError(file, f"skins[{s}].joints", "is not a non-empty array")
        skin_joints.append([check_index(file, f"skins[{s}].joints", j, len(nodes), "node") for j in joints])
    clips = [_parse_animation(a, anim, len(nodes), len(js.get("accessors", [])), file) for a, anim in enumerate(animations)]

    # -- the skeleton's nodes ------------------------------------------------------------------
    excluded = (vrm.expression_nodes | {vrm.look_at_node}) if vrm else set()
    chosen = {j for joints in skin_joints for j in joints}
    if vrm:
        chosen |= set(vrm.bones.values())
    if not skin_joints:
        chosen |= {ch[0] for clip in clips for ch in clip["channels"] if ch[1] in TRS_PATHS} - excluded
    if not chosen:
        raise UnusableInputError(file, "no skeleton: no skin, no VRM humanoid and no animated nodes")
    joint_nodes, parents, above = _order_joints(chosen, graph, nodes)
    names = _joint_names(nodes, joint_nodes)
    meta["folded_nodes"] = [nodes[n].get("name") or f"node{n}" for n in sorted({a for ch in above.values() for a in ch})]

    # -- core frame: units, up axis, facing ----------------------------------------------------
    if units is not None and units not in UNIT_SCALES:
        raise UsageError(f"unknown unit {units!r}; known: {', '.join(UNIT_SCALES)}")
    if up_axis is not None and up_axis not in UP_AXIS_ROTATIONS:
        raise UsageError(f"unknown up axis {up_axis!r}; known: {', '.join(UP_AXIS_ROTATIONS)}")
    if facing is not None and facing not in ("+Z", "-Z"):
        raise UsageError(f"facing must be '+Z' or '-Z', got {facing!r}")
    q_up = UP_AXIS_ROTATIONS[up_axis or "Y"]
    world = global_matrices(graph, trs_matrices(rest_t, rest_r, rest_s))
    detected_facing = _facing_from_humanoid(vrm, world, q_up)
    if facing is None:
        if vrm is not None and vrm.version == "0.x":
            facing, meta["facing_detected_by"] = detected_facing or "-Z", "humanoid arms" if detected_facing else "VRM 0.x spec"
        else:
            facing, meta["facing_detected_by"] = "+Z", "glTF spec"
            if detected_facing == "-Z":
                warnings.append("the humanoid faces -Z although glTF/VRM 1.0 models face +Z; use facing='-Z' to turn it")
    else:
        meta["facing_detected_by"] = "override"
    meta["facing"] = facing
    q_core = quat.multiply(TURN_Y, q_up) if facing == "-Z" else q_up
    core_from_file = (np.zeros(3), q_core, np.float64(UNIT_SCALES[units or "m"]))
    meta["up_axis_detected_by"] = "override" if up_axis else "file"

    rig = Rig(tuple(joint_nodes), parents, tuple(names), above, core_from_file)
    used = list(joint_nodes) + sorted({a for ch in above.values() for a in ch})
    posing = _Posing(rig, used, nodes, warnings)
    rest_rot, rest_trans, rest_cum = posing.pose(rest_t[used][None], rest_r[used][None], rest_s[used][None])
    rig.parent_scales = np.where(parents >= 0, rest_cum[0][np.maximum(parents, 0)], 1.0)
    rig.root_frames = {root: (np.array(ft[0]), np.array(fq[0]), float(fs[0])) for root, (ft, fq, fs) in posing.last_frames.items()}
    rig.end_sites = _end_sites(nodes, graph, joint_nodes)
    skeleton = _skeleton(rig, rest_rot[0], rest_trans[0], rest_cum[0], rest_t)

    # -- morph targets and VRM ------------------------------------------------------------------
    target_names = mesh_target_names(js)
    morph_targets = unique_in_order([t for t in target_names if t])
    humanoid: dict[str, str] = {}
    if vrm is not None:
        # Only expressions a weight can show: those binding morph targets (or a VRMA expression
        # node). One that binds materials only is listed in meta, but nothing animates it.
        shown = [e.name for e in vrm.expressions if e.binds or e.node is not None]
        morph_targets = unique_in_order([morph_targets, shown])
        meta["vrm_version"] = vrm.version
        humanoid = {bone: names[joint_nodes.index(n)] for bone, n in vrm.bones.items() if n in joint_nodes}
        meta["vrm_expressions"] = [e.name for e in vrm.expressions]
    meta["bind_pose"] = _bind_pose_check(skins, skin_joints, world, accessors, core_from_file[2], names, joint_nodes)

    # -- clips ----------------------------------------------------------------------------------
    motions: dict[str, Motion] = {}
    payload = GltfPayload(doc, rig, skeleton, vrm=vrm, target_names=target_names)
    meta["clips"] = {}
    for a, clip in enumerate(clips):
        name = clip["name"] if clip["name"] not in motions else f"{clip['name']}_{a}"
        result = _read_clip(clip, a, name, accessors, posing, skeleton, rest_t[used], rest_r[used], rest_s[used],
                            nodes, target_names, vrm, fps, file)
        if result is None:
            warnings.append(f"animations[{a}] ({name!r}) moves nothing of the skeleton or morph targets: skipped")
            continue
        motion, info = result
        motions[name] = motion
        meta["clips"][name] = info
        payload.clips[name] = SourceClip(a, motion)

    fmt = "vrma" if vrm and vrm.version.startswith("vrma") else "vrm" if vrm else doc.container
    has_mesh = any(isinstance(n.get("mesh"), int) for n in nodes)
    meshes = MeshLoader(doc, graph, world, joint_nodes, core_from_file, skeleton, warnings) if has_mesh else None
    return Asset(
        path=doc.path, format=fmt, skeleton=skeleton, motions=motions, morph_targets=morph_targets, humanoid=humanoid,
        facing_turned=facing == "-Z", warnings=warnings,
        source_units=units or "m", source_up_axis=up_axis or "Y",
        units_detected_by="override" if units else "file", meta=meta, payload=payload, mesh_loader=meshes,
    )


def _skeleton(rig: Rig, rest_rot, rest_trans, rest_cum, rest_t) -> Skeleton:
    """The core skeleton; end-site offsets are scaled like the translations of joints."""
    site_parents = [j for j, _ in rig.end_sites]
    site_offsets = np.array([rest_cum[j] * rest_t[n] for j, n in rig.end_sites]).reshape(-1, 3)
    return Skeleton(rig.names, rig.parents, rest_trans, quat.normalize(rest_rot), site_parents, site_offsets)


def _parse_animation(a: int, anim: dict, n_nodes: int, n_accessors: int, file) -> dict:
    """Check one animation's samplers and channels; channels are ``(node, path, sampler)``."""
    place = f"animations[{a}]"
    samplers = anim.get("samplers")
    channels = anim.get("channels")
    if not isinstance(samplers, list) or not isinstance(channels, list):
        raise InputError(file, place, "samplers and channels must be arrays")
    parsed_samplers = []
    for s, spl in enumerate(samplers):
        sp = f"{place}.samplers[{s}]"
        if not isinstance(spl, dict):
            raise InputError(file, sp, "is not an object")
        interp = spl.get("interpolation", "LINEAR")
        if interp not in INTERPOLATIONS:
            raise InputError(file, sp, f"unknown interpolation {interp!r}")
        parsed_samplers.append((check_index(file, sp, spl.get("input"), n_accessors, "input accessor"),
                                check_index(file, sp, spl.get("output"), n_accessors, "output accessor"), interp))
    parsed_channels = []
    for c, ch in enumerate(channels):
        cp = f"{place}.channels[{c}]"
        if not isinstance(ch, dict) or not isinstance(ch.get("target"), dict):
            raise InputError(file, cp, "is not an object with a target")
        sampler = check_index(file, cp, ch.get("sampler"), len(parsed_samplers), "sampler")
        node = ch["target"].get("node")
        if node is None:  # e.g. KHR_animation_pointer targets: not a node transform
            continue
        parsed_channels.append((check_index(file, f"{cp}.target", node, n_nodes, "node"), ch["target"].get("path"), sampler))
    name = anim.get("name")
    return {"name": name if isinstance(name, str) and name else f"animation{a}",
            "channels": parsed_channels, "samplers": parsed_samplers}


def _is_end_site(node: dict) -> bool:
    """A leaf node the writer marked as a BVH-style end site (not a joint)."""
    return bool((node.get("extras") or {}).get(END_SITE_MARK)) if isinstance(node.get("extras"), dict) else False


def _order_joints(chosen: set[int], graph, nodes: list) -> tuple[list[int], np.ndarray, dict[int, tuple[int, ...]]]:
    """Joint nodes in depth-first order (largest tree first), their parent indices, and the non-joint
    ancestors of each root (outermost first).

    Nodes between two chosen nodes join the skeleton, so it stays connected, and so do empty nodes
    hanging below joints (bone tips such as ``FootL_end``, IK poles): nodes whose subtree holds no
    mesh, camera or skin, except end sites marked by the writer.
    """
    joints = set(chosen)
    for j in chosen:
        between = []
        k = int(graph.parent[j])
        while k >= 0:
            if k in chosen:
                joints.update(between)
                break
            between.append(k)
            k = int(graph.parent[k])
    occupied = _occupied(graph, nodes)
    for n in graph.order:  # parents first, so an empty chain below a joint is taken whole
        p = int(graph.parent[n])
        if n not in joints and p in joints and not _is_end_site(nodes[n]) and not occupied[n]:
            joints.add(n)
    roots = [j for j in joints if graph.parent[j] < 0 or int(graph.parent[j]) not in joints]

    def subtree(root: int) -> list[int]:
        out, stack = [], [root]
        while stack:
            n = stack.pop()
            out.append(n)
            stack.extend(c for c in reversed(graph.children[n]) if c in joints)
        return out

    trees = sorted((subtree(r) for r in roots), key=lambda t: (-len(t), t[0]))
    order = [n for t in trees for n in t]
    index = {n: i for i, n in enumerate(order)}
    parents = np.array([index.get(int(graph.parent[n]), -1) for n in order], dtype=np.int64)
    above = {index[t[0]]: tuple(reversed(graph.ancestors(t[0]))) for t in trees}
    return order, parents, above


def _joint_names(nodes: list, joint_nodes: list[int]) -> list[str]:
    names: list[str] = []
    taken: set[str] = set()
    for n in joint_nodes:
        raw = nodes[n].get("name")
        name = raw if isinstance(raw, str) and raw else f"node{n}"
        if name in taken:
            name = f"{name}_{n}"
        taken.add(name)
        names.append(name)
    return names


def _facing_from_humanoid(vrm: VrmInfo | None, world: np.ndarray, q_up: np.ndarray) -> str | None:
    """``"+Z"`` when the humanoid's left side is at +X (after the up-axis turn), ``"-Z"`` when at -X."""
    if vrm is None:
        return None
    for left, right in (("leftUpperArm", "rightUpperArm"), ("leftUpperLeg", "rightUpperLeg"), ("leftHand", "rightHand")):
        if left in vrm.bones and right in vrm.bones:
            dx = quat.rotate(q_up, world[vrm.bones[left], :3, 3] - world[vrm.bones[right], :3, 3])[0]
            if abs(dx) > 1e-6:
                return "+Z" if dx > 0 else "-Z"
    return None


def _occupied(graph, nodes: list) -> np.ndarray:
    """(N,) bool: the node's subtree holds a mesh, camera or skin (one pass, children before parents)."""
    occupied = np.array([any(key in node for key in ("mesh", "camera", "skin")) for node in nodes], dtype=bool)
    for n in reversed(graph.order):
        p = int(graph.parent[n])
        if p >= 0 and occupied[n]:
            occupied[p] = True
    return occupied


def _end_sites(nodes: list, graph, joint_nodes: list[int]) -> tuple:
    """``(joint index, node index)`` of the end-site leaves (marked by the writer) under joints."""
    return tuple((j, c) for j, n in enumerate(joint_nodes) for c in graph.children[n] if _is_end_site(nodes[c]))


class _Posing:
    """Turns file TRS of the skeleton's nodes (joints, then the nodes above the roots) into core local
    rotations and translations, vectorized over frames."""

    def __init__(self, rig: Rig, used: list[int], nodes: list, warnings: list[str]):
        self.rig = rig
        self.col = {n: k for k, n in enumerate(used)}
        self.nodes = nodes
        self.warnings = warnings
        self._warned: set[int] = set()
        depth = np.zeros(len(rig.parents), dtype=np.int64)
        for j, p in enumerate(rig.parents):
            depth[j] = depth[p] + 1 if p >= 0 else 0
        self.levels = [np.nonzero(depth == d)[0] for d in range(1, int(depth.max()) + 1)]
        self.last_frames: dict[int, tuple] = {}  # root -> core_from_file ∘ ancestors, from the last pose()

    def _uniform(self, s: np.ndarray) -> np.ndarray:
        """(F,U) uniform scales from (F,U,3); warns once per node with a non-uniform scale."""
        mean = s.mean(axis=-1)
        uneven = np.any(np.abs(s - mean[..., None]) > 1e-4 * np.maximum(np.abs(mean[..., None]), 1e-12), axis=(0, 2))
        for k in np.nonzero(uneven)[0]:
            node = list(self.col)[k]
            if node not in self._warned:
                self._warned.add(node)
                self.warnings.append(f"nodes[{node}] ({self.nodes[node].get('name')!r}) has a non-uniform scale; "
                                     "its mean is used (shapes under it are approximate)")
        return mean

    def pose(self, t: np.ndarray, r: np.ndarray, s: np.ndarray, still_above: bool = False):
        """Core (rotations (F,J,4), translations (F,J,3), cumulative scales (F,J)) from file TRS arrays
        (F,U,3), (F,U,4), (F,U,3) over the used nodes. ``still_above``: the nodes above the roots hold
        their rest transforms (``rig.root_frames``) in every frame."""
        rig = self.rig
        su = self._uniform(s)
        f, j = t.shape[0], len(rig.joint_nodes)
        rot = np.array(r[:, :j])
        trans = np.empty((f, j, 3))
        cum = np.empty((f, j))
        for root, chain in rig.above.items():
            if still_above:
                frame = rig.root_frames[root]
            else:
                ct, cq, cs = rig.core_from_file
                frame = (np.broadcast_to(ct, (f, 3)), np.broadcast_to(cq, (f, 4)), np.full(f, float(cs)))
                for a in chain:
                    c = self.col[a]
                    frame = compose(frame, (t[:, c], r[:, c], su[:, c]))
                self.last_frames[root] = frame
            tt, qq, ss = compose(frame, (t[:, root], r[:, root], su[:, root]))
            trans[:, root], rot[:, root], cum[:, root] = tt, qq, ss
        parents = rig.parents
        for idx in self.levels:
            p = parents[idx]
            trans[:, idx] = cum[:, p, None] * t[:, idx]
            cum[:, idx] = cum[:, p] * su[:, idx]
        return rot, trans, cum


def _bind_pose_check(skins, skin_joints, world, accessors: AccessorReader, unit: float, names, joint_nodes) -> dict:
    """Whether every joint's world rest matrix times its inverse bind matrix gives one common matrix."""
    if not skins:
        return {"checked": False, "reason": "no skins"}
    index = {n: i for i, n in enumerate(joint_nodes)}
    worst_rot = worst_trans = 0.0
    differing: list[str] = []
    for s, skin in enumerate(skins):
        ibm_index = skin.get("inverseBindMatrices")
        if ibm_index is None:
            continue  # identity inverse bind matrices
        try:
            ibm = accessors.read(ibm_index, f"skins[{s}].inverseBindMatrices")
        except MissingFeatureError as exc:
            return {"checked": False, "reason": exc.problem}
        joints = skin_joints[s]
        if ibm.shape != (len(joints), 4, 4):
            raise InputError(accessors.file, f"skins[{s}].inverseBindMatrices", f"holds {ibm.shape[0]} matrices for {len(joints)} joints")
        m = world[joints] @ np.swapaxes(ibm, 1, 2).astype(np.float64)  # stored column-major
        scale = np.cbrt(np.abs(np.linalg.det(m[:, :3, :3])))[:, None, None]
        basis = m[:, :3, :3] / np.maximum(scale, 1e-12)
        cos = (np.einsum("ij,kij->k", basis[0], basis) - 1.0) / 2.0  # trace(B0^T Bk)
        d_rot = np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))
        d_trans = np.abs(m[:, :3, 3] - m[0, :3, 3]).max(axis=1) * unit
        extent = max(float(np.ptp(world[joints, :3, 3], axis=0).max()) * unit, 1e-9)
        worst_rot = max(worst_rot, float(d_rot.max()))
        worst_trans = max(worst_trans, float(d_trans.max()))
        bad = np.nonzero((d_rot > 0.1) | (d_trans > 1e-3 * extent))[0]
        differing += [names[index[joints[b]]] for b in bad if joints[b] in index]
    return {"checked": True, "matches_rest": not differing, "max_rotation_deviation_deg": worst_rot,
            "max_translation_deviation_m": worst_trans, "joints_differing": sorted(set(differing))[:20]}


def _read_clip(clip, a, name, accessors: AccessorReader, posing: _Posing, skeleton: Skeleton, rest_t, rest_r, rest_s,
               nodes, target_names, vrm, fps_override, file):
    """One animation resampled on a uniform grid: (Motion, info), or None."""
    col = posing.col
    expression_nodes = {e.node: e.name for e in vrm.expressions if e.node is not None} if vrm else {}
    trs, weights, ignored = [], [], 0
    for node, path, s in clip["channels"]:
        if path in TRS_PATHS and node in col:
            trs.append((node, path, s))
        elif path == "translation" and node in expression_nodes:
            weights.append((node, path, s))
        elif path == "weights" and isinstance(nodes[node].get("mesh"), int) and 0 <= nodes[node]["mesh"] < len(target_names) \
                and target_names[nodes[node]["mesh"]]:
            weights.append((node, path, s))
        else:
            ignored += 1
    if not trs and not weights:
        return None
    used_samplers = sorted({s for _, _, s in trs + weights})
    place = f"animations[{a}]"
    # Exporters often give every channel its own copy of one time list: check and sample each list once.
    times: dict[int, np.ndarray] = {}
    time_key: dict[int, bytes] = {}
    distinct: dict[bytes, np.ndarray] = {}
    for s in used_samplers:
        inp = clip["samplers"][s][0]
        arr = accessors.read(inp, f"{place}.samplers[{s}].input", check_finite=False)
        if arr.ndim != 2 or arr.shape[1] != 1 or arr.dtype.kind != "f":
            raise InputError(file, f"{place}.samplers[{s}].input", "keyframe times must be float scalars")
        key = arr.tobytes()
        if key not in distinct:
            accessors.read(inp, f"{place}.samplers[{s}].input")  # names the accessor if a time is NaN
            tk = arr[:, 0].astype(np.float64)
            if np.any(np.diff(tk) < 0):
                raise InputError(file, f"{place}.samplers[{s}].input", "keyframe times decrease")
            distinct[key] = tk
        times[s], time_key[s] = distinct[key], key
    if fps_override is not None:
        if not (np.isfinite(fps_override) and fps_override > 0):
            raise UsageError(f"fps must be positive, got {fps_override}")
        fps, fps_by = float(fps_override), "override"
    else:
        fps, fps_by = detect_fps(list(distinct.values()))
    start = min(float(t[0]) for t in distinct.values())
    end = max(float(t[-1]) for t in distinct.values())
    query = frame_times(start, end, fps)
    f = len(query)

    t = np.broadcast_to(rest_t, (f,) + rest_t.shape).copy()
    r = np.broadcast_to(rest_r, (f,) + rest_r.shape).copy()
    sc = np.broadcast_to(rest_s, (f,) + rest_s.shape).copy()
    target = {"translation": t, "rotation": r, "scale": sc}
    groups: dict[tuple, list] = {}
    for node, path, s in trs:
        groups.setdefault((time_key[s], clip["samplers"][s][2], path), []).append((node, s))
    for (_, interp, path), members in groups.items():
        width = 4 if path == "rotation" else 3
        vals = [_output(accessors, clip, s, times[s], interp, width, place, file) for _, s in members]
        stacked = np.stack(vals, axis=-2)  # (K, n, C) or (K, 3, n, C)
        if not np.all(np.isfinite(stacked)):
            for _, s in members:  # raises, naming the accessor
                accessors.read(clip["samplers"][s][1], f"{place}.samplers[{s}].output")
        if path == "rotation":
            stacked = quat.normalize(stacked)
        out = sample(times[members[0][1]], stacked, interp, query, rotation=path == "rotation")
        target[path][:, [col[n] for n, _ in members]] = out
    n_joints = len(skeleton.names)
    rot, trans, _ = posing.pose(t, r, sc, still_above=all(col[n] < n_joints for n, _, _ in trs))
    rest_trans = skeleton.rest_translations
    moving = np.abs(trans[:, 1:] - rest_trans[1:]).max() > STILL_M if len(rest_trans) > 1 else False
    tracks: dict[str, np.ndarray] = {}
    for node, path, s in weights:
        interp = clip["samplers"][s][2]
        if path == "translation":  # a VRMA expression node: translation.x is the weight
            vals = _output(accessors, clip, s, times[s], interp, 3, place, file)
            accessors.read(clip["samplers"][s][1], f"{place}.samplers[{s}].output")  # finite check
            tracks.setdefault(expression_nodes[node], sample(times[s], vals, interp, query, False)[:, 0])
            continue
        names_ = target_names[nodes[node]["mesh"]]
        vals = _output(accessors, clip, s, times[s], interp, len(names_), place, file)
        accessors.read(clip["samplers"][s][1], f"{place}.samplers[{s}].output")  # finite check
        out = sample(times[s], vals, interp, query, False)
        for k, tn in enumerate(names_):
            tracks.setdefault(tn, out[:, k])
    weight_names = tuple(tracks)
    morph_weights = np.stack([tracks[n] for n in weight_names], axis=1) if tracks else np.zeros((f, 0))
    animated = None if trs else np.zeros(skeleton.num_joints, dtype=bool)
    motion = Motion(skeleton, fps, quat.make_continuous(rot), trans[:, 0], trans if moving else None, name=name,
                    morph_names=weight_names, morph_weights=morph_weights, animated_joints=animated)
    info = {"animation": a, "fps": fps, "fps_detected_by": fps_by, "start_time": start, "frames": f,
            "interpolations": sorted({clip["samplers"][s][2] for s in used_samplers}), "ignored_channels": ignored}
    return motion, info


def _output(accessors: AccessorReader, clip, s: int, times: np.ndarray, interp: str, width: int, place: str, file) -> np.ndarray:
    """Sampler ``s`` output values as (K, width) or (K, 3, width) for CUBICSPLINE, float64."""
    out_index = clip["samplers"][s][1]
    vals = accessors.read(out_index, f"{place}.samplers[{s}].output", check_finite=False)
    k = len(times)
    per_key = 3 if interp == "CUBICSPLINE" else 1
    flat = np.asarray(vals, dtype=np.float64).reshape(-1)
    if flat.size != k * per_key * width:
        raise InputError(file, f"{place}.samplers[{s}].output",
                         f"holds {flat.size} numbers, expected {k} keys x {per_key} x {width}")
    return flat.reshape((k, 3, width) if per_key == 3 else (k, width))
