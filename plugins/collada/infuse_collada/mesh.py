"""The skinned meshes of a COLLADA scene as core :class:`~infuse.mesh.SkinnedMesh` surfaces.

One surface per primitive (one material) of every ``<instance_controller>`` and
``<instance_geometry>`` in the visual scene. With ``C`` the file-to-core matrix (unit scale and
up axis, as for the skeleton) and a skin's ``BSM``, ``W_i`` and ``IBM_i`` (see
:mod:`infuse_collada.skin`), a skinned surface keeps its bind shape ``C · BSM · v`` (metres, core
frame) and per bone ``inverse_bind = G_i⁻¹ · C · W_i · IBM_i · C⁻¹``, with ``G_i`` the joint's rigid
rest transform in the core skeleton: skinning with the core FK transforms then reproduces the
file's skinning exactly, whatever its units, up axis or scaled nodes above the skeleton. The
node holding a skin's instance does not move it (as COLLADA says). A geometry instanced without
a skin follows the nearest joint at or above its node rigidly, where its node puts it in the
rest pose; one outside the skeleton is not drawn. A skin whose source is a ``<morph>`` keeps
the morph's base geometry and its targets as position offsets.

Vertices are the distinct (position, normal, texture coordinate) corners of a primitive, so hard
edges keep their normals; a primitive without normals gets smooth ones (area-weighted, shared by
the corners of a position). Colours: see :mod:`infuse_collada.material`.

What cannot be drawn (a geometry without ``<mesh>``, a skin naming a missing geometry, a
malformed array in one instance) is left out with a warning in ``Asset.warnings``; only when
malformed data leaves nothing to draw does :class:`~infuse.errors.InputError` name it.
"""
from __future__ import annotations

import numpy as np

from infuse.errors import InputError
from infuse.mesh import SkinnedMesh, area_normals, rigid_matrices

from . import material
from .document import Document, place
from .geometry import Geometry, Input, Primitive, read_geometry
from .scene import SceneNode, find_joint
from .skin import read_skin

class MeshLoader:
    """Builds the surfaces of one document on demand (see the module doc); called by ``Asset.meshes``.

    ``nodes``/``elements``: the flattened visual scene; ``joints``: the node index of each skeleton
    joint; ``world`` (N, 4, 4): every node's rest world matrix in file units; ``change`` (4, 4):
    file to core frame; ``warnings``: the asset's ``warnings``, appended to.
    """

    def __init__(self, doc: Document, nodes: list[SceneNode], elements: list, joints: list[int],
                 world: np.ndarray, change: np.ndarray, skeleton, warnings: list[str]):
        self.doc, self.nodes, self.elements = doc, nodes, elements
        self.joint_of_node = {n: j for j, n in enumerate(joints)}
        self.index_of = {id(el): i for i, el in enumerate(elements)}
        self.world, self.change, self.skeleton, self.warnings = world, change, skeleton, warnings
        self._geometries: dict[int, Geometry | None] = {}
        self._sources: dict[str, np.ndarray] = {}
        self._images: dict[object, np.ndarray | None] = {}
        self._missing: set[str] = set()
        self._skipped: dict[str, list[str]] = {}  # why -> where

    def __call__(self) -> list[SkinnedMesh]:
        with np.errstate(all="ignore"):  # huge values overflow to infinity, which the surfaces' checks name
            return self._surfaces()

    def _surfaces(self) -> list[SkinnedMesh]:
        rest = rigid_matrices(self.skeleton.rest_global_rotations, self.skeleton.rest_global_positions)
        out: list[SkinnedMesh] = []
        errors: list[InputError] = []
        for n, el in enumerate(self.elements):
            for inst in el:
                if inst.tag not in ("instance_controller", "instance_geometry"):
                    continue
                try:
                    out.extend(self._instance(n, inst, rest))
                except InputError as exc:
                    errors.append(exc)
                    self._skip(exc.place or place(inst), exc.problem)
                except ValueError as exc:  # the surface's own checks: values that overflowed to infinity
                    errors.append(self.doc.error(inst, str(exc)))
                    self._skip(place(inst), str(exc))
        if errors and not out:
            raise errors[0]
        for why, places in self._skipped.items():
            more = f" and {len(places) - 1} more" if len(places) > 1 else ""
            self.warnings.append(f"{places[0]}{more}: not drawn: {why}")
        if self._missing:
            self.warnings.append(f"texture images not found beside the file, plain colours used: {', '.join(sorted(self._missing))}")
        return out

    # -- where the vertices go ----------------------------------------------------------------------
    def _instance(self, n: int, inst, rest: np.ndarray) -> list[SkinnedMesh]:
        doc = self.doc
        target = doc.resolve(inst.get("url"), inst)
        skin = None
        if inst.tag == "instance_controller":
            if target.tag != "controller":
                raise doc.error(inst, f"points to <{target.tag}>, expected <controller>")
            if target.find("skin") is not None:
                skin = read_skin(doc, target.find("skin"))
                if skin.source is None:
                    self._skip(place(inst), "the geometry its skin names is not in the file")
                    return []
                target = skin.source
        geometry_el, morph = self._base(target, inst)
        if geometry_el is None:
            return []
        geometry = self._geometry(geometry_el)
        if geometry is None:
            self._skip(place(geometry_el), "the geometry has no <mesh>")
            return []
        if skin is None:
            bones = self._rigid(n, inst, rest)
            if bones is None:
                return []
            bind_joints, inverse_bind, frame = bones
            joints = np.zeros((len(geometry.positions), 1), dtype=np.int64)
            weights = np.ones((len(geometry.positions), 1))
        else:
            if len(skin.joints) != len(geometry.positions):
                raise doc.error(skin.element.find("vertex_weights"),
                                f"weights for {len(skin.joints)} vertices, the geometry has {len(geometry.positions)} positions")
            roots = [doc.resolve((s.text or "").strip(), s) for s in inst.findall("skeleton")]
            nodes = []
            for name in skin.joint_names:
                found = find_joint(self.nodes, self.elements, self.index_of, roots, name)
                if found is None:
                    raise doc.error(skin.element, f"skin names joint {name[:60]!r}, which is not a node of the scene")
                nodes.append(found)
            bind_joints = np.array([self.joint_of_node[k] for k in nodes], dtype=np.int64)
            frame = self.change @ skin.bind_shape
            inverse_bind = np.linalg.inv(rest[bind_joints]) @ self.change @ self.world[nodes] @ skin.inverse_bind @ np.linalg.inv(self.change)
            joints, weights = skin.joints, skin.weights
        if abs(np.linalg.det(frame[:3, :3])) < 1e-18:
            raise doc.error(inst, "its bind shape matrix (or node transform) is singular")
        morph_names, offsets = self._morph_offsets(morph, geometry) if morph is not None else ((), None)
        double_sided = (geometry_el.findtext(".//extra/technique/double_sided") or "").strip() == "1"
        out = []
        for prim in geometry.primitives:
            if not len(prim.positions):
                continue
            label = geometry.name + (f".{prim.material}" if len(geometry.primitives) > 1 and prim.material else "")
            out.append(self._surface(label, geometry, prim, material.look(doc, inst, prim.material), frame,
                                     bind_joints, inverse_bind, joints, weights, morph_names, offsets, double_sided))
        return out

    def _base(self, element, inst):
        """``(geometry element, morph element or None)`` a skin's source or an instance's target leads
        to; ``(None, None)`` (with a warning) when it leads elsewhere (a morph of a morph, a spline)."""
        morph = None
        if element.tag == "controller" and element.find("morph") is not None:
            morph = element.find("morph")
            element = self.doc.resolve(morph.get("source"), morph)
        if element.tag == "geometry":
            return element, morph
        self._skip(place(inst), f"it does not lead to a geometry (a skin or morph of <{element.tag}>)")
        return None, None

    def _skip(self, where: str, why: str) -> None:
        self._skipped.setdefault(why, []).append(where)

    def _rigid(self, n: int, inst, rest: np.ndarray):
        """``(bind_joints (1,), inverse_bind (1, 4, 4), frame)`` of a geometry following the nearest joint
        at or above node ``n``; ``None`` (with a warning) when no joint is above it."""
        k = n
        while k >= 0 and k not in self.joint_of_node:
            k = self.nodes[k].parent
        if k < 0:
            self._skip(f"{place(inst)} in node {self.nodes[n].name!r}", "it has no skin and no joint above it")
            return None
        j = self.joint_of_node[k]
        return np.array([j]), np.linalg.inv(rest[[j]]), self.change @ self.world[n]

    # -- one primitive ------------------------------------------------------------------------------
    def _surface(self, label: str, geometry: Geometry, prim: Primitive, look: material.Look, frame: np.ndarray,
                 bind_joints, inverse_bind, joints, weights, morph_names, offsets, double_sided: bool) -> SkinnedMesh:
        linear = frame[:3, :3]
        mirrored = np.linalg.det(linear) < 0
        uv_input = self._texcoord_input(prim, look)
        keyed = [(prim.positions, len(geometry.positions))]
        normal_values = uv_values = None
        if prim.normals is not None:
            normal_values = self._source(prim.normals, 3)
            keyed.append((prim.normals.indices, len(normal_values)))
        if uv_input is not None:
            uv_values = self._source(uv_input, 2)
            keyed.append((uv_input.indices, len(uv_values)))
        key = np.zeros(prim.positions.size, dtype=np.int64)
        for indices, count in keyed:
            key = key * count + indices.reshape(-1)
        _, first, inverse = np.unique(key, return_index=True, return_inverse=True)
        pos_index = prim.positions.reshape(-1)[first]
        triangles = inverse.reshape(-1, 3)
        position_tris = prim.positions
        if mirrored:  # a mirroring frame turns faces inside out: keep them counter-clockwise
            triangles, position_tris = triangles[:, ::-1], position_tris[:, ::-1]
        all_positions = geometry.positions @ linear.T + frame[:3, 3]
        positions = all_positions[pos_index]
        if normal_values is not None:
            normals = normal_values[prim.normals.indices.reshape(-1)[first]]
        elif geometry.normals is not None:
            normals = geometry.normals[pos_index]
        else:
            normals = np.zeros_like(positions)
        normals = normals @ np.linalg.inv(linear)  # normals transform by the inverse transpose
        length = np.linalg.norm(normals, axis=1)
        if np.any(length < 1e-12):
            normals = np.where((length < 1e-12)[:, None], area_normals(all_positions, position_tris)[pos_index], normals)
            length = np.linalg.norm(normals, axis=1)
        normals = normals / np.maximum(length, 1e-12)[:, None]
        colors, base_color = None, look.color
        if uv_values is not None:
            pixels = self._pixels(look.image)
            if pixels is not None:  # the texture is the diffuse colour: white times the texels
                base_color = np.append(np.ones(3), look.color[3])
                colors = np.clip(material.sample(pixels, uv_values[uv_input.indices.reshape(-1)[first]]) * base_color, 0.0, 1.0)
        morph_positions = None if offsets is None else (offsets @ linear.T)[:, pos_index]
        return SkinnedMesh(label, positions, normals, triangles, joints[pos_index], weights[pos_index], bind_joints,
                           inverse_bind, base_color=base_color, colors=colors, double_sided=double_sided,
                           morph_names=morph_names, morph_positions=morph_positions)

    def _texcoord_input(self, prim: Primitive, look: material.Look) -> Input | None:
        """The texture coordinates a found texture reads (its bound set, else the first); ``None`` without one."""
        if look.missing:
            self._missing.add(look.missing)
        if look.image is None or not prim.texcoords:
            return None
        return next((t for t in prim.texcoords if t.set == look.texcoord_set), prim.texcoords[0])

    # -- data, read once ----------------------------------------------------------------------------
    def _geometry(self, element) -> Geometry | None:
        if id(element) not in self._geometries:
            self._geometries[id(element)] = read_geometry(self.doc, element)
        return self._geometries[id(element)]

    def _source(self, item: Input, width: int) -> np.ndarray:
        """The values (count, width) an input reads, its indices checked against them."""
        if item.url not in self._sources:
            values = self.doc.source(item.url, item.element)
            if values.shape[1] < width:
                raise self.doc.error(item.element, f"source {item.url!r} has {values.shape[1]} values per item, expected {width}")
            self._sources[item.url] = values
        values = self._sources[item.url][:, :width]
        if item.indices.size and (item.indices.min() < 0 or item.indices.max() >= len(values)):
            raise self.doc.error(item.element, f"an index is out of range (the source has {len(values)} items)")
        return values

    def _pixels(self, path) -> np.ndarray | None:
        if path not in self._images:
            self._images[path] = None
            try:
                self._images[path] = material.read_image(path)
            except ImportError:
                self.warnings.append("texture images are not used: Pillow is not installed")
            except (OSError, ValueError) as exc:
                self.warnings.append(f"texture {path.name} is not used: {exc}")
        return self._images[path]

    def _morph_offsets(self, morph, base: Geometry) -> tuple[tuple[str, ...], np.ndarray | None]:
        """Target names and position offsets (M, P, 3), file units, of a ``<morph>`` on ``base``."""
        doc = self.doc
        targets = morph.find("targets/input[@semantic='MORPH_TARGET']")
        if targets is None:
            raise doc.error(morph, "morph has no MORPH_TARGET input")
        names, offsets = [], []
        relative = morph.get("method", "NORMALIZED") == "RELATIVE"
        for ref in doc.source(targets.get("source"), targets, numeric=False).ravel():
            element = doc.ids.get(str(ref))
            geometry = self._geometry(element) if element is not None and element.tag == "geometry" else None
            if geometry is None or len(geometry.positions) != len(base.positions):
                raise doc.error(morph, f"morph target {str(ref)[:60]!r} is not a mesh with the base's {len(base.positions)} positions")
            names.append(element.get("name") or str(ref))
            offsets.append(geometry.positions if relative else geometry.positions - base.positions)
        return tuple(names), (np.array(offsets) if offsets else None)

