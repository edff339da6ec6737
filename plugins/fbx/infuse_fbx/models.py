"""FBX models (scene nodes): hierarchy, which are joints, and their local transforms.

A model's local matrix follows the FBX SDK::

    L = T · Roff · Rp · Rpre · R · Rpost⁻¹ · Rp⁻¹ · Soff · Sp · S · Sp⁻¹

with T/R/S the ``Lcl Translation/Rotation/Scaling`` properties, Euler angles in degrees in the
model's ``RotationOrder`` (``XYZ`` means X applied first), pre/post rotations in XYZ order, and
the rotation/scaling offsets and pivots. As in Blender's importer, pre/post rotations and the
rotation order apply only when ``RotationActive`` is set. Parents combine according to each
model's ``InheritType`` (see :func:`world_matrices`). Geometric transforms affect meshes only
(see :mod:`.mesh`).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .document import Document, FbxObject, number, vector

#: FBX RotationOrder enum -> axes in the order they are applied (extrinsic).
ROTATION_ORDERS = {0: "xyz", 1: "xzy", 2: "yzx", 3: "yxz", 4: "zxy", 5: "zyx", 6: "xyz"}

#: Model subclasses that are skeleton joints, and those kept when they sit above or below one.
BONE_CLASSES = ("LimbNode", "Root")
HELPER_CLASSES = ("Null",)


@dataclass
class Model:
    """A model with its static transform parts (file units, degrees)."""

    obj: FbxObject
    parent: int  # index into the model list, -1 for the scene root
    translation: np.ndarray
    rotation: np.ndarray
    scaling: np.ndarray
    order: str
    pre: np.ndarray  # 3x3
    post_inv: np.ndarray  # 3x3
    rotation_offset: np.ndarray
    rotation_pivot: np.ndarray
    scaling_offset: np.ndarray
    scaling_pivot: np.ndarray
    inherit: int  # InheritType: 0 RrSs (componentwise scale), 1 RSrs (plain products), 2 Rrs (parent scale ignored)


def models(doc: Document) -> list[Model]:
    """Every model, parents before children; a model under two models or on a cycle raises InputError."""
    objs = [o for o in doc.objects.values() if o.kind == "Model"]
    parent_id: dict[int, int | None] = {}
    for o in objs:
        for c in doc.by_child.get(o.id, ()):
            if c.parent != 0 and c.parent not in doc.objects:
                raise doc.error(o.node, f"model {o.name!r} is connected to unknown object id {c.parent}")
        model_parents = [p for p, prop in doc.parents_of(o.id, "Model") if prop is None]
        if len(model_parents) > 1:
            raise doc.error(o.node, f"model {o.name!r} has {len(model_parents)} parent models")
        parent_id[o.id] = model_parents[0].id if model_parents else None
    order: list[int] = []
    state: dict[int, int] = {}  # 1 visiting, 2 done
    for o in objs:
        chain = []
        cur = o.id
        while cur is not None and state.get(cur) != 2:
            if state.get(cur) == 1:
                raise doc.error(doc.objects[cur].node, f"model hierarchy has a cycle through {doc.objects[cur].name!r}")
            state[cur] = 1
            chain.append(cur)
            cur = parent_id[cur]
        for c in reversed(chain):
            state[c] = 2
            order.append(c)
    index = {oid: i for i, oid in enumerate(order)}
    out = []
    for oid in order:
        o = doc.objects[oid]
        p = parent_id[oid]
        out.append(_model(doc, o, index[p] if p is not None else -1))
    return out


def _model(doc: Document, o: FbxObject, parent: int) -> Model:
    from scipy.spatial.transform import Rotation  # imported when an FBX file is read, not with the plugin

    active = number(doc, o.props, "RotationActive", 0.0, o.node) != 0.0
    order_code = int(number(doc, o.props, "RotationOrder", 0.0, o.node)) if active else 0
    if order_code not in ROTATION_ORDERS:
        raise doc.error(o.node, f"model {o.name!r}: unknown RotationOrder {order_code}")
    zero = (0.0, 0.0, 0.0)
    inherit = int(number(doc, o.props, "InheritType", 1.0, o.node))  # files normally state it in their template
    if inherit not in (0, 1, 2):
        raise doc.error(o.node, f"model {o.name!r}: unknown InheritType {inherit}")
    pre = vector(doc, o, "PreRotation", zero) if active else np.zeros(3)
    post = vector(doc, o, "PostRotation", zero) if active else np.zeros(3)
    return Model(
        o, parent,
        vector(doc, o, "Lcl Translation", zero), vector(doc, o, "Lcl Rotation", zero),
        vector(doc, o, "Lcl Scaling", (1.0, 1.0, 1.0)), ROTATION_ORDERS[order_code],
        Rotation.from_euler("xyz", pre, degrees=True).as_matrix(),
        Rotation.from_euler("xyz", post, degrees=True).inv().as_matrix(),
        vector(doc, o, "RotationOffset", zero), vector(doc, o, "RotationPivot", zero),
        vector(doc, o, "ScalingOffset", zero), vector(doc, o, "ScalingPivot", zero),
        inherit,
    )


def euler_matrices(order: str, degrees: np.ndarray) -> np.ndarray:
    """Rotation matrices (F, 3, 3) from FBX Euler angles (F, 3) given as (x, y, z) in degrees."""
    from scipy.spatial.transform import Rotation

    axes = ["xyz".index(a) for a in order]
    return Rotation.from_euler(order, np.asarray(degrees, dtype=np.float64)[:, axes], degrees=True).as_matrix()


def local_parts(m: Model, translation: np.ndarray, rotation: np.ndarray, scaling: np.ndarray):
    """Model ``m``'s local transform as parts (t (F,3), r (F,3,3), s (F,3)) with ``L = T(t) · r · S(s)``,
    from per-frame T (F,3), R (F,3, degrees) and S (F,3): pivots and offsets only move the origin."""
    r3 = m.pre @ euler_matrices(m.order, rotation) @ m.post_inv
    rs = r3 * scaling[:, None, :]
    rp, sp = m.rotation_pivot, m.scaling_pivot
    t = translation + m.rotation_offset + rp - r3 @ rp
    t = t + np.einsum("fij,j->fi", r3, m.scaling_offset + sp) - np.einsum("fij,j->fi", rs, sp)
    return t, r3, np.array(scaling, dtype=np.float64)


def _trs(t: np.ndarray, r: np.ndarray, s: np.ndarray) -> np.ndarray:
    out = np.zeros(t.shape[:-1] + (4, 4))
    out[..., :3, :3] = r * s[..., None, :]
    out[..., :3, 3] = t
    out[..., 3, 3] = 1.0
    return out


def world_matrices(ms: list[Model], t: np.ndarray, r: np.ndarray, s: np.ndarray) -> np.ndarray:
    """Global matrices (F, N, 4, 4) from local parts (F, N, ...), honouring each model's InheritType.

    RSrs (1, assumed when neither the model nor its template says): ``parent_world · L``. RrSs (0,
    the usual template value) and Rrs (2) start from the parent's
    world without its scale, scale the child's translation by the parent's scale, and give the
    child the parent's scale componentwise after its own rotation (RrSs) or not at all (Rrs).
    Vectorized over frames and over the models of one depth at a time.
    """
    frames, n = t.shape[:2]
    parents = np.array([m.parent for m in ms], dtype=np.int64)
    mode = np.array([m.inherit for m in ms], dtype=np.int64)
    # Rrs models still take the scale accumulated above the nearest RrSs model of their chain.
    source = np.full(n, -1, dtype=np.int64)
    for i, m in enumerate(ms):
        a = m.parent
        while a >= 0 and mode[a] != 0:
            a = ms[a].parent
        source[i] = ms[a].parent if a >= 0 else -1
    world = np.empty((frames, n, 4, 4))
    unscaled = np.empty((frames, n, 4, 4))
    inherit_scale = np.array(s, dtype=np.float64)
    ones = np.ones((frames, 3))
    depth = np.zeros(n, dtype=np.int64)
    for i, p in enumerate(parents):
        depth[i] = depth[p] + 1 if p >= 0 else 0
    for level in range(int(depth.max(initial=0)) + 1):
        idx = np.nonzero(depth == level)[0]
        if level == 0:
            world[:, idx] = _trs(t[:, idx], r[:, idx], s[:, idx])
            unscaled[:, idx] = _trs(t[:, idx], r[:, idx], np.ones_like(s[:, idx]))
            continue
        for i in idx:  # few models per level; each step is vectorized over frames
            p = parents[i]
            if mode[i] == 1:
                world[:, i] = world[:, p] @ _trs(t[:, i], r[:, i], s[:, i])
                unscaled[:, i] = world[:, p] @ _trs(t[:, i], r[:, i], ones)
                continue
            extra = inherit_scale[:, p] if mode[i] == 0 else (inherit_scale[:, source[i]] if source[i] >= 0 else ones)
            scale = s[:, i] * extra
            if mode[i] == 0:
                inherit_scale[:, i] = scale
            moved = t[:, i] * inherit_scale[:, p]
            unscaled[:, i] = unscaled[:, p] @ _trs(moved, r[:, i], ones)
            world[:, i] = unscaled[:, p] @ _trs(moved, r[:, i], scale)
    return world


def joint_models(doc: Document, ms: list[Model]) -> list[int]:
    """Indices of the joints: bones (LimbNode, Root, or linked by a skin cluster), the Null models
    above them, and Null models hanging below a joint (end sites, sockets)."""
    clustered = {o.id for c in doc.objects.values() if c.kind == "Deformer" and c.subclass == "Cluster"
                 for o, _ in doc.children_of(c.id, "Model")}
    is_bone = [m.obj.subclass in BONE_CLASSES or m.obj.id in clustered for m in ms]
    chosen = set()
    for i, bone in enumerate(is_bone):
        if bone:
            chosen.add(i)
            p = ms[i].parent
            while p >= 0:
                if ms[p].obj.subclass in HELPER_CLASSES:
                    chosen.add(p)
                p = ms[p].parent
    for i, m in enumerate(ms):  # parents precede children, so one pass reaches whole Null chains
        if i not in chosen and m.obj.subclass in HELPER_CLASSES and m.parent in chosen:
            chosen.add(i)
    return sorted(chosen)


def unique_names(ms: list[Model], joints: list[int]) -> list[str]:
    """Joint names, with ``#k`` appended to repeats."""
    seen: set[str] = set()
    out = []
    for n in joints:
        base = name = ms[n].obj.name or f"model{ms[n].obj.id}"
        k = 1
        while name in seen:
            k += 1
            name = f"{base}#{k}"
        seen.add(name)
        out.append(name)
    return out
