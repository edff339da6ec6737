"""Parsing SmartBody ``.sk`` skeletons with SmartBody's own rules.

Grammar (``#`` comments)::

    set_name NAME            set_scale S           end
    skeleton root NAME { offset x y z
                         prerot axis x y z ang DEG     (also framerot; postrot likewise)
                         euler XYZ|YXZ|ZY
                         channel XPos|YPos|ZPos VALUE (free | [lim] LO HI)
                         channel XRot|YRot|ZRot DEG (free | [lim] LO HI)
                         channel Quat [axis x y z ang DEG] [frozen]
                         channels N NAME...        (BVH style: Euler YXZ, no limits)
                         align pre|post|prepost|preinv|postinv x y z
                         visgeo "file"  colgeo "file"  modelmat 16 numbers  modelrot axis .. ang ..
                         joint NAME { ... }  end NAME { ... } }

Semantics (as SmartBody's SkJoint computes them): the local rotation is
``prerot * value * postrot``, where ``value`` is the Quat channel (identity at rest) or the Euler
channels; the local translation is ``offset + (XPos, YPos, ZPos)``, in the parent's frame.
A position or Euler dof without a channel is frozen at 0; with ``lim`` its values are clamped.
Declaring a different rotation kind (``channel XRot`` after ``prerot``) starts a new rotation
object in SmartBody, dropping earlier pre/post rotations; that is reproduced here.
Angles in the file are degrees; lengths are in the file's unit.
"""
from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from infuse import quaternions as quat
from infuse.errors import InputError, UnusableInputError

from .tokens import TokenStream, tokenize

EULER_TYPES = ("XYZ", "YXZ", "ZY")
POS_CHANNELS = {"XPos": 0, "YPos": 1, "ZPos": 2, "XPosition": 0, "YPosition": 1, "ZPosition": 2}
ROT_CHANNELS = {"XRot": 0, "YRot": 1, "ZRot": 2, "XRotation": 0, "YRotation": 1, "ZRotation": 2}
_AXES = np.eye(3)
_UNITS_COMMENT = re.compile(r"#.*?\bUnits:\s*([A-Za-z]+)")
_UNIT_NAMES = {
    "m": "m", "meter": "m", "meters": "m", "metre": "m", "metres": "m",
    "cm": "cm", "centimeter": "cm", "centimeters": "cm", "centimetre": "cm", "centimetres": "cm",
    "mm": "mm", "millimeter": "mm", "millimeters": "mm", "dm": "dm",
    "in": "inch", "inch": "inch", "inches": "inch", "ft": "ft", "feet": "ft", "foot": "ft",
}


def declared_units(text: str, file: Path | str) -> tuple[str | None, int | None]:
    """The unit a ``# ... Units: cm`` header comment declares, and its line (``None`` if absent)."""
    m = _UNITS_COMMENT.search(text)
    if not m:
        return None, None
    line = text.count("\n", 0, m.start()) + 1
    unit = _UNIT_NAMES.get(m.group(1).lower())
    if unit is None:
        raise InputError(file, f"line {line}", f"unknown unit {m.group(1)!r} in the header comment")
    return unit, line


def euler_quaternions(euler_type: str, angles: np.ndarray) -> np.ndarray:
    """SmartBody's SkJointEuler rotation (...,4) from (...,3) angles in radians about X, Y, Z.

    ``YXZ`` is ``Qz * Qx * Qy``, ``XYZ`` is ``Qz * Qy * Qx`` and ``ZY`` is ``Qy * Qz`` (Hamilton
    products, the right factor applied first), as in SkJointEuler::get_quat.
    """
    angles = np.asarray(angles, dtype=np.float64)
    qx, qy, qz = (quat.from_axis_angle(_AXES[i], angles[..., i]) for i in range(3))
    if euler_type == "YXZ":
        return quat.multiply(qz, quat.multiply(qx, qy))
    if euler_type == "XYZ":
        return quat.multiply(qz, quat.multiply(qy, qx))
    return quat.multiply(qy, qz)


@dataclass
class SkJoint:
    """One joint as SmartBody holds it after loading (lengths in file units, angles in radians)."""

    name: str
    parent: int
    line: int
    offset: np.ndarray = field(default_factory=lambda: np.zeros(3))
    prerot: np.ndarray = field(default_factory=lambda: quat.IDENTITY.copy())
    postrot: np.ndarray = field(default_factory=lambda: quat.IDENTITY.copy())
    rot_type: str = "quat"  # "quat" or "euler"
    rot_active: bool = False
    euler_type: str = "YXZ"
    euler_values: np.ndarray = field(default_factory=lambda: np.zeros(3))
    euler_limited: np.ndarray = field(default_factory=lambda: np.ones(3, dtype=bool))
    euler_limits: np.ndarray = field(default_factory=lambda: np.zeros((3, 2)))
    pos_values: np.ndarray = field(default_factory=lambda: np.zeros(3))
    pos_limited: np.ndarray = field(default_factory=lambda: np.ones(3, dtype=bool))
    pos_limits: np.ndarray = field(default_factory=lambda: np.zeros((3, 2)))
    channels: dict = field(default_factory=dict)  # channel name -> as written (for meta)
    children: list = field(default_factory=list)

    def set_rot_type(self, kind: str) -> None:
        """Switch between Quat and Euler rotation, resetting the rotation as SkJoint::rot_type does."""
        if kind == self.rot_type:
            return
        self.rot_type = kind
        self.prerot = quat.IDENTITY.copy()
        self.postrot = quat.IDENTITY.copy()
        self.rot_active = False
        self.euler_type = "YXZ"
        self.euler_values = np.zeros(3)
        self.euler_limited = np.ones(3, dtype=bool)
        self.euler_limits = np.zeros((3, 2))

    def set_euler_type(self, euler_type: str) -> None:
        self.euler_type = euler_type
        if euler_type == "ZY":  # SkJointEuler::type freezes X
            self.euler_values[0] = 0.0
            self.euler_limited[0] = True
            self.euler_limits[0] = 0.0

    def rest_rotation(self) -> np.ndarray:
        """``prerot * value * postrot`` with the channels at their initial values."""
        value = euler_quaternions(self.euler_type, self.euler_values) if self.rot_type == "euler" else quat.IDENTITY
        return quat.normalize(quat.multiply(self.prerot, quat.multiply(value, self.postrot)))


@dataclass
class SkFile:
    """A parsed ``.sk``: joints in file order (parents first), lengths in file units."""

    path: Path
    name: str | None
    joints: list[SkJoint]
    units: str | None
    units_line: int | None
    scale: float
    collision_free_pairs: list[str]

    @property
    def names(self) -> list[str]:
        return [j.name for j in self.joints]

    @property
    def parents(self) -> np.ndarray:
        return np.array([j.parent for j in self.joints], dtype=np.int64)

    def rest_translations(self) -> np.ndarray:
        """(J,3) ``offset + position`` at rest, file units."""
        return np.array([j.offset + j.pos_values for j in self.joints])

    def rest_rotations(self) -> np.ndarray:
        return np.array([j.rest_rotation() for j in self.joints])


def _read_axis_angle(ts: TokenStream) -> np.ndarray:
    """``axis x y z ang DEG`` as SrQuat reads it: the axis is normalized, a zero axis gives no rotation."""
    ts.expect("axis")
    axis = np.array(ts.numbers(3, "an axis component"))
    ts.expect("ang")
    angle = np.deg2rad(ts.number("an angle in degrees"))
    norm = np.linalg.norm(axis)
    if norm == 0.0:
        return quat.IDENTITY.copy()
    return quat.from_axis_angle(axis / norm, angle)


def _read_limits(ts: TokenStream, what: str) -> tuple[float, bool, float, float]:
    """``VALUE free`` or ``VALUE [lim] LO HI``: (value, limited, lo, hi)."""
    value = ts.number(f"the initial value of {what}")
    tok = ts.peek()
    if tok is not None and tok.text == "free":
        ts.pos += 1
        return value, False, 0.0, 0.0
    if tok is not None and tok.text == "lim":
        ts.pos += 1
    lo = ts.number(f"the lower limit of {what} (or 'free')")
    hi = ts.number(f"the upper limit of {what}")
    if lo > hi:
        raise ts.error(f"{what}: lower limit {lo} is above upper limit {hi}")
    return value, True, lo, hi


def _read_channel(ts: TokenStream, joint: SkJoint) -> None:
    tok = ts.next("a channel type")
    kind = tok.text
    if kind == "Quat":
        joint.set_rot_type("quat")
        joint.rot_active = True
        written = "Quat"
        nxt = ts.peek()
        if nxt is not None and nxt.text == "axis":
            _read_axis_angle(ts)  # SmartBody reads and ignores this rotation
            written += " axis"
            nxt = ts.peek()
        if nxt is not None and nxt.text == "frozen":
            ts.pos += 1
            joint.rot_active = False
            written += " frozen"
        joint.channels["Quat"] = written
        return
    if kind in ("Swing", "Twist"):
        raise UnusableInputError(ts.file, f"line {tok.line}: {kind} channels (swing-twist joints) are not supported")
    if kind in POS_CHANNELS:
        d = POS_CHANNELS[kind]
        value, limited, lo, hi = _read_limits(ts, f"channel {kind} of {joint.name!r}")
        joint.pos_limited[d] = limited
        joint.pos_limits[d] = (lo, hi)
        joint.pos_values[d] = np.clip(value, lo, hi) if limited else value
        joint.channels["XYZ"[d] + "Pos"] = {"value": value, "limits": [lo, hi] if limited else None}
        return
    if kind in ROT_CHANNELS:
        d = ROT_CHANNELS[kind]
        joint.set_rot_type("euler")
        joint.rot_active = True
        value, limited, lo, hi = _read_limits(ts, f"channel {kind} of {joint.name!r}")
        joint.euler_limited[d] = limited
        joint.euler_limits[d] = np.deg2rad((lo, hi))
        v = np.deg2rad(value)
        joint.euler_values[d] = np.clip(v, *joint.euler_limits[d]) if limited else v
        joint.channels["XYZ"[d] + "Rot"] = {"value_deg": value, "limits_deg": [lo, hi] if limited else None}
        return
    raise ts.error(f"unknown channel type {kind!r} (expected XPos, YPos, ZPos, XRot, YRot, ZRot or Quat)", tok.line)


def _read_bvh_channels(ts: TokenStream, joint: SkJoint) -> None:
    """``channels N A B C``: SmartBody makes the joint Euler YXZ with unlimited channels."""
    count = ts.integer("the channel count")
    joint.set_rot_type("euler")
    joint.euler_type = "YXZ"
    for _ in range(count):
        tok = ts.next("a channel name")
        if tok.text in POS_CHANNELS:
            joint.pos_limited[POS_CHANNELS[tok.text]] = False
            joint.channels["XYZ"[POS_CHANNELS[tok.text]] + "Pos"] = {"value": 0.0, "limits": None}
        elif tok.text in ROT_CHANNELS:
            joint.euler_limited[ROT_CHANNELS[tok.text]] = False
            joint.rot_active = True
            joint.channels["XYZ"[ROT_CHANNELS[tok.text]] + "Rot"] = {"value_deg": 0.0, "limits_deg": None}
        elif tok.text == "Quat":
            joint.rot_active = True
            joint.channels["Quat"] = "Quat"
        else:
            raise ts.error(f"unknown channel {tok.text!r} in 'channels'", tok.line)


def _align(joint: SkJoint, joints: list[SkJoint], how: str, v: np.ndarray) -> None:
    """SkJointQuat::align: turn pre/post rotations so ``v`` lines up with the joint or first child offset."""
    if not joint.children:
        return
    child_offset = joints[joint.children[0]].offset
    pre, post = joint.prerot, joint.postrot
    if how == "postinv":
        q = quat.between(v, quat.rotate(post, child_offset))
        pre, post = quat.multiply(q, pre), quat.multiply(quat.conjugate(q), post)
    elif how == "preinv":
        q = quat.between(quat.rotate(pre, v), joint.offset)
        pre, post = quat.multiply(q, pre), quat.multiply(quat.conjugate(q), post)
    if how in ("pre", "prepost"):
        pre = quat.multiply(quat.between(quat.rotate(pre, v), joint.offset), pre)
    if how in ("post", "prepost"):
        post = quat.multiply(quat.conjugate(quat.between(v, quat.rotate(post, child_offset))), post)
    joint.prerot, joint.postrot = pre, post


def _read_joint(ts: TokenStream, parent: int, joints: list[SkJoint], names: dict[str, int]) -> None:
    """Read ``NAME { ... }`` (the ``root``/``joint`` keyword is already consumed) and its children."""
    words: list[str] = []
    start = ts.line
    while True:
        tok = ts.next("'{' after a joint name")
        if tok.text == "{" and not tok.quoted:
            break
        if tok.text == "}" and not tok.quoted:
            raise ts.error("'}' where a joint name and '{' were expected", tok.line)
        if tok.text == "joint":  # SmartBody restarts the name at a new 'joint' keyword
            words = []
            continue
        words.append(tok.text)
    name = " ".join(words)
    if not name:
        raise ts.error("joint without a name", start)
    if name in names:
        raise ts.error(f"duplicate joint name {name!r} (first on line {joints[names[name]].line})", start)
    joint = SkJoint(name, parent, start)
    index = len(joints)
    joints.append(joint)
    names[name] = index
    if parent >= 0:
        joints[parent].children.append(index)
    while True:
        tok = ts.next(f"'}}' closing joint {name!r} (opened on line {start})")
        kw = tok.text
        if kw == "}":
            return
        if kw in ("offset", "center"):
            joint.offset = np.array(ts.numbers(3, f"the offset of {name!r}"))
        elif kw == "channel":
            _read_channel(ts, joint)
        elif kw == "channels":
            _read_bvh_channels(ts, joint)
        elif kw == "euler":
            joint.set_rot_type("euler")
            t = ts.next("an Euler type")
            if t.text not in EULER_TYPES:
                raise ts.error(f"unknown Euler type {t.text!r} (expected {', '.join(EULER_TYPES)})", t.line)
            joint.set_euler_type(t.text)
        elif kw in ("prerot", "framerot"):
            joint.prerot = quat.multiply(joint.prerot, _read_axis_angle(ts))
        elif kw == "postrot":
            joint.postrot = quat.multiply(joint.postrot, _read_axis_angle(ts))
        elif kw == "align":
            how = ts.word("an align type")
            v = np.array(ts.numbers(3, "the align direction"))
            _align(joint, joints, how if how in ("pre", "post", "prepost", "preinv") else "postinv", v)
        elif kw in ("visgeo", "colgeo"):
            geo = ts.next(f"the {kw} file name")
            if not geo.quoted:
                raise ts.error(f"{kw} expects a quoted file name, found {geo.text!r}", geo.line)
        elif kw == "modelmat":
            ts.numbers(16, "a modelmat entry")  # geometry placement only
        elif kw == "modelrot":
            _read_axis_angle(ts)  # geometry placement only
        elif kw in ("joint", "end"):
            _read_joint(ts, index, joints, names)
        else:
            raise ts.error(f"unexpected {kw!r} in joint {name!r}", tok.line)


def parse_sk(path: Path, text: str) -> SkFile:
    """Parse ``.sk`` text into an :class:`SkFile`; malformed input raises :class:`InputError`."""
    ts = TokenStream(tokenize(text, path), path)
    joints: list[SkJoint] = []
    names: dict[str, int] = {}
    name: str | None = None
    scale: float | None = None
    pairs: list[str] = []
    while not ts.finished:
        tok = ts.next("a keyword")
        kw = tok.text
        if kw in ("set_name", "name"):
            name = ts.word("the skeleton name")
        elif kw == "set_scale":
            scale = ts.number("the scale")
        elif kw in ("add_path", "path"):
            ts.next("a path")
        elif kw in ("skeleton", "HIERARCHY"):
            if joints:
                raise ts.error("a second skeleton in one file", tok.line)
            ts.expect("root")
            _read_joint(ts, -1, joints, names)
        elif kw == "set_collision_free_pairs":
            while ts.upcoming() not in (None, "skeleton", "end", "set_name", "set_scale"):
                pairs.append(ts.word("a joint name"))
        elif kw == "end":
            break
        elif kw in ("joint_data", "add_posture", "joint_list", "joint", "root"):
            raise UnusableInputError(path, f"line {tok.line}: {kw!r} sections (merge files, postures, joint lists) are not supported")
        else:
            raise ts.error(f"unexpected {kw!r} (expected set_name, skeleton, end...)", tok.line)
    if not joints:
        raise InputError(path, None, "no skeleton (expected 'skeleton root NAME { ... }')")
    if scale is not None:
        for j in joints:
            free = ~(j.pos_limited & (j.pos_limits[:, 0] == j.pos_limits[:, 1]))
            j.pos_values = np.where(free, j.pos_values * scale, j.pos_values)
            j.pos_limits = np.where(free[:, None], j.pos_limits * scale, j.pos_limits)
    for j in joints:
        j.offset = j.offset * (1.0 if scale is None else scale)
    units, units_line = declared_units(text, path)
    return SkFile(path, name, joints, units, units_line, 1.0 if scale is None else scale, pairs)
