"""The mesh geometries of an FBX document as core :class:`~infuse.mesh.SkinnedMesh` surfaces.

One surface per material of every model that shows a ``Mesh`` geometry. Polygons become triangle
fans; a vertex is split where its corners differ in normal (or texture coordinates, when the
material has a texture). Each geometry point ``x`` (after the model's geometric transform
``Geo = T · R · S`` of ``GeometricTranslation/Rotation/Scaling``) is placed, in the file, where
the skin bound it: ``M · Geo · x``, ``M`` the mesh's bind matrix (see :mod:`.skin`); the core mesh
keeps it in the core frame, ``P = C · M · Geo · x`` (``C`` the same unit and up-axis change the
skeleton got), so it is in metres, in the bind pose. A bone ``b`` of joint ``j`` moves it in the
file's rest pose by ``W_j · Transform_b`` and so gets
``inverse_bind = G_j⁻¹ · C · W_j · Transform_b · M⁻¹ · C⁻¹``, ``G_j`` the joint's rigid rest
transform in the core skeleton: skinning with the core skeleton's rest pose then reproduces the
file's rest pose exactly, whatever the file's units, axes or scaled models above the skeleton.
Each point keeps its :data:`~.skin.MAX_INFLUENCES` largest weights, renormalized. Points that no
cluster moves, and meshes without a skin, follow the nearest joint above the mesh's model rigidly
(the root joint when the model hangs outside the skeleton; an unskinned mesh outside it is not
drawn). Normals come from the first ``LayerElementNormal`` (smooth normals are computed without
one); the material of each polygon from ``LayerElementMaterial``; colours from :mod:`.material`.
Blend-shape channels (``BlendShape`` -> ``BlendShapeChannel`` -> ``Shape`` with ``Indexes`` and
``Vertices`` offsets; the full-weight shape of each channel) become morph targets named after
their channel. A geometry that cannot be used is left out with a warning in ``Asset.warnings``.
"""
from __future__ import annotations

import numpy as np

from infuse.errors import InfuseError
from infuse.mesh import SkinnedMesh, rigid_matrices

from . import geometry, material, skin
from .document import Document, FbxObject, vector
from .geometry import GeometryError, Polygons
from .models import Model, euler_matrices


class MeshLoader:
    """Builds the surfaces of one document on demand (called once by ``Asset.meshes``).

    ``models`` (parents first) with ``world`` (N, 4, 4) their rest global matrices in the file's
    frame; ``joints``: the model index of each skeleton joint; ``change``: the 4x4 file -> core
    frame change; ``warnings``: the asset's ``warnings``, which reasons to skip go to.
    """

    def __init__(self, doc: Document, models: list[Model], world: np.ndarray, joints: list[int], change: np.ndarray,
                 skeleton, warnings: list[str]):
        self.doc, self.models, self.world = doc, models, world
        self.model_index = {m.obj.id: i for i, m in enumerate(models)}
        self.joint_of_model = {m: j for j, m in enumerate(joints)}
        self.change = change
        self.rest = rigid_matrices(skeleton.rest_global_rotations, skeleton.rest_global_positions)
        self.warnings = warnings
        self.textures = material.Textures(doc, warnings)

    def __call__(self) -> list[SkinnedMesh]:
        out: list[SkinnedMesh] = []
        with np.errstate(all="ignore"):  # non-finite results are caught by the checks, not numpy's warnings
            for geom in (o for o in self.doc.objects.values() if o.kind == "Geometry" and o.subclass == "Mesh"):
                users = [self.model_index[m.id] for m, _ in self.doc.parents_of(geom.id, "Model") if m.id in self.model_index]
                if not users:
                    self.warnings.append(f"geometry {geom.name!r} belongs to no model: not drawn")
                for i in users:
                    label = self.models[i].obj.name or geom.name
                    try:
                        out.extend(self._surfaces(geom, i, label))
                    except (InfuseError, ValueError, IndexError, OSError, np.linalg.LinAlgError) as exc:
                        self.warnings.append(f"mesh {label!r} is not drawn: {getattr(exc, 'problem', exc)}")
        return out

    # -- one model's geometry -------------------------------------------------------------------
    def _surfaces(self, geom: FbxObject, i: int, label: str) -> list[SkinnedMesh]:
        polys = geometry.polygons(geom.node)
        if not len(polys.triangles):
            raise GeometryError("has no polygon with three corners")
        num_points = len(polys.points)
        bind, bone_models, bone_file, point_bones, point_weights = self._binding(geom, i, num_points)
        to_core = self.change @ bind @ self._geometric(self.models[i])
        linear = to_core[:3, :3]
        det = np.linalg.det(linear)
        if not np.isfinite(det) or abs(det) < 1e-30:
            raise GeometryError("its bind matrix is singular")
        points = polys.points @ linear.T + to_core[:3, 3]
        inverse_bind = (np.linalg.inv(self.rest[[self.joint_of_model[b] for b in bone_models]]) @ self.change @ bone_file
                        @ np.linalg.inv(bind) @ np.linalg.inv(self.change))
        bind_joints = np.array([self.joint_of_model[b] for b in bone_models], dtype=np.int64)
        normals = self._normals(geom, polys, linear)
        morph_names, morph_points = self._morphs(geom, num_points, linear)

        mats = [m for m, _ in self.doc.children_of(self.models[i].obj.id, "Material")]
        slots = geometry.polygon_materials(geom.node, polys)[polys.corner_polygon[polys.triangles[:, 0]]]
        used_slots = np.unique(slots)
        slot_material = {int(s): mats[s] if 0 <= s < len(mats) else None for s in used_slots}
        slot_texture = {s: self.textures.diffuse(m) for s, m in slot_material.items()}
        uv = self._uv(geom, polys) if any(t is not None for t in slot_texture.values()) else None

        # One core vertex per distinct (point, normal[, uv]) corner.
        key = [polys.corner_points[:, None].astype(np.float64), normals] + ([uv] if uv is not None else [])
        _, first_corner, vertex = np.unique(np.concatenate(key, axis=1), axis=0, return_index=True, return_inverse=True)
        vertex = vertex.reshape(-1)
        out = []
        for s in used_slots:
            triangles = vertex[polys.triangles[slots == s]]
            used, local = np.unique(triangles, return_inverse=True)
            local = local.reshape(-1, 3)
            if det < 0:  # a mirroring transform turns faces inside out: keep them counter-clockwise
                local = local[:, ::-1]
            corners = first_corner[used]
            cp = polys.corner_points[corners]
            mat = slot_material[int(s)]
            texture = slot_texture[int(s)]
            colors = material.sample(texture, uv[corners]) if texture is not None and uv is not None else None
            name = label if len(used_slots) == 1 else f"{label}/{mat.name if mat is not None else int(s)}"
            out.append(SkinnedMesh(
                name, points[cp], normals[corners], local, point_bones[cp], point_weights[cp], bind_joints, inverse_bind,
                base_color=material.base_color(mat), colors=colors, morph_names=morph_names,
                morph_positions=morph_points[:, cp] if morph_names else None))
        return out

    def _geometric(self, m: Model) -> np.ndarray:
        """The model's geometric transform ``T · R · S`` (R in the model's rotation order)."""
        out = np.eye(4)
        rotation = euler_matrices(m.order, vector(self.doc, m.obj, "GeometricRotation", (0.0, 0.0, 0.0))[None])[0]
        out[:3, :3] = rotation * vector(self.doc, m.obj, "GeometricScaling", (1.0, 1.0, 1.0))
        out[:3, 3] = vector(self.doc, m.obj, "GeometricTranslation", (0.0, 0.0, 0.0))
        return out

    def _anchor(self, i: int) -> int | None:
        """The nearest model at or above model ``i`` that is a skeleton joint."""
        while i >= 0 and i not in self.joint_of_model:
            i = self.models[i].parent
        return i if i >= 0 else None

    def _binding(self, geom: FbxObject, i: int, num_points: int):
        """``(M, bone models (B,), bone matrices (B, 4, 4) geometry -> file rest world, point bones (V, K), point weights (V, K))``."""
        mesh_world = self.world[i]
        skins = [d for d, _ in self.doc.children_of(geom.id, "Deformer") if d.subclass == "Skin"]
        clusters = skin.clusters(self.doc, skins[0], self.model_index, self.world, mesh_world, num_points) if skins else []
        clusters = [c for c in clusters if c.model in self.joint_of_model]
        anchor = self._anchor(i)
        if not clusters:
            if anchor is None:
                raise GeometryError("has no skin and hangs outside the skeleton")
            return mesh_world, [anchor], mesh_world[None], np.zeros((num_points, 1), dtype=np.int64), np.ones((num_points, 1))
        bind = clusters[0].mesh_bind
        bones, weights = skin.influences(clusters, num_points)
        models = [c.model for c in clusters]
        files = [self.world[c.model] @ c.transform for c in clusters]
        loose = weights.sum(axis=1) == 0
        if np.any(loose):  # the file leaves them where the mesh's model puts them
            models.append(anchor if anchor is not None else self._root_model())
            files.append(mesh_world)
            bones[loose, 0] = len(clusters)
            weights[loose, 0] = 1.0
        return bind, models, np.array(files), bones, weights

    def _root_model(self) -> int:
        """The model of the skeleton's first root joint."""
        return next(m for m, j in self.joint_of_model.items() if j == 0)

    # -- corner data ----------------------------------------------------------------------------
    def _normals(self, geom: FbxObject, polys: Polygons, linear: np.ndarray) -> np.ndarray:
        """(N, 3) unit normals, core frame, at every polygon corner."""
        element = geometry.layer(geom.node, "LayerElementNormal")
        normals = None
        if element is not None:
            try:
                normals = geometry.corner_values(element, "Normals", "NormalsIndex", 3, polys) @ np.linalg.inv(linear)
            except GeometryError as exc:
                self.warnings.append(f"geometry {geom.name!r}: normals not used ({exc}); smooth normals computed")
        core_points = polys.points @ linear.T
        smooth = None
        if normals is None:
            smooth = geometry.smooth_normals(core_points, polys.corner_points[polys.triangles])
            if np.linalg.det(linear) < 0:
                smooth = -smooth
            return smooth[polys.corner_points]
        length = np.linalg.norm(normals, axis=1, keepdims=True)
        bad = ~(length[:, 0] > 1e-12)
        normals = normals / np.where(bad[:, None], 1.0, length)
        if np.any(bad):  # zero normals in the file: the faces' own
            smooth = geometry.smooth_normals(core_points, polys.corner_points[polys.triangles])
            normals[bad] = smooth[polys.corner_points[bad]]
        return normals

    def _uv(self, geom: FbxObject, polys: Polygons) -> np.ndarray | None:
        element = geometry.layer(geom.node, "LayerElementUV")
        if element is None:
            self.warnings.append(f"geometry {geom.name!r} has a texture but no texture coordinates: its colour is used")
            return None
        try:
            return geometry.corner_values(element, "UV", "UVIndex", 2, polys)
        except GeometryError as exc:
            self.warnings.append(f"geometry {geom.name!r}: texture coordinates not used ({exc})")
            return None

    def _morphs(self, geom: FbxObject, num_points: int, linear: np.ndarray) -> tuple[tuple[str, ...], np.ndarray | None]:
        """Channel names and (M, V, 3) core-frame offsets of the geometry's blend shapes."""
        names, offsets = [], []
        for shape_set in (d for d, _ in self.doc.children_of(geom.id, "Deformer") if d.subclass == "BlendShape"):
            for channel in (d for d, _ in self.doc.children_of(shape_set.id, "Deformer") if d.subclass == "BlendShapeChannel"):
                shapes = [g for g, _ in self.doc.children_of(channel.id, "Geometry") if g.subclass == "Shape"]
                if not shapes or channel.name in names:
                    continue
                try:
                    delta = _shape_offsets(self._full_shape(channel, shapes), num_points)
                except GeometryError as exc:
                    self.warnings.append(f"blend shape {channel.name!r} of {geom.name!r} is not used: {exc}")
                    continue
                names.append(channel.name)
                offsets.append(delta @ linear.T)
        return tuple(names), (np.array(offsets) if names else None)

    def _full_shape(self, channel: FbxObject, shapes: list[FbxObject]) -> FbxObject:
        """The shape a channel reaches at full weight: its last (in-between shapes come first)."""
        full = geometry.array(channel.node, "FullWeights", required=False)
        if full is not None and len(full) == len(shapes):
            return shapes[int(np.argmax(full))]
        return shapes[-1]


def _shape_offsets(shape: FbxObject, num_points: int) -> np.ndarray:
    """(V, 3) offsets of a ``Shape`` geometry's points, file units, geometry space."""
    index = geometry.array(shape.node, "Indexes").astype(np.int64)
    values = geometry.array(shape.node, "Vertices").astype(np.float64)
    if values.size != 3 * len(index) or not np.all(np.isfinite(values)):
        raise GeometryError(f"{len(index)} indices and {values.size} offset numbers")
    if len(index) and (index.min() < 0 or index.max() >= num_points):
        raise GeometryError(f"names point {int(index.max())} of {num_points}")
    out = np.zeros((num_points, 3))
    out[index] = values.reshape(-1, 3)
    return out
