"""What a reader returns (:class:`Asset`) and what a character is (:class:`Character`)."""
from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import Any, Callable, Sequence

import numpy as np

from .errors import PARSE_ERRORS, InfuseError, InputError
from .mesh import SkinnedMesh
from .motion import Motion
from .skeleton import Skeleton


@dataclass
class Asset:
    """The contents of one file, converted into the core frame (metres, +Y up).

    - ``skeleton``: the joint hierarchy (for a motion-only file: the joints its channels name,
      with the skeleton found beside it when there is one).
    - ``motions``: clip name -> :class:`Motion` (may be empty); a clip carries every track it
      animates (joints, root motion, morph weights, the mask of animated joints).
    - ``morph_targets``: names of blend shapes / morph targets, in file order.
    - ``source_units`` / ``source_up_axis``: what the file used, e.g. ``"cm"`` and ``"Z"``;
      ``units_detected_by``: ``"file"`` (declared), ``"guess"`` or ``"override"``.
    - ``meta``: format-specific facts for people and the format's own writer (channel orders,
      clip timing...); no other plugin reads it.
    - ``warnings``: what the reader left out or approximated, one sentence each (a mesh not drawn,
      a texture not found); the mesh loader adds its own when :attr:`meshes` is first used.
    - ``payload``: format-specific data a writer needs to keep what the core does not model
      (mesh, skin, materials); opaque to the core.
    - ``mesh_loader``: a callable returning the file's :class:`~infuse.mesh.SkinnedMesh` surfaces,
      called once, on first use of :attr:`meshes` (decoding geometry and textures costs more than
      reading a skeleton, and most commands never draw). ``None`` for files without meshes.
    - ``humanoid``: the file's own humanoid map, VRM humanoid bone name (``hips``, ``leftUpperArm``...)
      -> joint name, for files that declare one (VRM, VRMA); empty otherwise. Mappers use it first,
      and a ``.vrma`` writer needs it.
    - ``facing_turned``: the reader turned the file 180 degrees about +Y so that its characters face
      +Z (a VRM 0.x model faces -Z); what shows the file as it is turns core-frame points with it.
    """

    path: Path | None
    format: str
    skeleton: Skeleton
    motions: dict[str, Motion] = field(default_factory=dict)
    morph_targets: list[str] = field(default_factory=list)
    source_units: str = "m"
    source_up_axis: str = "Y"
    units_detected_by: str = "file"
    meta: dict[str, Any] = field(default_factory=dict)
    payload: Any = None
    mesh_loader: Callable[[], Sequence[SkinnedMesh]] | None = field(default=None, repr=False, compare=False)
    humanoid: dict[str, str] = field(default_factory=dict)
    facing_turned: bool = False
    warnings: list[str] = field(default_factory=list)

    @cached_property
    def meshes(self) -> tuple[SkinnedMesh, ...]:
        """The skinned surfaces bound to :attr:`skeleton` (core frame, bind pose; see :mod:`infuse.mesh`).

        Empty for a file without meshes, or whose meshes the reader cannot decode (it says why in
        :attr:`warnings`).
        """
        if self.mesh_loader is None:
            return ()
        try:
            with np.errstate(over="ignore", invalid="ignore", divide="ignore"):  # see fileio.load
                meshes = tuple(self.mesh_loader())
        except InfuseError:
            raise
        except RecursionError:
            raise InputError(self.path, "meshes", "cannot be decoded: nesting too deep") from None
        except PARSE_ERRORS as exc:  # a malformed mesh the reader's own checks missed
            raise InputError(self.path, "meshes", f"cannot be decoded: {type(exc).__name__}: {exc}") from exc
        for k, mesh in enumerate(meshes):
            for name, value in vars(mesh).items():
                if isinstance(value, np.ndarray) and value.dtype.kind == "f" and not np.all(np.isfinite(value)):
                    raise InputError(self.path, f"mesh {k} {name}", "is not finite (NaN or infinity)")
        return meshes

    @property
    def num_frames(self) -> int:
        return sum(m.num_frames for m in self.motions.values())

    @property
    def fps(self) -> float | None:
        return next(iter(self.motions.values())).fps if self.motions else None


@dataclass
class Character:
    """A skeleton ready to be animated: the asset it came from, plus what infuse adds to it.

    ``mapping`` (canonical name -> joint) and ``clips`` are filled by mappers and retargeters;
    ``asset.payload`` keeps the mesh and morph data so writers can write the character back.
    """

    name: str
    asset: Asset
    mapping: Any = None
    clips: dict[str, Motion] = field(default_factory=dict)

    @property
    def skeleton(self) -> Skeleton:
        return self.asset.skeleton

    @property
    def morph_targets(self) -> list[str]:
        return self.asset.morph_targets
