"""A COLLADA ``<skin>``: bind shape matrix, joints, inverse bind matrices and vertex weights.

COLLADA skins a position ``v`` of the bind shape as ``Σ w_i · W_i · IBM_i · BSM · v``, with ``W_i``
the world matrix of joint ``i``, ``IBM_i`` its inverse bind matrix and ``BSM`` the bind shape
matrix (matrices row-major in the file, acting on column vectors). Each position keeps its
:data:`MAX_INFLUENCES` largest weights, scaled to sum to 1. A joint index of -1 (the bind shape
itself, which no core bone carries) is dropped; a position left without weight follows the skin's
first joint.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .document import Document

#: Influences kept per vertex (the largest weights).
MAX_INFLUENCES = 4


@dataclass
class Skin:
    """``element``: the ``<skin>``; ``source``: the element it skins (a ``<geometry>``, or a
    ``<controller>`` holding a ``<morph>``), ``None`` when the file lacks it; ``bind_shape`` (4, 4);
    ``joint_names`` (B,) sids or ids; ``inverse_bind`` (B, 4, 4), file units; ``joints`` (P, K)
    indices into the joints and ``weights`` (P, K), rows summing to 1, for each position."""

    element: object
    source: object
    bind_shape: np.ndarray
    joint_names: list[str]
    inverse_bind: np.ndarray
    joints: np.ndarray
    weights: np.ndarray


def read_skin(doc: Document, skin) -> Skin:
    """The ``<skin>`` element ``skin``; raises :class:`~infuse.errors.InputError` when it is malformed."""
    source = doc.ids.get((skin.get("source") or "").removeprefix("#"))
    bsm = skin.find("bind_shape_matrix")
    bind_shape = np.eye(4) if bsm is None else doc.floats(bsm, 16).reshape(4, 4)
    joints = skin.find("joints")
    inputs = {} if joints is None else {i.get("semantic"): i for i in joints.findall("input")}
    if "JOINT" not in inputs:
        raise doc.error(skin, "skin has no <joints> JOINT input")
    names = [str(n) for n in doc.source(inputs["JOINT"].get("source"), inputs["JOINT"], numeric=False).ravel()]
    if "INV_BIND_MATRIX" in inputs:
        ibm = doc.source(inputs["INV_BIND_MATRIX"].get("source"), inputs["INV_BIND_MATRIX"])
        if ibm.shape != (len(names), 16):
            raise doc.error(inputs["INV_BIND_MATRIX"], f"{len(ibm)} inverse bind matrices of {ibm.shape[1]} values for {len(names)} joints")
        inverse_bind = ibm.reshape(-1, 4, 4)
    else:
        inverse_bind = np.broadcast_to(np.eye(4), (len(names), 4, 4)).copy()
    joint_index, weights = _vertex_weights(doc, skin, len(names))
    return Skin(skin, source, bind_shape, names, inverse_bind, joint_index, weights)


def _vertex_weights(doc: Document, skin, num_joints: int) -> tuple[np.ndarray, np.ndarray]:
    vw = skin.find("vertex_weights")
    if vw is None:
        raise doc.error(skin, "skin has no <vertex_weights>")
    inputs = {i.get("semantic"): i for i in vw.findall("input")}
    for needed in ("JOINT", "WEIGHT"):
        if needed not in inputs:
            raise doc.error(vw, f"<vertex_weights> has no {needed} input")
    offsets = {}
    for name, i in inputs.items():
        raw = i.get("offset", "0")
        if not raw.isdigit():
            raise doc.error(i, f"offset={raw!r} is not a non-negative integer")
        offsets[name] = int(raw)
    stride = max(offsets.values()) + 1
    weight_values = doc.source(inputs["WEIGHT"].get("source"), inputs["WEIGHT"])[:, 0]
    vcount_el, v_el = vw.find("vcount"), vw.find("v")
    counts = doc.ints(vcount_el) if vcount_el is not None else np.zeros(0, dtype=np.int64)
    pairs = doc.ints(v_el) if v_el is not None else np.zeros(0, dtype=np.int64)
    declared = vw.get("count")
    if declared is not None and declared.isdigit() and int(declared) != len(counts):
        raise doc.error(vw, f"count={declared} but <vcount> lists {len(counts)} vertices")
    if np.any(counts < 0):
        raise doc.error(vcount_el, "a vertex has a negative influence count")
    if pairs.size != int(counts.sum()) * stride:
        raise doc.error(v_el if v_el is not None else vw, f"<v> holds {pairs.size} indices, <vcount> needs {int(counts.sum()) * stride}")
    pairs = pairs.reshape(-1, stride)
    joint, weight_index = pairs[:, offsets["JOINT"]], pairs[:, offsets["WEIGHT"]]
    if joint.size and (joint.min() < -1 or joint.max() >= num_joints):
        raise doc.error(v_el, f"a joint index is out of range (the skin has {num_joints} joints)")
    if weight_index.size and (weight_index.min() < 0 or weight_index.max() >= len(weight_values)):
        raise doc.error(v_el, f"a weight index is out of range (there are {len(weight_values)} weights)")
    weight = np.where(joint >= 0, np.maximum(weight_values[weight_index], 0.0), 0.0)
    return strongest(counts, np.maximum(joint, 0), weight)


def strongest(counts: np.ndarray, joint: np.ndarray, weight: np.ndarray, keep: int = MAX_INFLUENCES) -> tuple[np.ndarray, np.ndarray]:
    """(P, K) joint indices and weights summing to 1 from ``counts[p]`` consecutive (joint, weight)
    influences per position: the ``keep`` largest, K = min(keep, most influences), at least 1."""
    num = len(counts)
    width = max(int(counts.max(initial=0)), 1)
    rows = np.repeat(np.arange(num), counts)
    cols = np.arange(len(joint)) - np.repeat(np.cumsum(counts) - counts, counts)
    dense_j = np.zeros((num, width), dtype=np.int64)
    dense_w = np.zeros((num, width))
    dense_j[rows, cols], dense_w[rows, cols] = joint, weight
    if width > keep:
        order = np.argsort(-dense_w, axis=1, kind="stable")[:, :keep]
        dense_j, dense_w = np.take_along_axis(dense_j, order, 1), np.take_along_axis(dense_w, order, 1)
    total = dense_w.sum(axis=1, keepdims=True)
    empty = total[:, 0] <= 0
    dense_w = dense_w / np.where(total > 0, total, 1.0)
    dense_j[empty], dense_w[empty] = 0, np.eye(1, dense_w.shape[1])
    dense_j = np.where(dense_w > 0, dense_j, 0)
    return dense_j, dense_w
