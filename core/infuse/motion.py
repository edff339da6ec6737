"""A motion: per-frame local joint rotations and root translation on one skeleton.

Arrays are struct-of-arrays over frames (no per-frame objects). Units are metres and seconds;
quaternions are (x, y, z, w); axes are the core's (+Y up, +Z forward, right-handed).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from . import limits
from .errors import InputError
from .skeleton import Skeleton


@dataclass(frozen=True, eq=False)
class Motion:
    """An immutable clip on ``skeleton``.

    - ``fps``: frames per second (> 0).
    - ``local_rotations``: (F, J, 4) local joint rotations (x, y, z, w); joints a file does not
      animate hold their rest rotation.
    - ``root_translations``: (F, 3) metres, the local translation of joint 0 (the first root).
    - ``joint_translations``: optional (F, J, 3) metres, local translations of every joint when a
      file animates them (BVH position channels on inner joints, glTF translation tracks); column 0
      is ignored in favour of ``root_translations``. ``None`` means rest offsets.
    - ``name``: the clip name; ``sync_points``: named times in seconds (ready, stroke, relax...).
    """

    skeleton: Skeleton
    fps: float
    local_rotations: np.ndarray
    root_translations: np.ndarray
    joint_translations: np.ndarray | None = None
    name: str = ""
    sync_points: dict = field(default_factory=dict)

    def __post_init__(self):
        lr = np.array(self.local_rotations, dtype=np.float64)
        rt = np.array(self.root_translations, dtype=np.float64)
        object.__setattr__(self, "local_rotations", lr)
        object.__setattr__(self, "root_translations", rt)
        if self.joint_translations is not None:
            object.__setattr__(self, "joint_translations", np.array(self.joint_translations, dtype=np.float64))
        for a in (lr, rt, self.joint_translations):
            if a is not None:
                a.setflags(write=False)
        self.validate()

    def validate(self, file: str | None = None) -> None:
        """Raise :class:`InputError` unless shapes agree and every value is finite."""
        j = self.skeleton.num_joints
        where = f"motion {self.name!r}" if self.name else "motion"
        if not (np.isfinite(self.fps) and self.fps > 0):
            raise InputError(file, where, f"frame rate must be positive, got {self.fps}")
        f = self.local_rotations.shape[0] if self.local_rotations.ndim == 3 else -1
        if self.local_rotations.shape != (f, j, 4):
            raise InputError(file, where, f"local_rotations has shape {self.local_rotations.shape}, expected (F, {j}, 4)")
        if self.root_translations.shape != (f, 3):
            raise InputError(file, where, f"root_translations has shape {self.root_translations.shape}, expected ({f}, 3)")
        if self.joint_translations is not None and self.joint_translations.shape != (f, j, 3):
            raise InputError(file, where, "joint_translations does not match (F, J, 3)")
        for label, arr in (("rotation", self.local_rotations), ("root translation", self.root_translations),
                           ("joint translation", self.joint_translations)):
            if arr is not None and not np.all(np.isfinite(arr)):
                frame = int(np.argmax(~np.isfinite(arr.reshape(f, -1)).all(axis=1)))
                raise InputError(file, f"{where} frame {frame}", f"{label} is not finite (NaN or infinity)")
        limits.check(file, where, "frame rate (fps)", self.fps, "MAX_FPS")
        for label, arr in (("root translation", self.root_translations), ("joint translation", self.joint_translations)):
            if arr is not None and arr.size and np.max(np.abs(arr)) > limits.MAX_COORDINATE_M:
                frame = int(np.argmax(np.abs(arr.reshape(f, -1)).max(axis=1)))
                limits.check_coordinates(file, f"{where} frame {frame}", arr[frame], label)

    @property
    def num_frames(self) -> int:
        return self.local_rotations.shape[0]

    @property
    def duration(self) -> float:
        """Seconds from the first to the last frame."""
        return max(self.num_frames - 1, 0) / self.fps

    def local_translations(self) -> np.ndarray:
        """(F, J, 3) local translations of every joint, metres."""
        if self.joint_translations is not None:
            out = np.array(self.joint_translations)
        else:
            out = np.broadcast_to(self.skeleton.rest_translations, (self.num_frames,) + self.skeleton.rest_translations.shape).copy()
        out[:, 0] = self.root_translations
        return out

    def replace(self, **changes) -> "Motion":
        """A copy with some fields replaced."""
        fields = dict(
            skeleton=self.skeleton, fps=self.fps, local_rotations=self.local_rotations,
            root_translations=self.root_translations, joint_translations=self.joint_translations,
            name=self.name, sync_points=dict(self.sync_points),
        )
        fields.update(changes)
        return Motion(**fields)

    @classmethod
    def rest_pose(cls, skeleton: Skeleton, frames: int = 1, fps: float = 30.0, name: str = "rest") -> "Motion":
        """A motion that holds the rest pose for ``frames`` frames."""
        rots = np.broadcast_to(skeleton.rest_rotations, (frames,) + skeleton.rest_rotations.shape)
        root = np.broadcast_to(skeleton.rest_translations[0], (frames, 3))
        return cls(skeleton, fps, rots, root, name=name)
