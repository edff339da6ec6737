"""The skinned meshes of a glTF document as core :class:`~infuse.mesh.SkinnedMesh` surfaces.

One surface per triangle primitive of every mesh node in the scene. A skinned node's vertices are
bound through its skin: joint ``j`` moves a vertex by ``C · W_j · IBM_j`` in the file (``C`` the
file-to-core similarity, ``W_j`` the joint's world matrix, ``IBM_j`` its inverse bind matrix). The
core mesh keeps the vertices as the skin's root bone binds them (``A = C · W_r · IBM_r``: the bind
pose in the core frame, in metres, where the rest skeleton's root bone stands) and per bone
``inverse_bind = G_j⁻¹ · C · W_j · IBM_j · A⁻¹``, with ``G_j`` the joint's rigid rest transform in
the core skeleton. Skinning with the core FK transforms then reproduces the file's skinning
exactly, whatever the file's units, up axis or scaled nodes above the skeleton. A mesh node
without a skin that hangs under a joint follows that joint rigidly; one outside the skeleton is
not drawn (a warning says so).

Colour: the material's base colour factor, times the base colour texture sampled at each vertex
(bilinear, on the texture reduced to at most :data:`infuse.texture.TEXTURE_SIZE` pixels, sRGB converted to linear),
times ``COLOR_0``. Triangles whose three vertices fall under the alpha cutoff (``MASK``) or are
mostly transparent (``BLEND``) are dropped. Morph targets keep their position offsets; default mesh
weights are not applied. Compressed mesh data is decoded: meshopt views (indices, octahedral normals)
and Draco primitives (:mod:`infuse_gltf.draco`, which needs the ``DracoPy`` package: without it they are
skipped with a warning in ``Asset.warnings``); points and lines are not surfaces and are left out.
"""
from __future__ import annotations

import numpy as np

from infuse.errors import InputError, MissingFeatureError
from infuse.mesh import SkinnedMesh, area_normals, rigid_matrices
from infuse.texture import TEXTURE_SIZE, bilinear, decode_image

from . import draco
from .accessors import AccessorReader
from .container import read_uri
from .morph import mesh_target_names

#: Alpha under which a ``BLEND`` material's vertex counts as transparent.
BLEND_CUTOFF = 0.5
WRAP_CLAMP, WRAP_MIRROR = 33071, 33648


def similarity_matrix(t, q, s) -> np.ndarray:
    """4x4 matrix of the similarity ``x -> t + s · rotate(q, x)``."""
    return rigid_matrices(np.asarray(q, dtype=np.float64), np.asarray(t, dtype=np.float64)) @ np.diag([s, s, s, 1.0])


class MeshLoader:
    """Builds the surfaces of one document on demand (see the module doc); called by ``Asset.meshes``."""

    def __init__(self, doc, graph, world: np.ndarray, joint_nodes, core_from_file, skeleton, warnings: list[str]):
        self.doc, self.graph, self.world = doc, graph, world
        self.accessors = AccessorReader(doc, mesh=True)
        self.joint_of_node = {n: j for j, n in enumerate(joint_nodes)}
        self.core = similarity_matrix(*core_from_file)
        self.skeleton = skeleton
        self.warnings = warnings
        self.file = doc.path
        self._textures: dict[int, tuple | None] = {}

    def __call__(self) -> list[SkinnedMesh]:
        js = self.doc.json
        nodes, meshes = js.get("nodes") or [], js.get("meshes") or []
        names = mesh_target_names(js)
        rest = rigid_matrices(self.skeleton.rest_global_rotations, self.skeleton.rest_global_positions)
        out: list[SkinnedMesh] = []
        skipped: dict[str, list[str]] = {}  # why -> primitives
        for n in self._scene_nodes():
            m = nodes[n].get("mesh")
            if not isinstance(m, int) or not 0 <= m < len(meshes) or not isinstance(meshes[m], dict):
                continue
            bones = self._bones(n, nodes[n], rest)
            if bones is None:
                continue
            prims = meshes[m].get("primitives")
            for p, prim in enumerate(prims if isinstance(prims, list) else []):
                label = f"{meshes[m].get('name') or nodes[n].get('name') or f'mesh{m}'}" + (f".{p}" if len(prims) > 1 else "")
                try:
                    surface = self._primitive(prim, f"meshes[{m}].primitives[{p}]", label, bones, names[m])
                except MissingFeatureError as exc:
                    skipped.setdefault(exc.problem, []).append(f"meshes[{m}].primitives[{p}]")
                    continue
                if surface is not None:
                    out.append(surface)
        for why, places in skipped.items():
            more = f" and {len(places) - 1} more primitives" if len(places) > 1 else ""
            self.warnings.append(f"{places[0]}{more} not drawn: {why}")
        return out

    # -- where the vertices go ----------------------------------------------------------------------
    def _scene_nodes(self) -> list[int]:
        """Nodes of the default scene (every node when the file has no scene), parents first."""
        js = self.doc.json
        scenes = js.get("scenes")
        index = js.get("scene", 0)
        roots = None
        if isinstance(scenes, list) and isinstance(index, int) and 0 <= index < len(scenes) and isinstance(scenes[index], dict):
            roots = [r for r in scenes[index].get("nodes") or [] if isinstance(r, int) and 0 <= r < len(self.graph.parent)]
        if roots is None:
            return list(self.graph.order)
        out, stack = [], list(reversed(roots))
        while stack:
            k = stack.pop()
            out.append(k)
            stack.extend(reversed(self.graph.children[k]))
        return out

    def _bones(self, n: int, node: dict, rest: np.ndarray):
        """``(bind_joints (B,), file_bind (B, 4, 4), rest (B, 4, 4))``: each bone's skeleton joint, its
        ``C · W_j · IBM_j`` and its rigid rest transform ``G_j``; ``None`` when the node is not drawn."""
        js = self.doc.json
        skin = node.get("skin")
        if isinstance(skin, int) and 0 <= skin < len(js.get("skins") or []):
            joints = js["skins"][skin]["joints"]
            count = len(joints)
            ibm_index = js["skins"][skin].get("inverseBindMatrices")
            if ibm_index is None:
                ibm = np.broadcast_to(np.eye(4), (count, 4, 4))
            else:
                try:
                    ibm = np.swapaxes(self.accessors.read(ibm_index, f"skins[{skin}].inverseBindMatrices"), 1, 2)  # column-major
                except MissingFeatureError as exc:
                    self.warnings.append(f"nodes[{n}] is not drawn: {exc.problem}")
                    return None
                if ibm.shape != (count, 4, 4):
                    raise InputError(self.file, f"skins[{skin}].inverseBindMatrices", f"holds {len(ibm)} matrices for {count} joints")
            bind_joints = np.array([self.joint_of_node[j] for j in joints], dtype=np.int64)
            file_bind = self.core @ self.world[list(joints)] @ ibm.astype(np.float64)
            return bind_joints, file_bind, rest[bind_joints]
        k = n
        while k >= 0 and k not in self.joint_of_node:
            k = int(self.graph.parent[k])
        if k < 0:
            self.warnings.append(f"nodes[{n}] ({node.get('name')!r}) has a mesh outside the skeleton: not drawn")
            return None
        j = self.joint_of_node[k]
        return np.array([j]), (self.core @ self.world[n])[None], rest[[j]]

    # -- one primitive ------------------------------------------------------------------------------
    def _read(self, index, place: str) -> np.ndarray:
        return np.asarray(self.accessors.read(index, place))

    def _primitive(self, prim, place: str, label: str, bones, target_names: list[str]) -> SkinnedMesh | None:
        if not isinstance(prim, dict):
            raise InputError(self.file, place, "is not an object")
        attributes = prim.get("attributes")
        if not isinstance(attributes, dict) or "POSITION" not in attributes:
            raise InputError(self.file, f"{place}.attributes", "has no POSITION")
        mode = prim.get("mode", 4)
        if mode not in (4, 5, 6):
            return None  # points and lines are not surfaces
        extensions = prim.get("extensions")
        compressed = isinstance(extensions, dict) and draco.EXTENSION in extensions
        # A Draco primitive's attribute accessors are filled by the decoder before they are read.
        draco_triangles = draco.load_primitive(self.accessors, prim, place) if compressed else None
        raw = self._read(attributes["POSITION"], f"{place}.attributes.POSITION").astype(np.float64)
        v = len(raw)
        if draco_triangles is None:
            triangles = self._triangles(prim, place, mode, v)
        elif draco_triangles.size and draco_triangles.max() >= v:
            raise InputError(self.file, f"{place}.attributes.POSITION", f"has {v} vertices, fewer than the Draco faces name")
        else:
            triangles = draco_triangles
        bind_joints, file_bind, rest = bones
        joints, weights = self._influences(attributes, place, v, len(bind_joints))
        frame = file_bind[int(np.argmin(self.skeleton.depths[bind_joints]))]  # the bind frame of the skin's root bone
        if abs(np.linalg.det(frame[:3, :3])) < 1e-18:
            raise MissingFeatureError(self.file, "its bind matrix is singular")
        to_bind = np.linalg.inv(frame)
        inverse_bind = np.linalg.inv(rest) @ file_bind @ to_bind
        linear = frame[:3, :3]
        positions = raw @ linear.T + frame[:3, 3]
        if np.linalg.det(linear) < 0:  # a mirroring bind frame turns faces inside out: keep them counter-clockwise
            triangles = triangles[:, ::-1]
        if "NORMAL" in attributes:
            normals = self._read(attributes["NORMAL"], f"{place}.attributes.NORMAL").astype(np.float64) @ np.linalg.inv(linear)
        else:
            normals = area_normals(positions, triangles)
        normals /= np.maximum(np.linalg.norm(normals, axis=-1, keepdims=True), 1e-12)
        material = self._material(prim.get("material"))
        colors = self._colors(attributes, place, material, v)
        alpha_mode = material.get("alphaMode", "OPAQUE")
        if colors is not None and alpha_mode in ("MASK", "BLEND") and len(triangles):
            cutoff = float(material.get("alphaCutoff", 0.5)) if alpha_mode == "MASK" else BLEND_CUTOFF
            triangles = triangles[~np.all(colors[triangles, 3] < cutoff, axis=1)]
        morph_names, morph_positions = (), None
        targets = prim.get("targets")
        if isinstance(targets, list) and targets and len(target_names) == len(targets):
            deltas = np.zeros((len(targets), v, 3))
            for k, target in enumerate(targets):
                if isinstance(target, dict) and "POSITION" in target:
                    delta = self._read(target["POSITION"], f"{place}.targets[{k}].POSITION")
                    if delta.shape != (v, 3):
                        raise InputError(self.file, f"{place}.targets[{k}].POSITION", f"holds {delta.shape} offsets for {v} vertices")
                    deltas[k] = delta
            morph_names, morph_positions = tuple(target_names), deltas @ linear.T
        pbr = material.get("pbrMetallicRoughness") or {}
        base = np.array(pbr.get("baseColorFactor", (1.0, 1.0, 1.0, 1.0)), dtype=np.float64)
        return SkinnedMesh(label, positions, normals, triangles, joints, weights, bind_joints, inverse_bind,
                           base_color=base if base.shape == (4,) else np.ones(4), colors=colors,
                           double_sided=bool(material.get("doubleSided", False)),
                           morph_names=morph_names, morph_positions=morph_positions)

    def _triangles(self, prim, place: str, mode: int, v: int) -> np.ndarray:
        if "indices" in prim:
            idx = self._read(prim["indices"], f"{place}.indices").reshape(-1).astype(np.int64)
            if idx.size and (idx.min() < 0 or idx.max() >= v):
                raise InputError(self.file, f"{place}.indices", f"an index is out of range (there are {v} vertices)")
        else:
            idx = np.arange(v)
        if mode == 4:
            return idx[: len(idx) // 3 * 3].reshape(-1, 3)
        k = np.arange(max(len(idx) - 2, 0))
        if mode == 5:  # strip: every other triangle is wound the other way
            odd = k % 2 == 1
            return np.stack([idx[k], np.where(odd, idx[k + 2], idx[k + 1]), np.where(odd, idx[k + 1], idx[k + 2])], axis=1)
        return np.stack([np.full(len(k), idx[0]), idx[k + 1], idx[k + 2]], axis=1)  # fan

    def _influences(self, attributes: dict, place: str, v: int, bones: int) -> tuple[np.ndarray, np.ndarray]:
        """(V, K) bone indices and normalized weights; rigid (one bone, weight 1) without JOINTS_0."""
        sets = []
        k = 0
        while f"JOINTS_{k}" in attributes and f"WEIGHTS_{k}" in attributes:
            j = self._read(attributes[f"JOINTS_{k}"], f"{place}.attributes.JOINTS_{k}").astype(np.int64)
            w = self._read(attributes[f"WEIGHTS_{k}"], f"{place}.attributes.WEIGHTS_{k}").astype(np.float64)
            if j.shape != (v, 4) or w.shape != (v, 4):
                raise InputError(self.file, f"{place}.attributes.JOINTS_{k}", "JOINTS/WEIGHTS must be VEC4 with one per vertex")
            sets.append((j, w))
            k += 1
        if not sets or bones == 1:
            return np.zeros((v, 1), dtype=np.int64), np.ones((v, 1))
        joints = np.concatenate([j for j, _ in sets], axis=1)
        weights = np.maximum(np.concatenate([w for _, w in sets], axis=1), 0.0)
        if np.any(joints[weights > 0] >= bones):
            raise InputError(self.file, f"{place}.attributes.JOINTS_0", f"names a joint beyond the skin's {bones}")
        joints = np.where(weights > 0, joints, 0)
        total = weights.sum(axis=1, keepdims=True)
        weights = np.where(total > 0, weights / np.where(total > 0, total, 1.0), np.eye(1, weights.shape[1]))
        return joints, weights

    # -- colour ---------------------------------------------------------------------------------
    def _material(self, index) -> dict:
        materials = self.doc.json.get("materials") or []
        if isinstance(index, int) and 0 <= index < len(materials) and isinstance(materials[index], dict):
            return materials[index]
        return {}

    def _colors(self, attributes: dict, place: str, material: dict, v: int) -> np.ndarray | None:
        """(V, 4) linear RGBA, or ``None`` when every vertex has the plain base colour."""
        pbr = material.get("pbrMetallicRoughness") or {}
        base = np.array(pbr.get("baseColorFactor", (1.0, 1.0, 1.0, 1.0)), dtype=np.float64).reshape(-1)
        base = base if base.shape == (4,) else np.ones(4)
        colors = None
        texture = pbr.get("baseColorTexture")
        if isinstance(texture, dict) and isinstance(texture.get("index"), int):
            uv_key = f"TEXCOORD_{texture.get('texCoord', 0)}"
            image = self._texture(texture["index"]) if uv_key in attributes else None
            if image is not None:
                uv = self._read(attributes[uv_key], f"{place}.attributes.{uv_key}").astype(np.float64)
                colors = sample_texture(*image, uv) * base
        if "COLOR_0" in attributes:
            c = self._read(attributes["COLOR_0"], f"{place}.attributes.COLOR_0").astype(np.float64)
            c = np.concatenate([c, np.ones((v, 1))], axis=1) if c.shape[1] == 3 else c
            colors = (colors if colors is not None else base) * c
        return None if colors is None else np.clip(colors, 0.0, 1.0)

    def _texture(self, index: int):
        """``(linear RGBA image (H, W, 4), wrap_s, wrap_t)`` of texture ``index``, reduced; ``None`` if unreadable."""
        if index in self._textures:
            return self._textures[index]
        self._textures[index] = None
        js = self.doc.json
        textures, images = js.get("textures") or [], js.get("images") or []
        if not 0 <= index < len(textures) or not isinstance(textures[index], dict):
            return None
        tex = textures[index]
        source = tex.get("source")
        for ext in (tex.get("extensions") or {}).values():  # EXT_texture_webp and the like name their own image
            if source is None and isinstance(ext, dict):
                source = ext.get("source")
        if not isinstance(source, int) or not 0 <= source < len(images) or not isinstance(images[source], dict):
            return None
        samplers = js.get("samplers") or []
        sampler = samplers[tex["sampler"]] if isinstance(tex.get("sampler"), int) and 0 <= tex["sampler"] < len(samplers) else {}
        try:
            pixels = self._image_pixels(images[source], f"images[{source}]")
        except (InputError, OSError, ValueError) as exc:
            self.warnings.append(f"images[{source}] is not used for colours: {getattr(exc, 'problem', exc)}")
            return None
        self._textures[index] = (pixels, sampler.get("wrapS", 10497), sampler.get("wrapT", 10497))
        return self._textures[index]

    def _image_pixels(self, image: dict, place: str) -> np.ndarray:
        if isinstance(image.get("bufferView"), int):
            views = self.doc.json.get("bufferViews") or []
            view = views[image["bufferView"]] if image["bufferView"] < len(views) else None
            buffers = self.doc.buffers
            if not isinstance(view, dict) or not isinstance(view.get("buffer"), int) or view["buffer"] >= len(buffers) \
                    or buffers[view["buffer"]] is None:
                raise InputError(self.file, place, "names a missing bufferView")
            start = int(view.get("byteOffset", 0))
            data = bytes(buffers[view["buffer"]][start:start + int(view.get("byteLength", 0))])
        else:
            data = read_uri(image.get("uri"), self.file, place)
        return decode_image(data, TEXTURE_SIZE)


def _wrap(c: np.ndarray, mode) -> np.ndarray:
    if mode == WRAP_CLAMP:
        return np.clip(c, 0.0, 1.0)
    if mode == WRAP_MIRROR:
        return 1.0 - np.abs(np.mod(c, 2.0) - 1.0)
    return np.mod(c, 1.0)


def sample_texture(pixels: np.ndarray, wrap_s, wrap_t, uv: np.ndarray) -> np.ndarray:
    """(N, 4) bilinear samples of ``pixels`` (H, W, 4) at glTF texture coordinates ``uv`` (N, 2)
    (origin at the image's top left corner)."""
    return bilinear(pixels, _wrap(uv[:, 0], wrap_s), _wrap(uv[:, 1], wrap_t))
