"""What a render shows: figures (a skeleton moving through global joint positions) and markers.

Coordinates are the core frame: metres, right-handed, +Y up, +Z the character's forward, +X its
left. Times are seconds; frame ``i`` of a figure is at ``i / fps``.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from typing import Iterable, Mapping, Sequence

import numpy as np
from PIL import ImageColor

from ..kinematics import end_site_positions, motion_fk
from ..mesh import SkinnedMesh
from ..motion import Motion
from ..skeleton import Skeleton
from .meshes import FigureMesh

RGB = tuple[int, int, int]
#: What a figure is drawn as: ``mesh`` (the shaded skinned mesh), ``stick`` (the skeleton) or ``auto``
#: (the mesh when there is one that shows the character, else the skeleton).
STYLES = ("auto", "mesh", "stick")
#: A mesh spanning less than this share of the skeleton's height does not show the character.
MIN_MESH_SIZE = 0.25

#: Base colours given to figures that do not choose one, in order.
PALETTE: tuple[RGB, ...] = (
    (38, 101, 181),   # blue
    (214, 104, 22),   # orange
    (36, 145, 84),    # green
    (142, 68, 173),   # purple
    (192, 57, 43),    # red
    (22, 139, 150),   # teal
)

#: Side codes of :attr:`Figure.sides`.
LEFT, CENTRE, RIGHT = 1, 0, -1


def to_rgb(color) -> RGB:
    """``"#rrggbb"``, a colour name or an (r, g, b) tuple of 0..255 ints -> (r, g, b)."""
    if isinstance(color, str):
        return ImageColor.getrgb(color)[:3]
    r, g, b = (int(c) for c in color[:3])
    return (r, g, b)


def default_sides(skeleton: Skeleton, pose: np.ndarray | None = None, mask: np.ndarray | None = None,
                  centre_tolerance: float = 0.02) -> np.ndarray:
    """(J,) side of each joint from geometry: +1 left (+X), -1 right (-X), 0 centre.

    The rest pose is used when it stands upright (at least half as tall along +Y as it is wide);
    otherwise ``pose`` (J, 3), e.g. a clip's first frame, when given (some files keep every bone
    along one axis at rest). Only the joints in ``mask`` (J,) bool, default all, are measured, so
    a detached root does not make a lying rest pose look tall. Sides are measured from the median
    joint X; joints within ``centre_tolerance`` x the pose's size of it are centre, and a joint under
    a left or right joint takes its side (limbs do not change side). Callers who know
    the sides from names (a mapping, see :func:`sides_from_mapping`) should pass their own array.
    """
    mask = np.ones(skeleton.num_joints, dtype=bool) if mask is None else np.asarray(mask, dtype=bool)
    rest = skeleton.rest_global_positions
    extent = np.ptp(rest[mask], axis=0)
    upright = extent[1] >= 0.5 * extent.max()  # a T-pose is about as wide as tall; a lying rest is flat in Y
    points = rest if upright or pose is None else np.asarray(pose, dtype=np.float64)
    dx = points[:, 0] - np.median(points[mask, 0])
    tol = centre_tolerance * max(float(np.max(np.ptp(points[mask], axis=0))), 1e-9)
    own = np.where(dx > tol, LEFT, np.where(dx < -tol, RIGHT, CENTRE)).astype(np.int8)
    sides = own.copy()
    for j, parent in enumerate(skeleton.parents):  # a limb keeps its side (a foot crossing the midline mid-stride)
        if parent >= 0 and sides[parent] != CENTRE:
            sides[j] = sides[parent]
    return sides


def sides_from_mapping(skeleton: Skeleton, mapping) -> np.ndarray:
    """(J,) sides from a canonical :class:`~infuse.mapping.Mapping`; unmapped joints take their
    nearest mapped ancestor's side (fingers follow their wrist), roots without one are centre."""
    from ..canonical import canonical_joint

    codes = {"left": LEFT, "right": RIGHT, "center": CENTRE}
    own = {}
    for canonical, joint in mapping.mapped().items():
        if joint in skeleton.index:
            own.setdefault(skeleton.index[joint], codes[canonical_joint(canonical).side])
    sides = np.zeros(skeleton.num_joints, dtype=np.int8)
    for j, parent in enumerate(skeleton.parents):  # parents come first, so they are already set
        sides[j] = own.get(j, sides[parent] if parent >= 0 else CENTRE)
    return sides


def _namespace_length(names: Sequence[str]) -> int:
    """Length of a namespace prefix (up to a ``:`` or ``|``) that every name shares, else 0."""
    first = names[0]
    cut = max(first.rfind(":"), first.rfind("|")) + 1
    while cut and not all(n.startswith(first[:cut]) for n in names):
        cut = max(first.rfind(":", 0, cut - 1), first.rfind("|", 0, cut - 1)) + 1
    return cut


@dataclass
class Marker:
    """A labelled point in space, fixed or moving: a gaze or reach target.

    - ``position``: (3,) metres, or (F, 3) one per frame of the figure it belongs to.
    - ``style``: ``"cross"`` (three axis strokes) or ``"sphere"`` (a shaded disc).
    - ``size``: metres, the cross's half length or the sphere's radius.
    - ``ray_from``: a joint name of the owning figure; a dashed line goes from it to the marker
      (a gaze ray, a reach line).
    """

    position: np.ndarray
    label: str = ""
    color: object = (200, 30, 90)
    style: str = "cross"
    size: float = 0.05
    ray_from: str | None = None

    def __post_init__(self):
        pos = np.asarray(self.position, dtype=np.float64)
        if pos.shape == (3,):
            pos = pos[None]
        if pos.ndim != 2 or pos.shape[1] != 3 or not np.all(np.isfinite(pos)):
            raise ValueError(f"marker {self.label!r}: position must be finite (3,) or (F, 3), got shape {np.shape(self.position)}")
        if self.style not in ("cross", "sphere"):
            raise ValueError(f"marker {self.label!r}: style must be 'cross' or 'sphere', got {self.style!r}")
        self.position = pos
        self.color = to_rgb(self.color)

    def at(self, frames: np.ndarray) -> np.ndarray:
        """(T, 3) positions at the owning figure's frame indices ``frames`` (held at the ends)."""
        return self.position[np.clip(frames, 0, len(self.position) - 1)]


@dataclass
class Figure:
    """A skeleton and where its joints are over time: one stick figure to draw.

    - ``positions``: (F, J, 3) global joint positions, metres (e.g. from :func:`infuse.motion_fk`).
    - ``fps``: frames per second of ``positions``.
    - ``end_sites``: optional (F, E, 3) global end-site positions (leaf tips: head top, toes).
    - ``color``: base colour; the left side is drawn lighter and the right side darker.
    - ``sides``: (J,) +1 left / -1 right / 0 centre; default :func:`default_sides` (of the rest
      pose, or of the first frame when the rest pose is not upright).
    - ``highlight``: joints to ring (low-confidence mappings...): joint names or a (J,) bool array.
    - ``names``: joint labels to draw: ``True`` for every joint (without a namespace every name
      shares, such as ``mixamorig:``), joint names, or {joint: text}. Stored as {joint index: text}.
    - ``contacts``: {joint name: (F,) bool}; the joint and its ground spot turn the contact colour
      on frames where it is True (foot contacts).
    - ``markers``: :class:`Marker` objects that belong to this figure (drawn in its panel).
    - ``mesh``: a :class:`~infuse.render.meshes.FigureMesh` with one pose per frame: the figure is
      drawn as its shaded skinned surfaces instead of a stick figure.
    """

    skeleton: Skeleton
    positions: np.ndarray
    fps: float = 30.0
    label: str = ""
    color: object | None = None
    end_sites: np.ndarray | None = None
    sides: np.ndarray | None = None
    highlight: Iterable[str] | np.ndarray | None = None
    names: bool | Sequence[str] | Mapping[str, str] | None = None
    contacts: Mapping[str, np.ndarray] | None = None
    markers: list[Marker] = field(default_factory=list)
    mesh: FigureMesh | None = None

    def __post_init__(self):
        sk = self.skeleton
        j = sk.num_joints
        pos = np.asarray(self.positions, dtype=np.float64)
        if pos.ndim == 2:
            pos = pos[None]
        if pos.ndim != 3 or pos.shape[1:] != (j, 3) or len(pos) == 0:
            raise ValueError(f"figure {self.label!r}: positions must be (F, {j}, 3), got {np.shape(self.positions)}")
        if not np.all(np.isfinite(pos)):
            raise ValueError(f"figure {self.label!r}: positions contain NaN or infinity")
        self.positions = pos
        if not (np.isfinite(self.fps) and self.fps > 0):
            raise ValueError(f"figure {self.label!r}: fps must be positive")
        if self.end_sites is not None:
            es = np.asarray(self.end_sites, dtype=np.float64)
            if es.ndim == 2:
                es = es[None]
            if es.shape != (len(pos), len(sk.end_site_parents), 3):
                raise ValueError(f"figure {self.label!r}: end_sites must be (F, E, 3) matching the skeleton's end sites")
            self.end_sites = es
        if self.sides is None:
            self.sides = default_sides(sk, pos[0], self.visible[:j])
        self.sides = np.asarray(self.sides, dtype=np.int8)
        if self.sides.shape != (j,):
            raise ValueError(f"figure {self.label!r}: sides must be ({j},)")
        self.highlight = self._joint_mask(self.highlight, "highlight")
        self.names = self._name_labels(self.names)
        contacts = {}
        for name, flags in (self.contacts or {}).items():
            flags = np.asarray(flags, dtype=bool).reshape(-1)
            if len(flags) != len(pos):
                raise ValueError(f"figure {self.label!r}: contact array for {name!r} has {len(flags)} frames, expected {len(pos)}")
            contacts[self._joint(name, "contacts")] = flags
        self.contacts = contacts
        for marker in self.markers:
            if marker.ray_from is not None:
                self._joint(marker.ray_from, f"marker {marker.label!r} ray_from")
        if self.mesh is not None and (self.mesh.num_frames != len(pos) or self.mesh.rotations.shape[1] != j):
            raise ValueError(f"figure {self.label!r}: its mesh has {self.mesh.num_frames} frames of "
                             f"{self.mesh.rotations.shape[1]} joints, expected {len(pos)} of {j}")

    # -- construction ----------------------------------------------------------------------------
    @classmethod
    def from_motion(cls, motion: Motion, meshes: Sequence[SkinnedMesh] = (), **options) -> "Figure":
        """A figure playing ``motion`` (FK of every frame at once, end sites included).

        With ``meshes`` (surfaces bound to the motion's skeleton, e.g. ``asset.meshes``) it is drawn
        as those surfaces skinned by the motion, their morph targets moved by the motion's morph weights.
        """
        g_rot, g_pos = motion_fk(motion)
        ends = end_site_positions(motion.skeleton, g_rot, g_pos) if len(motion.skeleton.end_site_parents) else None
        options.setdefault("label", motion.name)
        morph_weights = dict(zip(motion.morph_names, motion.morph_weights.T))
        mesh = FigureMesh(meshes, g_rot, g_pos, morph_weights) if meshes else None
        return cls(motion.skeleton, g_pos, fps=motion.fps, end_sites=ends, mesh=mesh, **options)

    @classmethod
    def from_skeleton(cls, skeleton: Skeleton, meshes: Sequence[SkinnedMesh] = (), **options) -> "Figure":
        """A one-frame figure in the skeleton's rest pose (drawn as ``meshes`` when given)."""
        ends = skeleton.rest_end_site_positions[None] if len(skeleton.end_site_parents) else None
        mesh = FigureMesh(meshes, skeleton.rest_global_rotations[None], skeleton.rest_global_positions[None]) if meshes else None
        return cls(skeleton, skeleton.rest_global_positions[None], end_sites=ends, mesh=mesh, **options)

    # -- derived ---------------------------------------------------------------------------------
    @property
    def num_frames(self) -> int:
        return len(self.positions)

    @property
    def duration(self) -> float:
        """Seconds from the first to the last frame."""
        return (self.num_frames - 1) / self.fps

    def frames_at(self, times: np.ndarray) -> np.ndarray:
        """(T,) frame index nearest to each time in seconds, held at the first and last frame."""
        return np.clip(np.rint(np.asarray(times) * self.fps).astype(np.int64), 0, self.num_frames - 1)

    def points(self) -> np.ndarray:
        """(F, J + E, 3): joints then end sites, the points bones connect."""
        if self.end_sites is None:
            return self.positions
        return np.concatenate((self.positions, self.end_sites), axis=1)

    @cached_property
    def bones(self) -> np.ndarray:
        """(B, 2) indices into :meth:`points`: (parent, child) links that act as rigid bones.

        A link whose length changes by more than 5% of the skeleton's height over the clip is not
        a bone but a free joint (a BVH root left at the origin while the hips walk away) and is
        left out.
        """
        sk = self.skeleton
        child = np.nonzero(sk.parents >= 0)[0]
        pairs = [np.stack((sk.parents[child], child), axis=1)]
        if self.end_sites is not None:
            e = len(sk.end_site_parents)
            pairs.append(np.stack((sk.end_site_parents, sk.num_joints + np.arange(e)), axis=1))
        pairs = np.concatenate(pairs).astype(np.int64).reshape(-1, 2)
        pts = self.points()
        lengths = np.linalg.norm(pts[:, pairs[:, 1]] - pts[:, pairs[:, 0]], axis=-1)  # (F, B)
        rigid = np.ptp(lengths, axis=0) <= 0.05 * max(sk.height(), 1e-6)
        return pairs[rigid]

    @cached_property
    def root(self) -> int:
        """Index of the first joint that is drawn: the one the trail and a following camera track."""
        return int(np.argmax(self.visible[: self.skeleton.num_joints]))

    @cached_property
    def visible(self) -> np.ndarray:
        """(J + E,) bool: points that belong to a drawn bone (every point when there is no bone)."""
        mask = np.zeros(self.points().shape[1], dtype=bool)
        mask[self.bones.reshape(-1)] = True
        return mask if mask.any() else ~mask

    # -- helpers ---------------------------------------------------------------------------------
    def _joint(self, name: str, what: str) -> int:
        try:
            return self.skeleton.index[name]
        except KeyError:
            raise ValueError(f"figure {self.label!r}: {what} names unknown joint {name!r}") from None

    def _joint_mask(self, value, what: str) -> np.ndarray:
        j = self.skeleton.num_joints
        if value is None:
            return np.zeros(j, dtype=bool)
        arr = np.asarray(value)
        if arr.dtype == bool:
            if arr.shape != (j,):
                raise ValueError(f"figure {self.label!r}: {what} mask must be ({j},)")
            return arr
        mask = np.zeros(j, dtype=bool)
        for name in value:
            mask[self._joint(name, what)] = True
        return mask

    def _name_labels(self, value) -> dict[int, str]:
        """Joint index -> text to draw beside it."""
        if not value:
            return {}
        if value is True:
            names = self.skeleton.names
            cut = _namespace_length(names)
            return {j: n[cut:] or n for j, n in enumerate(names)}
        if isinstance(value, Mapping):
            return {self._joint(k, "names"): str(v) for k, v in value.items()}
        return {self._joint(k, "names"): k for k in value}


def drawable_meshes(asset, skeleton: Skeleton, style: str = "auto", path=None) -> tuple[SkinnedMesh, ...]:
    """The surfaces of ``asset`` to draw a figure on ``skeleton`` with, for ``style`` (:data:`STYLES`).

    None for ``stick``, or when ``skeleton`` is not the asset's own (its meshes are bound to that). A mesh
    much smaller than the skeleton (a placeholder plane in a skeleton-only file) does not show the
    character: ``auto`` draws the stick figure instead, ``mesh`` raises :class:`UnusableInputError`
    naming ``path`` (default: the asset's file), as it does for an asset without a mesh.
    """
    from ..errors import UnusableInputError

    if style == "stick":
        return ()
    path = asset.path if path is None else path
    meshes = tuple(m for m in asset.meshes if m.num_triangles) if skeleton is asset.skeleton else ()
    if meshes:
        extent = float(np.ptp(np.concatenate([m.positions for m in meshes]), axis=0).max())
        if extent < MIN_MESH_SIZE * skeleton.height():
            if style == "mesh":
                raise UnusableInputError(path, f"its mesh is {extent:.3g} m across, too small to show a "
                                               f"{skeleton.height():.3g} m skeleton; use --style stick or auto")
            return ()
    if not meshes and style == "mesh":
        why = [w for w in asset.warnings if "not drawn" in w]
        detail = f" ({why[0]})" if why else ""
        raise UnusableInputError(path, f"has no skinned mesh to draw{detail}; use --style stick or auto")
    return meshes
