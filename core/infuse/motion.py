"""A motion: one animation clip on one skeleton, as a set of frame-major tracks.

The clip holds every animated quantity on one uniform frame grid: local joint rotations, root
motion, local joint translations, morph-target / expression weights, and the mask of joints it
animates. Arrays are struct-of-arrays over frames (no per-frame objects), frame-major (axis 0 is
the frame). Units are metres and seconds; quaternions are (x, y, z, w); axes are the core's
(+Y up, +Z forward, right-handed).
"""
from __future__ import annotations

import dataclasses
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
    - ``morph_names``: (M,) morph target or expression names the clip animates (a mesh target, a
      VRM expression...); ``morph_weights``: (F, M) their weights, usually 0..1, one column per
      name. Targets not named keep the character's own weights. Empty (M = 0) by default; an
      empty array given with names means zero weights.
    - ``animated_joints``: optional (J,) bool mask of the joints the clip has data for (a SmartBody
      motion names only some joints of its skeleton; a clip of morph weights alone animates none).
      The others hold their rest pose in the arrays above; writers leave them out and a runtime
      clip leaves them to the pose below. ``None`` means every joint.
    """

    skeleton: Skeleton
    fps: float
    local_rotations: np.ndarray
    root_translations: np.ndarray
    joint_translations: np.ndarray | None = None
    name: str = ""
    sync_points: dict = field(default_factory=dict)
    morph_names: tuple[str, ...] = ()
    morph_weights: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    animated_joints: np.ndarray | None = None

    def __post_init__(self):
        lr = np.array(self.local_rotations, dtype=np.float64)
        rt = np.array(self.root_translations, dtype=np.float64)
        object.__setattr__(self, "local_rotations", lr)
        object.__setattr__(self, "root_translations", rt)
        if self.joint_translations is not None:
            object.__setattr__(self, "joint_translations", np.array(self.joint_translations, dtype=np.float64))
        object.__setattr__(self, "morph_names", tuple(str(n) for n in self.morph_names))
        frames = lr.shape[0] if lr.ndim else 0
        weights = np.array(self.morph_weights, dtype=np.float64)
        if weights.size == 0:  # none given: zero weights of the names (M = 0 by default)
            weights = np.zeros((frames, len(self.morph_names)))
        object.__setattr__(self, "morph_weights", weights)
        if self.animated_joints is not None:
            object.__setattr__(self, "animated_joints", np.array(self.animated_joints, dtype=bool))
        for a in (lr, rt, self.joint_translations, self.morph_weights, self.animated_joints):
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
        m = len(self.morph_names)
        if self.morph_weights.shape != (f, m):
            raise InputError(file, where, f"morph_weights has shape {self.morph_weights.shape}, expected ({f}, {m}) "
                                          "(frames, morph names)")
        if len(set(self.morph_names)) != m:
            repeated = next(n for k, n in enumerate(self.morph_names) if n in self.morph_names[:k])
            raise InputError(file, where, f"morph target {repeated!r} is named twice")
        if self.animated_joints is not None and self.animated_joints.shape != (j,):
            raise InputError(file, where, f"animated_joints has shape {self.animated_joints.shape}, expected ({j},)")
        for label, arr in (("rotation", self.local_rotations), ("root translation", self.root_translations),
                           ("joint translation", self.joint_translations), ("morph weight", self.morph_weights)):
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

    @property
    def frame_times(self) -> np.ndarray:
        """(F,) seconds of each frame from the clip's start."""
        return np.arange(self.num_frames) / self.fps

    @property
    def animated_mask(self) -> np.ndarray:
        """(J,) bool: the joints the clip has data for (``animated_joints``, or every joint)."""
        if self.animated_joints is None:
            return np.ones(self.skeleton.num_joints, dtype=bool)
        return self.animated_joints

    def morph_weight(self, name: str) -> np.ndarray | None:
        """(F,) weights of morph target ``name``, or ``None`` when the clip does not animate it."""
        if name not in self.morph_names:
            return None
        return self.morph_weights[:, self.morph_names.index(name)]

    def local_translations(self) -> np.ndarray:
        """(F, J, 3) local translations of every joint, metres."""
        if self.joint_translations is not None:
            out = np.array(self.joint_translations)
        else:
            out = np.broadcast_to(self.skeleton.rest_translations, (self.num_frames,) + self.skeleton.rest_translations.shape).copy()
        out[:, 0] = self.root_translations
        return out

    def replace(self, **changes) -> "Motion":
        """A copy with some fields replaced.

        Tracks that no longer fit are left out unless given: the morph weights when the number of
        frames changes, the joint mask when the skeleton's number of joints does.
        """
        changes.setdefault("sync_points", dict(self.sync_points))
        frames = np.shape(changes.get("local_rotations", self.local_rotations))[0]
        if frames != self.num_frames and "morph_weights" not in changes:
            changes = {"morph_names": (), "morph_weights": np.zeros((0, 0)), **changes}
        joints = changes.get("skeleton", self.skeleton).num_joints
        if joints != self.skeleton.num_joints and "animated_joints" not in changes:
            changes["animated_joints"] = None
        return dataclasses.replace(self, **changes)

    @classmethod
    def rest_pose(cls, skeleton: Skeleton, frames: int = 1, fps: float = 30.0, name: str = "rest") -> "Motion":
        """A motion that holds the rest pose for ``frames`` frames."""
        rots = np.broadcast_to(skeleton.rest_rotations, (frames,) + skeleton.rest_rotations.shape)
        root = np.broadcast_to(skeleton.rest_translations[0], (frames, 3))
        return cls(skeleton, fps, rots, root, name=name)


def carry_morph_weights(motion: Motion, source: Motion, targets) -> Motion:
    """``motion`` (a clip made from ``source``, e.g. retargeted onto another character) with the morph
    weights of ``source`` whose names are among ``targets`` (that character's morph targets), sampled
    at ``motion``'s frame times (linear, held at the ends). A retargeted clip keeps its face where the
    character has morph targets of the same names; ``motion`` as it is when there are none."""
    available = set(targets)
    keep = [k for k, name in enumerate(source.morph_names) if name in available]
    if not keep or motion.num_frames == 0:
        return motion
    times, source_times = motion.frame_times, source.frame_times
    weights = np.stack([np.interp(times, source_times, source.morph_weights[:, k]) for k in keep], axis=1)
    return motion.replace(morph_names=[source.morph_names[k] for k in keep], morph_weights=weights)
