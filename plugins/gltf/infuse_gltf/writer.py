"""Write an :class:`~infuse.asset.Asset` as glTF 2.0: ``.glb``/``.vrm``/``.vrma`` (binary) or ``.gltf`` (JSON).

A character read from glTF/VRM (``asset.payload`` is a :class:`~infuse_gltf.reader.GltfPayload`) is
written back as a copy: meshes, skins, materials, textures, extensions and every node stay as they
were, and its animations become ``asset.motions``:

- a clip the reader produced and nobody replaced (the same Motion object) keeps its original glTF
  animation, byte for byte;
- any other Motion becomes a new animation: a rotation track on every joint node the clip animates
  (``Motion.animated_joints``, every joint by default), a translation track on the first joint and
  on joints whose offsets move (LINEAR, at the clip's frame times), converted back to the file's
  node frames (parents, scale and axes the reader folded are undone), and a weights track from the
  clip's morph weights;
- clips the reader found but that are no longer in ``asset.motions`` are dropped;
- the animations follow the order of ``asset.motions`` (then animations the reader did not turn
  into clips): the first is the one Blender makes active and three.js code playing
  ``animations[0]`` plays.

A clip's morph weights (``Motion.morph_names``, ``Motion.morph_weights`` (F, M)) drive targets by
name, at the clip's frame times: a mesh morph target name (every mesh node with that target is
driven), a VRM expression (its morph target binds are driven, scaled by their weights) or a VRMA
expression (its node's translation.x). Targets of a driven mesh that the clip does not name keep
the mesh's default weights. A name nothing in the file matches raises
:class:`~infuse.errors.UsageError`. A clip that animates no joint and no morph target writes no
animation.

Any other asset (from BVH, SmartBody, COLLADA, FBX...) is written as a new glTF: one node per joint
(rest translation and rotation, metres, +Y up, +Z forward), end sites as leaf nodes marked
``extras.infuse_end_site``, a skin listing every joint with its inverse bind matrix (so readers
know the whole skeleton), the asset's skinned meshes (``asset.meshes``, each with its own skin,
material and named morph targets, see :mod:`infuse_gltf.mesh_writer`), and one animation per
Motion. Morph weights drive those meshes' targets by name; an asset without morph targets cannot
carry them (:class:`~infuse.errors.UsageError`).

A ``.vrma`` (VRM Animation) is written the same way from any asset with a humanoid map in
``asset.humanoid`` (a VRM character has one): the skeleton, the clips, the ``VRMC_vrm_animation``
humanoid map, and one expression node per morph name the clips animate (VRM 1.0 preset names go
under ``preset``, others under ``custom``). A ``.vrm`` is only written from a VRM
character (it needs the VRM extension the file came with).

New binary data is appended to buffer 0 (the GLB BIN chunk). External buffers and images of a
``.gltf`` source are embedded (``data:`` URIs in ``.gltf`` output), so the output stands alone.
"""
from __future__ import annotations

import base64
import copy
import json
import mimetypes
import struct
from pathlib import Path

import numpy as np

import infuse
from infuse import quaternions as quat
from infuse.errors import UsageError
from infuse.motion import Motion

from .container import CHUNK_BIN, CHUNK_JSON, GLB_MAGIC, read_uri
from .graph import invert, trs_matrices
from .mesh_writer import add_meshes
from .morph import mesh_target_names
from .reader import END_SITE_MARK, STILL_M, GltfPayload
from .vrm import VRM_PRESET_EXPRESSIONS, Expression, VrmInfo

FLOAT = 5126
BINARY_SUFFIXES = (".glb", ".vrm", ".vrma")


class _Binary:
    """Appends typed arrays to one buffer and records the bufferViews and accessors that describe them."""

    def __init__(self, doc: dict, buffer_index: int, existing: bytes):
        self.doc = doc
        self.buffer_index = buffer_index
        self.parts = [bytes(existing)]
        self.length = len(existing)

    def view(self, data: np.ndarray, target: int | None = None) -> int:
        """A new bufferView holding ``data`` (4-byte aligned), for GPU buffer ``target`` when given
        (vertex attributes, indices); returns its index."""
        raw = np.ascontiguousarray(data).tobytes()
        pad = (-self.length) % 4
        if pad:
            self.parts.append(b"\0" * pad)
            self.length += pad
        views = self.doc.setdefault("bufferViews", [])
        views.append({"buffer": self.buffer_index, "byteOffset": self.length, "byteLength": len(raw)})
        if target is not None:
            views[-1]["target"] = target
        self.parts.append(raw)
        self.length += len(raw)
        return len(views) - 1

    def accessor(self, view: int, offset: int, count: int, kind: str, minmax: np.ndarray | None = None,
                 component: int = FLOAT) -> int:
        acc = {"bufferView": view, "byteOffset": offset, "componentType": component, "count": count, "type": kind}
        if minmax is not None:
            acc["min"] = [float(v) for v in np.atleast_1d(minmax.min(axis=0))]
            acc["max"] = [float(v) for v in np.atleast_1d(minmax.max(axis=0))]
        accessors = self.doc.setdefault("accessors", [])
        accessors.append(acc)
        return len(accessors) - 1

    def blocks(self, arrays: list[np.ndarray], kind: str) -> list[int]:
        """One bufferView holding every array (float32, back to back) and one accessor per array."""
        if not arrays:
            return []
        flat = [np.asarray(a, dtype=np.float32) for a in arrays]
        view = self.view(np.concatenate([a.reshape(-1) for a in flat]))
        out, offset = [], 0
        for a in flat:
            count = a.shape[0] if kind != "SCALAR" else a.size
            out.append(self.accessor(view, offset, count, kind))
            offset += a.nbytes
        return out

    def data(self) -> bytes:
        return b"".join(self.parts)


class _Target:
    """The skeleton's place in the output document: node per joint and the file <- core conversion."""

    def __init__(self, names, joint_nodes, parents, root_frames: dict, parent_scales: np.ndarray, rest_translations):
        self.index = {n: i for i, n in enumerate(names)}
        self.joint_nodes = list(joint_nodes)
        self.parents = np.asarray(parents)
        self.root_frames = root_frames
        self.parent_scales = np.asarray(parent_scales, dtype=np.float64)
        self.rest_translations = np.asarray(rest_translations, dtype=np.float64)

    def file_pose(self, motion: Motion) -> tuple[list[int], np.ndarray, np.ndarray]:
        """Rig joint indices of the motion's joints and their file-frame rotations (F,n,4) and translations (F,n,3)."""
        missing = [n for n in motion.skeleton.names if n not in self.index]
        if missing:
            raise UsageError(f"clip {motion.name!r} moves joints the character does not have: {', '.join(missing[:8])}")
        joints = [self.index[n] for n in motion.skeleton.names]
        rot = np.array(motion.local_rotations)
        trans = motion.local_translations()
        for k, j in enumerate(joints):
            if self.parents[j] >= 0:
                trans[:, k] /= self.parent_scales[j]
                continue
            ft, fq, fs = invert(self.root_frames[j])
            trans[:, k] = ft + fs * quat.rotate(fq, trans[:, k])
            rot[:, k] = quat.multiply(fq, rot[:, k])
        return joints, quat.make_continuous(quat.normalize(rot)), trans

    def moving(self, motion: Motion, joints: list[int]) -> list[int]:
        """Positions (in ``joints``) of the joints whose translation must be written: the motion's
        first joint and those whose offsets leave the rest offsets."""
        keep = [0]
        if motion.joint_translations is not None:
            dev = np.abs(motion.joint_translations - self.rest_translations[joints]).max(axis=(0, 2))
            keep += [k for k in range(1, len(joints)) if dev[k] > STILL_M]
        return keep


def write(asset: infuse.Asset, path: str | Path) -> None:
    """Write ``asset`` to ``path`` (binary for .glb/.vrm/.vrma, JSON for .gltf); see the module doc."""
    path = Path(path)
    suffix = path.suffix.lower()
    binary = suffix in BINARY_SUFFIXES
    payload = asset.payload if isinstance(asset.payload, GltfPayload) else None
    version = payload.vrm.version if payload is not None and payload.vrm is not None else None
    if suffix == ".vrm" and version not in ("0.x", "1.0"):
        raise UsageError(".vrm output needs a VRM character (one read from a .vrm file); write a .glb instead")
    if payload is not None and not (suffix == ".vrma" and version != "vrma-1.0"):
        doc, bin_writer, other = _copy_document(payload, binary)
        _write_animations(doc, bin_writer, asset, payload, payload.vrm)
        _finish(doc, bin_writer, other, path, binary)
        return
    # A new document: the skeleton as nodes, its meshes (for .vrma, the humanoid map and expression nodes).
    vrma = suffix == ".vrma"
    meshes = () if vrma else asset.meshes
    if any(m.morph_names for m in asset.motions.values()) and not vrma and not any(m.morph_names for m in meshes):
        raise UsageError("morph weights need a character with morph targets (this asset's meshes have none)")
    doc, bin_writer, other, vrm = _skeleton_document(asset, vrma, meshes)
    _write_animations(doc, bin_writer, asset, None, vrm)
    _finish(doc, bin_writer, other, path, binary)


# -- the document ---------------------------------------------------------------------------------
def _copy_document(payload: GltfPayload, binary: bool):
    """A deep copy of the source JSON, its buffers resolved, and the writer for new data."""
    src = payload.document
    doc = copy.deepcopy(src.json)
    buffers = doc.setdefault("buffers", [])
    data = list(src.buffers)
    if not buffers or data[0] is None:
        buffers.insert(0, {"byteLength": 0})
        data.insert(0, b"")
        for view in doc.get("bufferViews", []):
            view["buffer"] += 1
            ext = (view.get("extensions") or {}).get("EXT_meshopt_compression") or (view.get("extensions") or {}).get("KHR_meshopt_compression")
            if ext and "buffer" in ext:
                ext["buffer"] += 1
    for image in doc.get("images", []):
        uri = image.get("uri")
        if isinstance(uri, str) and not uri.startswith("data:"):
            raw = read_uri(uri, src.path, "images")
            mime = image.get("mimeType") or mimetypes.guess_type(uri)[0] or "application/octet-stream"
            image["uri"] = f"data:{mime};base64," + base64.b64encode(raw).decode("ascii")
    return doc, _Binary(doc, 0, data[0]), data


def _skeleton_document(asset: infuse.Asset, vrma: bool, meshes):
    """A new document with the skeleton as nodes, a skin of every joint and ``meshes`` (core surfaces,
    see :mod:`infuse_gltf.mesh_writer`); for a VRMA, also the humanoid map and one expression node per
    morph name the clips animate."""
    sk = asset.skeleton
    doc: dict = {"asset": {"version": "2.0", "generator": f"infuse {infuse.__version__}"}, "buffers": [{"byteLength": 0}]}
    nodes = [{"name": n, "translation": [float(v) for v in t], "rotation": [float(v) for v in q]}
             for n, t, q in zip(sk.names, sk.rest_translations, quat.normalize(sk.rest_rotations))]
    for j, p in enumerate(sk.parents):
        if p >= 0:
            nodes[p].setdefault("children", []).append(j)
    taken = set(sk.names)
    for e, (p, offset) in enumerate(zip(sk.end_site_parents, sk.end_site_offsets)):
        name = f"{sk.names[p]}_end"
        while name in taken:
            name += f"_{e}"
        taken.add(name)
        nodes.append({"name": name, "translation": [float(v) for v in offset], "extras": {END_SITE_MARK: True}})
        nodes[p].setdefault("children", []).append(len(nodes) - 1)
    doc["nodes"] = nodes
    roots = [int(r) for r in sk.roots]
    if len(roots) > 1:  # one common root keeps the skin valid; an identity node the reader folds away
        name = "skeleton_root"
        while name in taken:
            name += "_"
        nodes.append({"name": name, "children": roots})
        roots = [len(nodes) - 1]
    bin_writer = _Binary(doc, 0, b"")
    world = np.linalg.inv(_rest_world(sk))
    ibm = bin_writer.blocks([np.swapaxes(world, 1, 2).reshape(len(world), 16)], "MAT4")[0]
    doc["skins"] = [{"joints": list(range(sk.num_joints)), "inverseBindMatrices": ibm}]
    roots += add_meshes(doc, bin_writer, meshes, range(sk.num_joints))
    vrm = None
    if vrma:
        humanoid = asset.humanoid
        if not humanoid:
            raise UsageError("a .vrma needs a VRM humanoid map (asset.humanoid = {vrm bone: joint name})")
        bones = {bone: {"node": sk.index[j]} for bone, j in humanoid.items() if j in sk.index}
        ext: dict = {"specVersion": "1.0", "humanoid": {"humanBones": bones}}
        expressions = []
        for name in dict.fromkeys(n for motion in asset.motions.values() for n in motion.morph_names):
            nodes.append({"name": name})  # a VRMA expression: its translation.x carries the weight
            roots.append(len(nodes) - 1)
            group = "preset" if name in VRM_PRESET_EXPRESSIONS else "custom"
            ext.setdefault("expressions", {}).setdefault(group, {})[name] = {"node": len(nodes) - 1}
            expressions.append(Expression(name, node=len(nodes) - 1))
        doc["extensions"] = {"VRMC_vrm_animation": ext}
        doc["extensionsUsed"] = ["VRMC_vrm_animation"]
        vrm = VrmInfo("vrma-1.0", {b: v["node"] for b, v in bones.items()}, expressions)
    doc["scenes"] = [{"nodes": roots}]
    doc["scene"] = 0
    return doc, bin_writer, [b""], vrm


def _rest_world(sk) -> np.ndarray:
    """(J,4,4) rest world matrices of a skeleton."""
    return trs_matrices(sk.rest_global_positions, sk.rest_global_rotations, np.ones((sk.num_joints, 3)))


# -- animations -----------------------------------------------------------------------------------
def _write_animations(doc: dict, bin_writer: _Binary, asset: infuse.Asset, payload: GltfPayload | None,
                      vrm: VrmInfo | None):
    if payload is not None:
        rig = payload.rig
        target = _Target(rig.names, rig.joint_nodes, rig.parents, rig.root_frames, rig.parent_scales,
                         payload.skeleton.rest_translations)
        source = payload.document.json.get("animations") or []
        from_clips = {sc.animation for sc in payload.clips.values()}
        kept = {name: sc.animation for name, sc in payload.clips.items()
                if asset.motions.get(name) is sc.motion}
    else:
        sk = asset.skeleton
        ident = (np.zeros(3), quat.IDENTITY, 1.0)
        target = _Target(sk.names, range(sk.num_joints), sk.parents, {int(r): ident for r in sk.roots},
                         np.ones(sk.num_joints), sk.rest_translations)
        source, from_clips, kept = [], set(), {}
    # The asset's clips come first, in their order (a viewer plays the first animation), then any
    # animation the reader did not turn into a clip, untouched.
    animations = []
    for name, motion in asset.motions.items():
        if name in kept:
            animations.append(copy.deepcopy(source[kept[name]]))
            continue
        if not (motion.animated_mask.any() or motion.morph_names):
            continue
        anim = {"name": name, "channels": [], "samplers": []}
        time_acc = _times_accessor(bin_writer, motion.frame_times)
        _motion_channels(anim, bin_writer, target, motion, time_acc)
        _weight_channels(anim, bin_writer, doc, vrm, motion, time_acc)
        if anim["channels"]:
            animations.append(anim)
    animations += [copy.deepcopy(a) for i, a in enumerate(source) if i not in from_clips]
    if animations:
        doc["animations"] = animations
    else:
        doc.pop("animations", None)


def _times_accessor(bin_writer: _Binary, times: np.ndarray) -> int:
    times = np.asarray(times, dtype=np.float32)
    view = bin_writer.view(times)
    return bin_writer.accessor(view, 0, len(times), "SCALAR", times[:, None])


def _motion_channels(anim: dict, bin_writer: _Binary, target: _Target, motion: Motion, time_acc: int) -> None:
    """Rotation and translation channels on the joint nodes the clip animates."""
    joints, rot, trans = target.file_pose(motion)
    animated = motion.animated_mask
    moving = [k for k in target.moving(motion, joints) if animated[k]]
    rotating = np.nonzero(animated)[0]
    rot_acc = bin_writer.blocks([rot[:, k] for k in rotating], "VEC4")
    trans_acc = bin_writer.blocks([trans[:, k] for k in moving], "VEC3")
    for k, acc in zip(moving, trans_acc):
        _channel(anim, time_acc, acc, target.joint_nodes[joints[k]], "translation")
    for k, acc in zip(rotating, rot_acc):
        _channel(anim, time_acc, acc, target.joint_nodes[joints[k]], "rotation")


def _channel(anim: dict, time_acc: int, out_acc: int, node: int, path: str) -> None:
    anim["samplers"].append({"input": time_acc, "output": out_acc, "interpolation": "LINEAR"})
    anim["channels"].append({"sampler": len(anim["samplers"]) - 1, "target": {"node": node, "path": path}})


def _weight_channels(anim: dict, bin_writer: _Binary, doc: dict, vrm: VrmInfo | None, motion: Motion,
                     time_acc: int) -> None:
    """Weights channels on the mesh nodes (and VRMA expression translations) the clip's morph weights drive."""
    if not motion.morph_names:
        return
    clip = motion.name
    weights = dict(zip(motion.morph_names, motion.morph_weights.T))
    binds = _target_binds(doc, vrm)
    unknown = [n for n in weights if n not in binds]
    if unknown:
        raise UsageError(f"clip {clip!r}: morph weights name targets this character does not have: {', '.join(unknown[:8])}")
    unbound = [n for n in weights if not binds[n]]
    if unbound:
        raise UsageError(f"clip {clip!r}: VRM expressions without morph target binds cannot be animated: "
                         f"{', '.join(unbound[:8])}")
    frames = motion.num_frames
    per_node: dict[int, np.ndarray] = {}
    touched: dict[int, set] = {}
    expression_nodes: dict[int, np.ndarray] = {}
    nodes = doc["nodes"]
    meshes = doc.get("meshes", [])
    for name, w in weights.items():
        for kind, node, k, scale in binds[name]:
            if kind == "expression-node":
                expression_nodes[node] = expression_nodes.get(node, 0.0) + w * scale
                continue
            if node not in per_node:
                mesh = meshes[nodes[node]["mesh"]]
                n_targets = len(mesh["primitives"][0].get("targets", []))
                default = np.asarray(nodes[node].get("weights") or mesh.get("weights") or np.zeros(n_targets), dtype=np.float64)
                per_node[node] = np.broadcast_to(default, (frames, n_targets)).copy()
                touched[node] = set()
            if k not in touched[node]:
                per_node[node][:, k] = 0.0
                touched[node].add(k)
            per_node[node][:, k] += w * scale
    nodes_sorted = sorted(per_node)
    for node, acc in zip(nodes_sorted, bin_writer.blocks([per_node[n] for n in nodes_sorted], "SCALAR")):
        _channel(anim, time_acc, acc, node, "weights")
    for node in sorted(expression_nodes):
        xyz = np.zeros((frames, 3))
        xyz[:, 0] = expression_nodes[node]
        _channel(anim, time_acc, bin_writer.blocks([xyz], "VEC3")[0], node, "translation")


def _target_binds(doc: dict, vrm: VrmInfo | None) -> dict[str, list[tuple]]:
    """Target name -> ``(kind, node, target index, scale)`` for mesh targets, VRM and VRMA expressions."""
    names = mesh_target_names(doc)
    nodes = doc.get("nodes", [])
    mesh_nodes: dict[int, list[int]] = {}
    for i, node in enumerate(nodes):
        if isinstance(node.get("mesh"), int):
            mesh_nodes.setdefault(node["mesh"], []).append(i)
    binds: dict[str, list[tuple]] = {}
    for m, targets in enumerate(names):
        for k, name in enumerate(targets):
            binds.setdefault(name, []).extend(("mesh", n, k, 1.0) for n in mesh_nodes.get(m, []))
    for expr in vrm.expressions if vrm else []:
        if expr.name in binds:
            continue  # a mesh target of that name wins
        if expr.node is not None:
            binds[expr.name] = [("expression-node", expr.node, 0, 1.0)]
            continue
        out = []
        for kind, ref, k, weight in expr.binds:
            targets = [ref] if kind == "node" else mesh_nodes.get(ref, [])
            out += [("mesh", n, k, weight) for n in targets
                    if 0 <= n < len(nodes) and isinstance(nodes[n].get("mesh"), int) and k < len(names[nodes[n]["mesh"]])]
        binds[expr.name] = out
    return binds


# -- serialization --------------------------------------------------------------------------------
def _finish(doc: dict, bin_writer: _Binary, buffers_data: list, path: Path, binary: bool) -> None:
    body = bin_writer.data() or b"\0\0\0\0"  # a buffer holds at least one byte
    buffers = doc["buffers"]
    buffers[0]["byteLength"] = len(body)
    for i, buf in enumerate(buffers):
        data = body if i == 0 else buffers_data[i]
        if data is None:
            continue  # a meshopt fallback buffer: no data by design
        if i == 0 and binary:
            buf.pop("uri", None)
        elif i > 0 and isinstance(buf.get("uri"), str) and buf["uri"].startswith("data:"):
            continue
        else:
            buf["uri"] = "data:application/octet-stream;base64," + base64.b64encode(bytes(data)).decode("ascii")
    text = json.dumps(doc, separators=(",", ":"), ensure_ascii=False).encode("utf-8")
    if not binary:
        path.write_bytes(text)
        return
    text += b" " * ((-len(text)) % 4)
    chunks = struct.pack("<II", len(text), CHUNK_JSON) + text
    if "uri" not in buffers[0]:
        body += b"\0" * ((-len(body)) % 4)
        chunks += struct.pack("<II", len(body), CHUNK_BIN) + body
    path.write_bytes(GLB_MAGIC + struct.pack("<II", 2, 12 + len(chunks)) + chunks)
