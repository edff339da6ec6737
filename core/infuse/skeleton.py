"""The skeleton: joint names, parents in topological order, and the rest pose.

Conventions (see docs/conventions.md): metres, right-handed, +Y up, +Z forward (the character's
front), +X the character's left. Quaternions are (x, y, z, w). A joint's rest transform is the
local translation (offset from its parent, in the parent's frame) and local rotation that place it
when no motion is applied. Roots have parent -1 and their rest translation is in world space.
"""
from __future__ import annotations

import re
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from . import limits, quaternions as quat
from .errors import InputError


_CONTROL = re.compile(r"[\x00-\x1f\x7f]")


def _frozen(array, dtype, shape_tail: tuple[int, ...]) -> np.ndarray:
    out = np.array(array, dtype=dtype, copy=True)
    if out.size == 0:
        out = out.reshape((0,) + shape_tail)
    out.setflags(write=False)
    return out


@dataclass(frozen=True, eq=False)
class Skeleton:
    """An immutable joint hierarchy with its rest pose.

    - ``names``: J unique joint names.
    - ``parents``: (J,) int, index of each joint's parent, -1 for roots; always parent < child.
    - ``rest_translations``: (J, 3) metres, local offsets from the parent.
    - ``rest_rotations``: (J, 4) local rest rotations (x, y, z, w).
    - ``end_site_parents`` / ``end_site_offsets``: (E,) and (E, 3) leaf tips that are not joints
      (BVH ``End Site``), offsets in metres in the parent joint's frame.
    """

    names: tuple[str, ...]
    parents: np.ndarray
    rest_translations: np.ndarray
    rest_rotations: np.ndarray
    end_site_parents: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    end_site_offsets: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))

    def __post_init__(self):
        object.__setattr__(self, "names", tuple(str(n) for n in self.names))
        object.__setattr__(self, "parents", _frozen(self.parents, np.int64, ()))
        object.__setattr__(self, "rest_translations", _frozen(self.rest_translations, np.float64, (3,)))
        object.__setattr__(self, "rest_rotations", _frozen(self.rest_rotations, np.float64, (4,)))
        object.__setattr__(self, "end_site_parents", _frozen(self.end_site_parents, np.int64, ()))
        object.__setattr__(self, "end_site_offsets", _frozen(self.end_site_offsets, np.float64, (3,)))
        self.validate()

    def validate(self, file: str | None = None) -> None:
        """Raise :class:`InputError` unless the arrays are consistent, ordered and finite."""
        j = len(self.names)
        if j == 0:
            raise InputError(file, "skeleton", "no joints")
        limits.check(file, "skeleton", "joints", j, "MAX_JOINTS")
        bad_name = next((n for n in self.names if not n or _CONTROL.search(n)), None)
        if bad_name is not None:  # a writer could not put it in a text format (BVH, glTF JSON keeps it escaped)
            raise InputError(file, f"joint {bad_name[:40]!r}", "joint name is empty or holds control characters")
        if len(set(self.names)) != j:
            dup = sorted({n for n in self.names if self.names.count(n) > 1})
            raise InputError(file, "skeleton", f"duplicate joint names: {', '.join(dup[:5])}")
        if self.parents.shape != (j,):
            raise InputError(file, "skeleton", f"parents has shape {self.parents.shape}, expected ({j},)")
        if self.rest_translations.shape != (j, 3) or self.rest_rotations.shape != (j, 4):
            raise InputError(file, "skeleton", "rest arrays do not match the joint count")
        bad = np.nonzero((self.parents >= np.arange(j)) | (self.parents < -1))[0]
        if bad.size:
            raise InputError(file, f"joint {self.names[bad[0]]!r}", "parent does not precede the joint (cycle or bad order)")
        for label, arr in (("rest translation", self.rest_translations), ("rest rotation", self.rest_rotations),
                           ("end site offset", self.end_site_offsets)):
            if not np.all(np.isfinite(arr)):
                row = int(np.nonzero(~np.all(np.isfinite(arr), axis=-1))[0][0])
                where = f"joint {self.names[row]!r}" if arr is not self.end_site_offsets else f"end site {row}"
                raise InputError(file, where, f"{label} is not finite")
        for label, arr in (("rest translation", self.rest_translations), ("end site offset", self.end_site_offsets)):
            if arr.size and np.max(np.abs(arr)) > limits.MAX_COORDINATE_M:
                row = int(np.argmax(np.max(np.abs(arr), axis=-1)))
                where = f"joint {self.names[row]!r}" if arr is self.rest_translations else f"end site {row}"
                limits.check_coordinates(file, where, arr[row], label)
        depth = int(self.depths.max())
        if depth > limits.MAX_DEPTH:
            deepest = self.names[int(np.argmax(self.depths))]
            limits.check(file, f"joint {deepest!r}", "hierarchy depth", depth, "MAX_DEPTH")
        norms = np.linalg.norm(self.rest_rotations, axis=-1)
        if np.any(np.abs(norms - 1.0) > 1e-3):
            row = int(np.argmax(np.abs(norms - 1.0)))
            raise InputError(file, f"joint {self.names[row]!r}", "rest rotation is not a unit quaternion")
        if self.end_site_parents.size and (self.end_site_parents.min() < 0 or self.end_site_parents.max() >= j):
            raise InputError(file, "skeleton", "end site parent out of range")

    # -- structure -----------------------------------------------------------------------------
    @property
    def num_joints(self) -> int:
        return len(self.names)

    @cached_property
    def index(self) -> dict[str, int]:
        """Joint name -> index."""
        return {n: i for i, n in enumerate(self.names)}

    @cached_property
    def children(self) -> tuple[tuple[int, ...], ...]:
        """Child indices of every joint."""
        kids: list[list[int]] = [[] for _ in self.names]
        for i, p in enumerate(self.parents):
            if p >= 0:
                kids[p].append(i)
        return tuple(tuple(k) for k in kids)

    @cached_property
    def depths(self) -> np.ndarray:
        """(J,) number of ancestors of each joint (roots have depth 0)."""
        d = np.zeros(self.num_joints, dtype=np.int64)
        for i, p in enumerate(self.parents):
            if p >= 0:
                d[i] = d[p] + 1
        return d

    @cached_property
    def levels(self) -> tuple[np.ndarray, ...]:
        """Joint indices grouped by depth, shallowest first (used for vectorized FK)."""
        return tuple(np.nonzero(self.depths == k)[0] for k in range(int(self.depths.max()) + 1))

    @cached_property
    def roots(self) -> np.ndarray:
        return np.nonzero(self.parents < 0)[0]

    # -- rest pose -----------------------------------------------------------------------------
    @cached_property
    def rest_global_rotations(self) -> np.ndarray:
        """(J, 4) global rotations at rest."""
        return self._rest_fk[0]

    @cached_property
    def rest_global_positions(self) -> np.ndarray:
        """(J, 3) global joint positions at rest, metres."""
        return self._rest_fk[1]

    @cached_property
    def rest_end_site_positions(self) -> np.ndarray:
        """(E, 3) global positions of the end sites at rest, metres."""
        p = self.end_site_parents
        return self.rest_global_positions[p] + quat.rotate(self.rest_global_rotations[p], self.end_site_offsets)

    @cached_property
    def _rest_fk(self):
        from .kinematics import forward_kinematics

        g_rot, g_pos = forward_kinematics(self, self.rest_rotations[None], self.rest_translations[self.roots[0]][None])
        return g_rot[0], g_pos[0]

    def height(self) -> float:
        """Largest extent of the rest pose along any axis, metres (a scale for tolerances)."""
        pts = np.concatenate((self.rest_global_positions, self.rest_end_site_positions))
        return float(np.max(np.ptp(pts, axis=0))) if len(pts) > 1 else 0.0

    # -- derived skeletons ---------------------------------------------------------------------
    def with_rest(self, rest_translations=None, rest_rotations=None) -> "Skeleton":
        """A copy with some rest arrays replaced."""
        return Skeleton(
            self.names,
            self.parents,
            self.rest_translations if rest_translations is None else rest_translations,
            self.rest_rotations if rest_rotations is None else rest_rotations,
            self.end_site_parents,
            self.end_site_offsets,
        )

    def transformed(self, scale: float = 1.0, rotation: np.ndarray | None = None) -> "Skeleton":
        """The same skeleton scaled uniformly and with a global rotation (x,y,z,w) applied at the roots."""
        rot = quat.IDENTITY if rotation is None else np.asarray(rotation, dtype=np.float64)
        trans = self.rest_translations * scale
        rots = np.array(self.rest_rotations)
        roots = self.roots
        trans[roots] = quat.rotate(rot, trans[roots])
        rots[roots] = quat.multiply(rot, rots[roots])
        return Skeleton(self.names, self.parents, trans, rots, self.end_site_parents, self.end_site_offsets * scale)

    def describe_tree(self, max_lines: int | None = None) -> str:
        """An indented text tree of joint names."""
        lines: list[str] = []
        stack = [(int(r), 0) for r in reversed(self.roots)]
        while stack:  # depth first, children in order, without recursion (hierarchies may be deep)
            i, depth = stack.pop()
            lines.append("  " * depth + self.names[i])
            stack.extend((c, depth + 1) for c in reversed(self.children[i]))
        if max_lines is not None and len(lines) > max_lines:
            lines = lines[:max_lines] + [f"... ({len(lines) - max_lines} more)"]
        return "\n".join(lines)
