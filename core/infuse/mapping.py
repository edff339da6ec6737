"""Mappings from canonical joint names to the joints of one skeleton, and how to obtain them.

A :class:`Mapping` says, for every canonical name (:mod:`infuse.canonical`), which joint of a
skeleton it means (or ``None``: no counterpart), how sure the mapper is (0..1) and why. Mappings
are made by mapper plugins (:func:`map_skeleton` looks them up by name), saved as small JSON
files a person can edit, and completed from a partial hand-made file::

    {"mapping": {"base": "Hips", "l_wrist": null, ...},
     "confidence": {"base": 0.98, ...},
     "unmapped": ["HeadTop_End", ...],
     "reasons": {"base": "...", ...}, "mapper": "heuristic", "overall_confidence": 0.95}

In a hand-edited file ``null`` means "this skeleton has no such joint"; a canonical name that is
left out means "let the mapper decide".
"""
from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Iterable, Sequence

import numpy as np

from . import registry
from .atomic import atomic_path
from .canonical import ALL_NAMES, CANONICAL_NAMES, EXTRA_NAMES, is_canonical
from .errors import InputError
from .skeleton import Skeleton

#: The built-in default mapper; a user may choose another (:func:`infuse.registry.default_name`).
DEFAULT_MAPPER = registry.KINDS["mapper"].default


@dataclass
class Mapping:
    """Canonical name -> joint name (or ``None``) for one skeleton, with confidences and reasons.

    - ``joints``: every canonical name (required and extra) -> joint name or ``None``.
    - ``confidence``: canonical name -> 0..1, how sure the mapper is of that entry (also of a ``None``).
    - ``reasons``: canonical name -> a short sentence saying why.
    - ``unmapped``: joints of the skeleton no canonical name points to, in skeleton order.
    - ``overall_confidence``: 0..1 for the whole map (by default the mean over the required names).
    - ``mapper``: the name of the mapper that made it (``"saved"`` for a file used as is).
    """

    joints: dict[str, str | None]
    confidence: dict[str, float] = field(default_factory=dict)
    reasons: dict[str, str] = field(default_factory=dict)
    unmapped: tuple[str, ...] = ()
    overall_confidence: float = 0.0
    mapper: str = ""

    @classmethod
    def build(cls, skeleton: Skeleton, joints: dict[str, str | None], confidence: dict[str, float] | None = None,
              reasons: dict[str, str] | None = None, mapper: str = "", overall_confidence: float | None = None) -> "Mapping":
        """A complete mapping from a partial ``joints`` dict: missing names become ``None``, the
        unmapped joints and (unless given) the overall confidence are computed."""
        confidence = dict(confidence or {})
        reasons = dict(reasons or {})
        full = {name: joints.get(name) for name in ALL_NAMES}
        for name in ALL_NAMES:
            confidence.setdefault(name, 0.5)
            confidence[name] = float(min(1.0, max(0.0, confidence[name])))
            reasons.setdefault(name, "")
        used = {v for v in full.values() if v is not None}
        unmapped = tuple(n for n in skeleton.names if n not in used)
        if overall_confidence is None:
            overall_confidence = float(np.mean([confidence[n] for n in CANONICAL_NAMES]))
        return cls(full, confidence, reasons, unmapped, float(overall_confidence), mapper)

    # -- access ------------------------------------------------------------------------------------
    def __getitem__(self, canonical: str) -> str | None:
        return self.joints[canonical]

    def get(self, canonical: str, default: str | None = None) -> str | None:
        value = self.joints.get(canonical)
        return default if value is None else value

    def mapped(self) -> dict[str, str]:
        """Only the canonical names that have a joint."""
        return {k: v for k, v in self.joints.items() if v is not None}

    def inverse(self) -> dict[str, str]:
        """Joint name -> canonical name (the first canonical name, in table order, when a joint is used twice)."""
        out: dict[str, str] = {}
        for k, v in self.joints.items():
            if v is not None:
                out.setdefault(v, k)
        return out

    def indices(self, skeleton: Skeleton) -> dict[str, int]:
        """Canonical name -> joint index in ``skeleton`` for the mapped names."""
        return {k: skeleton.index[v] for k, v in self.mapped().items()}

    # -- files ---------------------------------------------------------------------------------------
    def to_dict(self, extras: bool = True) -> dict[str, Any]:
        """The JSON document (``mapping``, ``confidence``, ``unmapped``, plus ``reasons``, ``mapper``,
        ``overall_confidence``): the 69 required names first, then the extra names that are mapped
        (all of them with ``extras``)."""
        names = list(CANONICAL_NAMES) + [n for n in EXTRA_NAMES if extras or self.joints.get(n) is not None]
        return {
            "mapping": {n: self.joints.get(n) for n in names},
            "confidence": {n: round(self.confidence.get(n, 0.0), 3) for n in names},
            "unmapped": list(self.unmapped),
            "reasons": {n: self.reasons.get(n, "") for n in names},
            "mapper": self.mapper,
            "overall_confidence": round(self.overall_confidence, 3),
        }

    def save(self, path: str | Path) -> Path:
        """Write the JSON document atomically; returns ``path``."""
        path = Path(path)
        with atomic_path(path) as tmp:
            Path(tmp).write_text(json.dumps(self.to_dict(extras=False), indent=1, ensure_ascii=False) + "\n", encoding="utf-8")
        return path

    @classmethod
    def load(cls, path: str | Path, skeleton: Skeleton) -> "Mapping":
        """Read a saved mapping for ``skeleton``; names missing from the file become ``None``.

        Use :func:`map_skeleton` with ``saved_map=`` to let a mapper fill in the missing names instead.
        """
        saved = read_map(path)
        check_map(saved, skeleton, path)
        return cls.build(skeleton, saved.joints, saved.confidence, saved.reasons, mapper=saved.mapper or "saved")


@dataclass
class SavedMap:
    """The entries a mapping file states (possibly partial): ``joints`` holds only the names present."""

    joints: dict[str, str | None]
    confidence: dict[str, float]
    reasons: dict[str, str]
    mapper: str
    source: str

    def is_complete(self) -> bool:
        return all(n in self.joints for n in CANONICAL_NAMES)


def parse_map(doc: Any, source: str = "<map>") -> SavedMap:
    """Validate a mapping document (a dict, as read from JSON); raises :class:`InputError` naming the key."""
    if not isinstance(doc, dict) or not isinstance(doc.get("mapping"), dict):
        raise InputError(source, "mapping", 'expected an object {"mapping": {canonical name: joint name or null}}')
    joints: dict[str, str | None] = {}
    for key, value in doc["mapping"].items():
        if not is_canonical(key):
            raise InputError(source, f"mapping.{key}", f"{key!r} is not a canonical joint name")
        if value is not None and not isinstance(value, str):
            raise InputError(source, f"mapping.{key}", "expected a joint name (string) or null")
        joints[key] = value
    confidence: dict[str, float] = {}
    raw_conf = doc.get("confidence") or {}
    if not isinstance(raw_conf, dict):
        raise InputError(source, "confidence", "expected an object {canonical name: number}")
    for key, value in raw_conf.items():
        if key not in joints:
            continue  # a confidence without an entry says nothing
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not 0.0 <= float(value) <= 1.0:
            raise InputError(source, f"confidence.{key}", "expected a number between 0 and 1")
        confidence[key] = float(value)
    reasons = {k: str(v) for k, v in (doc.get("reasons") or {}).items() if k in joints} if isinstance(doc.get("reasons"), dict) else {}
    return SavedMap(joints, confidence, reasons, str(doc.get("mapper") or ""), source)


def read_map(path: str | Path) -> SavedMap:
    """Read and validate a mapping file (JSON)."""
    path = Path(path)
    if not path.is_file():
        raise InputError(path, None, "mapping file not found")
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise InputError(path, None, f"not a JSON mapping file: {exc}") from None
    return parse_map(doc, str(path))


def check_map(saved: SavedMap, skeleton: Skeleton, source: str | Path | None = None) -> None:
    """Raise :class:`InputError` (naming the file and the key) if the map names a joint ``skeleton`` lacks."""
    for key, value in saved.joints.items():
        if value is not None and value not in skeleton.index:
            raise InputError(source or saved.source, f"mapping.{key}", f"joint {value!r} is not in the skeleton")


def _as_saved(saved_map: Any) -> SavedMap:
    if isinstance(saved_map, SavedMap):
        return saved_map
    if isinstance(saved_map, Mapping):
        return SavedMap(dict(saved_map.joints), dict(saved_map.confidence), dict(saved_map.reasons), saved_map.mapper, "<mapping>")
    if isinstance(saved_map, dict):
        return parse_map(saved_map if "mapping" in saved_map else {"mapping": saved_map}, "<map>")
    return read_map(saved_map)


def get_mapper(name: str | None = None):
    """The installed mapper plugin called ``name`` (the default mapper when ``None``); :class:`UsageError`
    listing the installed ones otherwise."""
    return registry.get("mapper", name)


def sample_poses(asset, count: int = 12) -> np.ndarray | None:
    """(F, J, 3) global joint positions (metres) of up to ``count`` frames spread over the asset's
    first clip (its first frame first), or ``None`` when it has no motion.

    Mappers use them when a file's rest pose says little about the body (e.g. every bone along one
    axis), and to tell the body's front from how it moves.
    """
    from .kinematics import forward_kinematics

    motion = next(iter(getattr(asset, "motions", {}).values()), None)
    if motion is None or motion.num_frames == 0 or motion.skeleton.num_joints != asset.skeleton.num_joints:
        return None
    frames = np.unique(np.linspace(0, motion.num_frames - 1, min(count, motion.num_frames)).astype(np.int64))
    jt = None if motion.joint_translations is None else motion.joint_translations[frames]
    _, pos = forward_kinematics(motion.skeleton, motion.local_rotations[frames], motion.root_translations[frames], jt)
    return pos if np.all(np.isfinite(pos)) else None


def resolve_pose(pose) -> np.ndarray | None:
    """A mapper's ``pose`` option as an array: it may be given as a zero-argument callable so that
    poses are computed only when a mapper needs them."""
    return pose() if callable(pose) else pose


def complete(saved: SavedMap, produced: Mapping, skeleton: Skeleton) -> Mapping:
    """Hand-set entries of ``saved`` win over ``produced``; a joint given by hand to one name is taken
    away from any other name the mapper gave it to."""
    joints = dict(produced.joints)
    confidence = dict(produced.confidence)
    reasons = dict(produced.reasons)
    taken = {v: k for k, v in saved.joints.items() if v is not None}
    for key, value in list(joints.items()):
        if key not in saved.joints and value in taken:
            joints[key] = None
            confidence[key] = 0.3
            reasons[key] = f"{value!r} is set to {taken[value]} by hand"
    for key, value in saved.joints.items():
        joints[key] = value
        confidence[key] = saved.confidence.get(key, 1.0)
        reasons[key] = saved.reasons.get(key) or f"set by hand in {saved.source}"
    mapper = f"{produced.mapper}+saved" if produced.mapper else "saved"
    return Mapping.build(skeleton, joints, confidence, reasons, mapper=mapper)


def map_skeleton(source, mapper: str | None = None, saved_map: Any = None, *,
                 pose: np.ndarray | Callable[[], np.ndarray | None] | None = None,
                 meta: dict | None = None, humanoid: dict | None = None, animated: Sequence[str] | None = None,
                 **options) -> Mapping:
    """Map a skeleton (or the skeleton of an :class:`~infuse.asset.Asset`) to the canonical names.

    - ``mapper``: the name of an installed mapper plugin (see ``infuse plugins``); ``None`` is the
      default mapper (:func:`infuse.registry.default_name`).
    - ``saved_map``: a mapping file path, a parsed dict or a :class:`Mapping`; its entries win and
      the mapper fills in the names it leaves out (a complete file is used as is).
    - ``pose``: optional (J, 3) or (F, J, 3) global joint positions in metres (core frame) of
      representative poses, for skeletons whose rest pose is arbitrary; sampled from an Asset's
      first clip when not given (:func:`sample_poses`). Mappers receive it as an array or as a
      zero-argument callable returning one (see :func:`resolve_pose`). ``meta``: format facts, from an Asset.
    - ``humanoid``: the file's own humanoid map {VRM humanoid bone: joint name} (``Asset.humanoid``,
      taken from an Asset when not given). Mappers receive ``meta`` and ``humanoid`` as keywords.
    - ``animated``: names of the joints a motion file has data for; entries naming other joints
      become ``None`` (:func:`restrict_to_animated`). From an Asset, the joints its clips animate
      (:func:`animated_joint_names`); map its ``skeleton`` instead to map every joint.

    Raises :class:`UsageError` for an unknown mapper, :class:`InputError` for a map naming joints the
    skeleton does not have, :class:`~infuse.errors.NotHumanoidError` when the mapper refuses the skeleton.
    """
    file = options.pop("file", None)
    if isinstance(source, Skeleton):
        skeleton = source
    else:  # an Asset
        skeleton = source.skeleton
        file = file or getattr(source, "path", None)
        meta = dict(source.meta) if meta is None else meta
        humanoid = source.humanoid if humanoid is None else humanoid
        animated = animated_joint_names(source) if animated is None else animated
        if pose is None:
            asset = source
            pose = lambda: sample_poses(asset)  # noqa: E731 - computed only if the mapper asks
    saved = _as_saved(saved_map) if saved_map is not None else None
    if saved is not None:
        check_map(saved, skeleton)
        if saved.is_complete():
            return Mapping.build(skeleton, saved.joints, saved.confidence, saved.reasons, mapper=saved.mapper or "saved")
    plugin = get_mapper(mapper)
    fixed = dict(saved.joints) if saved is not None else None
    result = plugin.map(skeleton, pose=pose, meta=meta or {}, humanoid=humanoid or {}, fixed=fixed, file=file, **options)
    if not isinstance(result, Mapping):  # a plain {canonical: joint} dict from a simple plugin
        result = Mapping.build(skeleton, dict(result), mapper=plugin.name)
    elif not result.mapper:
        result.mapper = plugin.name
    _check_result(result, skeleton, plugin.name)
    result = restrict_to_animated(result, skeleton, animated)
    return complete(saved, result, skeleton) if saved is not None else result


def animated_joint_names(asset) -> list[str] | None:
    """Names of the joints an Asset's clips animate (the union of their ``animated_joints``), or
    ``None`` when a clip animates every joint or no clip says which joints it animates."""
    masks = [m.animated_joints for m in asset.motions.values() if m.skeleton.names == asset.skeleton.names]
    if not masks or any(mask is None for mask in masks):
        return None
    union = np.logical_or.reduce(masks)
    return [name for name, animated in zip(asset.skeleton.names, union) if animated] or None


def restrict_to_animated(mapping: Mapping, skeleton: Skeleton, animated) -> Mapping:
    """Drop entries naming joints a motion file does not animate.

    A motion file (e.g. SmartBody ``.skm``) may animate only some joints of the skeleton it names
    (``animated``: their names, from :func:`animated_joint_names`). Canonical names pointing
    elsewhere become ``None``: the file has no data for them.
    """
    if not animated:
        return mapping
    keep = set(animated)
    joints = dict(mapping.joints)
    confidence = dict(mapping.confidence)
    reasons = dict(mapping.reasons)
    for key, value in mapping.joints.items():
        if value is not None and value not in keep:
            joints[key] = None
            reasons[key] = f"{value!r} is not animated in this file"
    return Mapping.build(skeleton, joints, confidence, reasons, mapper=mapping.mapper,
                         overall_confidence=mapping.overall_confidence)


def _check_result(result: Mapping, skeleton: Skeleton, name: str) -> None:
    for key, value in result.joints.items():
        if value is not None and value not in skeleton.index:
            raise ValueError(f"mapper {name!r} returned joint {value!r} for {key}, which is not in the skeleton")


def format_table(mapping: Mapping, names: Iterable[str] = CANONICAL_NAMES) -> str:
    """A text table: canonical name, joint, confidence, reason."""
    rows = []
    width = max(len(str(mapping.joints.get(n))) for n in names)
    for n in names:
        joint = mapping.joints.get(n)
        rows.append(f"  {n:<20} {('-' if joint is None else joint):<{width}}  {mapping.confidence.get(n, 0):.2f}  {mapping.reasons.get(n, '')}")
    return "\n".join(rows)
