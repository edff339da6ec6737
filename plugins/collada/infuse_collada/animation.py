"""COLLADA animations: channels targeting node transform elements, sampled on a regular frame grid.

A channel target is ``node_id/sid`` (the whole element), ``node_id/sid.X`` (a member: X, Y, Z,
ANGLE) or ``node_id/sid(i)`` / ``node_id/sid(row)(col)`` (an entry of a vector or matrix).
Channels on anything else (visibility, materials, morph weights) are counted and skipped.
Rotation angles stay in degrees, as in the scene graph.
"""
from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np

from .curves import Curve, sample_all
from .document import Document
from .scene import MEMBERS, TRANSFORM_SIZES, SceneNode

_TARGET = re.compile(r"^(?P<node>[^/]+)/(?P<sid>[^./()]+)(?:\.(?P<member>\w+)|\((?P<i>\d+)\)(?:\((?P<j>\d+)\))?)?$")

#: Frame rates tried, in order, when deciding which grid the key times lie on.
_FRAME_RATES = (30.0, 24.0, 25.0, 60.0, 50.0, 48.0, 120.0)


@dataclass
class Channel:
    """One animated value: which node(s) and transform element, which entries, the curve, and the
    ids of the ``<animation>`` elements around it (what animation clips refer to)."""

    nodes: list[int]
    transform: int
    entries: slice | int
    curve: Curve
    animations: frozenset[str]


def channels(doc: Document, nodes: list[SceneNode]) -> tuple[list[Channel], int]:
    """Every channel that animates a node transform, and how many other channels were skipped."""
    by_id: dict[str, list[int]] = {}
    for i, node in enumerate(nodes):
        if node.id:
            by_id.setdefault(node.id, []).append(i)
    found: list[Channel] = []
    skipped = 0
    for animation in doc.root.iterfind("library_animations//animation"):
        for ch in animation.findall("channel"):
            match = _TARGET.match(ch.get("target") or "")
            targets = by_id.get(match["node"]) if match else None
            if match is None or not targets:
                skipped += 1
                continue
            node = nodes[targets[0]]
            t_index = next((k for k, tr in enumerate(node.transforms) if tr.sid == match["sid"]), None)
            if t_index is None:
                skipped += 1
                continue
            kind = node.transforms[t_index].kind
            entries = _entries(doc, ch, kind, match)
            if entries is None:
                skipped += 1
                continue
            curve = _curve(doc, doc.resolve(ch.get("source"), ch))
            width = curve.values.shape[1]
            expected = TRANSFORM_SIZES[kind] if isinstance(entries, slice) else 1
            if width != expected:
                raise doc.error(ch, f"channel {ch.get('target')!r} gives {width} values per key, expected {expected}")
            owners = frozenset(a.get("id") for a in ch.iterancestors("animation") if a.get("id"))
            found.append(Channel(targets, t_index, entries, curve, owners))
    return found, skipped


def _entries(doc: Document, ch, kind: str, match) -> slice | int | None:
    size = TRANSFORM_SIZES[kind]
    if match["member"]:
        index = MEMBERS.get(match["member"].upper())
    elif match["j"] is not None:
        index = int(match["i"]) * 4 + int(match["j"])
    elif match["i"] is not None:
        index = int(match["i"])
    else:
        return slice(None)
    if index is None or index >= size:
        raise doc.error(ch, f"target {ch.get('target')!r} addresses no value of a <{kind}>")
    return index


def _curve(doc: Document, sampler) -> Curve:
    inputs = {i.get("semantic"): i for i in sampler.findall("input")}
    for needed in ("INPUT", "OUTPUT"):
        if needed not in inputs:
            raise doc.error(sampler, f"sampler has no {needed} input")
    times = doc.source(inputs["INPUT"].get("source"), inputs["INPUT"])[:, 0]
    values = doc.source(inputs["OUTPUT"].get("source"), inputs["OUTPUT"])
    if len(times) == 0 or len(times) != len(values):
        raise doc.error(sampler, f"{len(times)} key times for {len(values)} key values")
    if np.any(np.diff(times) < 0):
        raise doc.error(sampler, "key times decrease")
    if "INTERPOLATION" in inputs:
        interp = doc.source(inputs["INTERPOLATION"].get("source"), inputs["INTERPOLATION"], numeric=False)[:, 0]
        if len(interp) != len(times):
            raise doc.error(sampler, f"{len(interp)} interpolation names for {len(times)} keys")
        interp = np.array([str(v).upper() for v in interp])
    else:
        interp = np.full(len(times), "LINEAR")
    tangents: list[np.ndarray | None] = []
    for semantic in ("IN_TANGENT", "OUT_TANGENT"):
        if semantic in inputs:
            tan = doc.source(inputs[semantic].get("source"), inputs[semantic])
            if len(tan) != len(times) or tan.shape[1] not in (values.shape[1], 2 * values.shape[1]):
                raise doc.error(sampler, f"{semantic} does not match the {len(times)} keys of width {values.shape[1]}")
            tangents.append(tan.reshape(len(times), -1))
        else:
            tangents.append(None)
    into, out = tangents
    if (into is None) != (out is None) or (into is not None and out is not None and into.shape != out.shape):
        into = out = None
    return Curve(times, values, interp, into, out)


def frame_rate(chs: list[Channel]) -> float:
    """The first common frame rate whose grid holds every key time (to 1 ms), else 30 fps."""
    times = np.concatenate([c.curve.times for c in chs])
    for fps in _FRAME_RATES:
        if np.all(np.abs(times * fps - np.round(times * fps)) < 1e-3 * fps):
            return fps
    return 30.0


def sample_transforms(nodes: list[SceneNode], chs: list[Channel], times: np.ndarray) -> dict[tuple[int, int], np.ndarray]:
    """Per-frame values (F, k) of every animated transform element, keyed by (node, transform) index."""
    out: dict[tuple[int, int], np.ndarray] = {}
    for ch, values in zip(chs, sample_all([ch.curve for ch in chs], times)):
        for n in ch.nodes:
            key = (n, ch.transform)
            if key not in out:
                out[key] = np.broadcast_to(nodes[n].transforms[ch.transform].values, (len(times), TRANSFORM_SIZES[nodes[n].transforms[ch.transform].kind])).copy()
            if isinstance(ch.entries, slice):
                out[key][:] = values
            else:
                out[key][:, ch.entries] = values[:, 0]
    return out
