"""An independent reference for BVH tests: a minimal token parser and a 4x4 matrix chain.

Deliberately shares nothing with the plugin: no quaternions, no vectorization. Each joint's
local matrix is built by applying its channels in file order (translations set the offset's
components, each rotation channel multiplies on the right), and global matrices are chained
parent by parent. Positions come out in file units and file axes.
"""
from __future__ import annotations

import math

import numpy as np


def rotation_matrix(axis: str, degrees: float) -> np.ndarray:
    c, s = math.cos(math.radians(degrees)), math.sin(math.radians(degrees))
    if axis == "X":
        return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])
    if axis == "Y":
        return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def parse_raw(text: str) -> dict:
    """Joints (name, parent, offset, channels), end sites and the (F, C) value table of a BVH text."""
    tokens = text.split()
    i = 0
    joints: list[dict] = []
    sites: list[dict] = []
    stack: list[dict] = []
    pending: dict | None = None  # the ROOT, JOINT or End Site whose "{" comes next
    while tokens[i] != "MOTION":
        t = tokens[i]
        if t in ("ROOT", "JOINT"):
            pending = {"name": tokens[i + 1], "parent": stack[-1]["index"] if t == "JOINT" else -1,
                       "index": len(joints), "channels": []}
            joints.append(pending)
            i += 2
        elif t == "End":
            pending = {"parent": stack[-1]["index"]}
            sites.append(pending)
            i += 2
        elif t == "{":
            stack.append(pending)
            i += 1
        elif t == "}":
            stack.pop()
            i += 1
        elif t == "OFFSET":
            stack[-1]["offset"] = np.array([float(v) for v in tokens[i + 1:i + 4]])
            i += 4
        elif t == "CHANNELS":
            n = int(tokens[i + 1])
            stack[-1]["channels"] = tokens[i + 2:i + 2 + n]
            i += 2 + n
        else:  # HIERARCHY
            i += 1
    frames = int(tokens[i + 2])
    frame_time = float(tokens[i + 5])
    width = sum(len(j["channels"]) for j in joints)
    values = np.array([float(v) for v in tokens[i + 6:]]).reshape(frames, width)
    return {"joints": joints, "sites": sites, "frame_time": frame_time, "values": values}


def matrix_chain_positions(raw: dict, frames=None) -> np.ndarray:
    """(F, J, 3) global joint positions in file units, frame by frame and joint by joint."""
    joints = raw["joints"]
    values = raw["values"] if frames is None else raw["values"][frames]
    out = np.zeros((len(values), len(joints), 3))
    for f, row in enumerate(values):
        world: list[np.ndarray] = []
        col = 0
        for j in joints:
            translation = np.array(j["offset"], dtype=float)
            rotation = np.eye(3)
            for name in j["channels"]:
                v = row[col]
                col += 1
                if name.endswith("position"):
                    translation["XYZ".index(name[0])] = v
                else:
                    rotation = rotation @ rotation_matrix(name[0], v)
            local = np.eye(4)
            local[:3, :3] = rotation
            local[:3, 3] = translation
            world.append(local if j["parent"] < 0 else world[j["parent"]] @ local)
            out[f, j["index"]] = world[-1][:3, 3]
    return out
