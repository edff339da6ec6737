"""A tiny glTF document builder for tests, written from the glTF 2.0 spec and independent of the plugin.

``mini_rig()`` builds a Blender-style character: an ``Armature`` node (-90° about X, scale 0.01, like
a Z-up rig in centimetres) above five joints, a mesh node with two morph targets under the head, a
skin, and one animation ``wave`` touching the Armature, the hips, the spine, an arm and the morph
weights.
"""
from __future__ import annotations

import base64
import json
import struct
from pathlib import Path

import numpy as np

from infuse import quaternions as quat

TYPES = {1: "SCALAR", 2: "VEC2", 3: "VEC3", 4: "VEC4", 16: "MAT4"}
DTYPES = {5120: "<i1", 5121: "<u1", 5122: "<i2", 5123: "<u2", 5125: "<u4", 5126: "<f4"}
MAX_INT = {5120: 127, 5121: 255, 5122: 32767, 5123: 65535}
ARMATURE_ROTATION = quat.from_axis_angle(np.array([1.0, 0.0, 0.0]), -np.pi / 2)


class GltfBuilder:
    def __init__(self):
        # "buffers" holds the buffers after the first (buffer 0, the GLB BIN chunk, is added on output).
        self.doc: dict = {"asset": {"version": "2.0", "generator": "test builder"}, "nodes": [], "buffers": [],
                          "bufferViews": [], "accessors": []}
        self.bin = bytearray()

    def view(self, raw: bytes, stride: int | None = None) -> int:
        self.bin += b"\0" * ((-len(self.bin)) % 4)
        view = {"buffer": 0, "byteOffset": len(self.bin), "byteLength": len(raw)}
        if stride:
            view["byteStride"] = stride
        self.bin += raw
        self.doc["bufferViews"].append(view)
        return len(self.doc["bufferViews"]) - 1

    def accessor(self, data, component: int = 5126, normalized: bool = False, minmax: bool = False, kind: str | None = None) -> int:
        data = np.asarray(data, dtype=np.float64)
        data = data.reshape(len(data), -1)
        if normalized:
            stored = np.round(data * MAX_INT[component]).astype(DTYPES[component])
        else:
            stored = data.astype(DTYPES[component])
        acc = {"bufferView": self.view(stored.tobytes()), "componentType": component, "count": len(data),
               "type": kind or TYPES[data.shape[1]]}
        if normalized:
            acc["normalized"] = True
        if minmax:
            acc["min"] = [float(v) for v in stored.min(axis=0)]
            acc["max"] = [float(v) for v in stored.max(axis=0)]
        self.doc["accessors"].append(acc)
        return len(self.doc["accessors"]) - 1

    def node(self, name: str, parent: int | None = None, **fields) -> int:
        node = {"name": name}
        for key, value in fields.items():
            node[key] = [float(v) for v in value] if key in ("translation", "rotation", "scale", "matrix", "weights") else value
        self.doc["nodes"].append(node)
        index = len(self.doc["nodes"]) - 1
        if parent is not None:
            self.doc["nodes"][parent].setdefault("children", []).append(index)
        return index

    def animation(self, name: str, channels: list) -> int:
        """``channels``: (node, path, times, values, interpolation[, component, normalized])."""
        anim = {"name": name, "channels": [], "samplers": []}
        for node, path, times, values, interp, *quant in channels:
            t_acc = self.accessor(np.asarray(times)[:, None], minmax=True)
            comp, norm = (quant + [5126, False])[:2] if quant else (5126, False)
            v_acc = self.accessor(values, component=comp, normalized=norm)
            anim["samplers"].append({"input": t_acc, "output": v_acc, "interpolation": interp})
            anim["channels"].append({"sampler": len(anim["samplers"]) - 1, "target": {"node": node, "path": path}})
        self.doc.setdefault("animations", []).append(anim)
        return len(self.doc["animations"]) - 1

    def _json(self, buffer: dict) -> dict:
        doc = json.loads(json.dumps(self.doc))
        doc["buffers"] = [dict(buffer, byteLength=len(self.bin))] + self.doc["buffers"]
        for key in ("bufferViews", "accessors"):
            if not doc[key]:
                del doc[key]
        return doc

    def glb(self) -> bytes:
        text = json.dumps(self._json({})).encode()
        text += b" " * ((-len(text)) % 4)
        body = bytes(self.bin) + b"\0" * ((-len(self.bin)) % 4)
        chunks = struct.pack("<II", len(text), 0x4E4F534A) + text + struct.pack("<II", len(body), 0x004E4942) + body
        return b"glTF" + struct.pack("<II", 2, 12 + len(chunks)) + chunks

    def write_glb(self, path: Path) -> Path:
        path.write_bytes(self.glb())
        return path

    def write_gltf(self, path: Path, external: bool = True) -> Path:
        if external:
            bin_name = path.with_suffix(".bin").name
            (path.parent / bin_name).write_bytes(bytes(self.bin))
            doc = self._json({"uri": bin_name})
        else:
            doc = self._json({"uri": "data:application/octet-stream;base64," + base64.b64encode(bytes(self.bin)).decode()})
        path.write_text(json.dumps(doc, indent=1))
        return path


def mini_rig(animated: bool = True) -> tuple[GltfBuilder, dict]:
    """The builder and a dict name -> node index (see the module doc)."""
    b = GltfBuilder()
    n = {}
    n["Armature"] = b.node("Armature", rotation=ARMATURE_ROTATION, scale=[0.01] * 3)
    n["hips"] = b.node("hips", n["Armature"], translation=[0, 0, 100])
    n["spine"] = b.node("spine", n["hips"], translation=[0, 0, 20])
    n["head"] = b.node("head", n["spine"], translation=[0, 0, 30])
    n["arm.L"] = b.node("arm.L", n["spine"], translation=[15, 0, 25])
    n["arm.R"] = b.node("arm.R", n["spine"], translation=[-15, 0, 25])
    # A morph-targeted triangle on the head (not skinned): mesh data valid per spec.
    pos = b.accessor(np.array([[0, 0, 0], [0.1, 0, 0], [0, 0.1, 0]]), minmax=True)
    t1 = b.accessor(np.array([[0, 0, 0.01], [0, 0, 0], [0, 0, 0]]), minmax=True)
    t2 = b.accessor(np.array([[0, 0, 0], [0, 0, 0.01], [0, 0, 0]]), minmax=True)
    b.doc["meshes"] = [{"name": "face", "primitives": [{"attributes": {"POSITION": pos}, "targets": [{"POSITION": t1}, {"POSITION": t2}]}],
                        "weights": [0.0, 0.0], "extras": {"targetNames": ["smile", "blink"]}}]
    n["face"] = b.node("face", n["head"], mesh=0)
    joints = [n[k] for k in ("hips", "spine", "head", "arm.L", "arm.R")]
    world = world_matrices(b.doc)
    ibm = np.linalg.inv(world[joints])
    b.doc["skins"] = [{"joints": joints, "inverseBindMatrices": b.accessor(np.swapaxes(ibm, 1, 2).reshape(-1, 16), kind="MAT4")}]
    b.doc["scenes"] = [{"nodes": [n["Armature"]]}]
    b.doc["scene"] = 0
    if animated:
        turn = quat.multiply(quat.from_axis_angle(np.array([0.0, 1.0, 0.0]), np.pi / 2), ARMATURE_ROTATION)
        bend = quat.from_axis_angle(np.array([1.0, 0.0, 0.0]), 0.6)
        b.animation("wave", [
            (n["Armature"], "rotation", [0.0, 1.0], np.stack([ARMATURE_ROTATION, turn]), "LINEAR"),
            (n["hips"], "translation", [0.0, 0.5, 1.0], [[0, 0, 100], [0, 10, 90], [0, 20, 100]], "LINEAR"),
            (n["spine"], "rotation", [0.0, 1.0], np.stack([quat.IDENTITY, bend]), "LINEAR"),
            (n["arm.L"], "rotation", [0.0, 0.5], np.stack([quat.IDENTITY, bend]), "STEP"),
            (n["face"], "weights", [0.0, 1.0], [[0.0], [0.0], [1.0], [0.5]], "LINEAR"),
        ])
    return b, n


def node_local_matrix(node: dict) -> np.ndarray:
    if "matrix" in node:
        return np.array(node["matrix"], dtype=np.float64).reshape(4, 4).T
    m = np.eye(4)
    q = np.array(node.get("rotation", [0, 0, 0, 1]), dtype=np.float64)
    m[:3, :3] = quat.to_matrix(q / np.linalg.norm(q)) * np.array(node.get("scale", [1, 1, 1]), dtype=np.float64)
    m[:3, 3] = node.get("translation", [0, 0, 0])
    return m


def world_matrices(doc: dict) -> np.ndarray:
    """(N,4,4) world matrices by walking parent links."""
    nodes = doc["nodes"]
    parent = {c: i for i, n in enumerate(nodes) for c in n.get("children", [])}

    def world(i):
        return world(parent[i]) @ node_local_matrix(nodes[i]) if i in parent else node_local_matrix(nodes[i])

    return np.array([world(i) for i in range(len(nodes))])


# -- an EXT_meshopt_compression encoder (vertex codec version 0, ATTRIBUTES mode), from the spec ------
def _zigzag(delta: np.ndarray) -> np.ndarray:
    d = delta.astype(np.int8).astype(np.int16)
    return (((d << 1) ^ (d >> 7)) & 0xFF).astype(np.uint8)


def _encode_lane(values: np.ndarray) -> bytes:
    """One byte lane of a block: 2-bit group modes, then each group with the cheapest packing."""
    padded = np.zeros(-(-len(values) // 16) * 16, dtype=np.uint8)
    padded[:len(values)] = values
    groups = padded.reshape(-1, 16)
    header = bytearray((len(groups) + 3) // 4)
    body = bytearray()
    for g, group in enumerate(groups):
        costs = {1: 4 + int(np.sum(group >= 3)), 2: 8 + int(np.sum(group >= 15)), 3: 16}
        mode = 0 if not group.any() else min(costs, key=costs.get)
        header[g // 4] |= mode << ((g % 4) * 2)
        if mode == 3:
            body += group.tobytes()
        elif mode in (1, 2):
            width, sentinel = (2, 3) if mode == 1 else (4, 15)
            codes = np.minimum(group, sentinel)
            packed = bytearray(16 * width // 8)
            for i, c in enumerate(codes):
                packed[i * width // 8] |= int(c) << (8 - width - (i * width) % 8)
            body += packed + bytes(int(v) for v in group if v >= sentinel)
    return bytes(header) + bytes(body)


def meshopt_encode(elements: np.ndarray) -> bytes:
    """Encode (count, stride) uint8 elements as a meshopt vertex stream."""
    count, stride = elements.shape
    block = min((8192 // stride) & ~15, 256)
    out = bytearray([0xA0])
    last = elements[0].copy()
    for first in range(0, count, block):
        chunk = elements[first:first + block]
        previous = np.vstack((last[None], chunk[:-1]))
        for k in range(stride):
            out += _encode_lane(_zigzag(chunk[:, k].astype(np.int16) - previous[:, k]))
        last = chunk[-1].copy()
    tail = max(stride, 32)
    out += bytes(tail - stride) + elements[0].tobytes()
    return bytes(out)


def exponential_filter(values: np.ndarray, exponent: int = -15) -> np.ndarray:
    """float32 values -> meshopt EXPONENTIAL words (24-bit mantissa, 8-bit exponent) as bytes (n, 4*c)."""
    mantissa = np.round(np.asarray(values, dtype=np.float64) * 2.0 ** -exponent).astype(np.int64)
    words = ((exponent & 0xFF) << 24) | (mantissa & 0xFFFFFF)
    return words.astype("<u4").view(np.uint8).reshape(len(values), -1)


def quaternion_filter(quats: np.ndarray, bits: int = 12) -> np.ndarray:
    """Unit quaternions -> meshopt QUATERNION int16 x4 (largest component dropped) as bytes (n, 8)."""
    q = np.asarray(quats, dtype=np.float64)
    largest = np.argmax(np.abs(q), axis=1)
    q = np.where(q[np.arange(len(q)), largest][:, None] < 0, -q, q)
    scale = (1 << bits) - 1
    out = np.zeros((len(q), 4), dtype=np.int64)
    for k in range(3):
        out[:, k] = np.round(q[np.arange(len(q)), (largest + k + 1) & 3] * np.sqrt(2.0) * scale)
    out[:, 3] = (scale & ~3) | largest
    return out.astype("<i2").view(np.uint8).reshape(len(q), 8)
