"""A behaviour pack on disk: its manifest, its built analysis and its clips, and the installed packs.

``infuse pack build`` stores, beside the analysis JSON, an ``.npz`` with the pack's skeleton and every
clip's arrays, so loading a built pack reads one binary file instead of parsing every clip. A change
to any clip file (size, time or content) makes the pack unbuilt again.
"""
from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path

import numpy as np

from .. import fileio, registry
from ..errors import InputError, UnusableInputError, UsageError
from ..mapping import Mapping
from ..motion import Motion
from ..skeleton import Skeleton
from .manifest import Manifest, read_manifest
from .tessellation import Tessellation

FORMAT_VERSION = 1


def file_digest(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def _record_key(path: Path, folder: Path) -> str:
    """``path`` relative to the pack folder when it lies inside it, so a built pack names no machine path."""
    try:
        return path.relative_to(folder).as_posix()
    except ValueError:
        return str(path)


def fingerprint(manifest: Manifest, known: dict | None = None) -> tuple[str, dict]:
    """A digest of the manifest and every file it names, and the per-file records ``{path: [size,
    mtime_ns, sha256]}`` (paths relative to the pack folder when inside it; a record in ``known`` with the
    same size and time is trusted without rehashing)."""
    known = known or {}
    records = {}
    h = hashlib.sha256(manifest.path.read_bytes())
    for path in [manifest.skeleton] + [c.file for c in manifest.clips]:
        if not path.is_file():
            raise InputError(manifest.path, str(path), "file named by the manifest not found")
        st = path.stat()
        key = _record_key(path, manifest.folder)
        old = known.get(key)
        digest = old[2] if old and old[0] == st.st_size and old[1] == st.st_mtime_ns else file_digest(path)
        records[key] = [st.st_size, st.st_mtime_ns, digest]
        h.update(digest.encode())
    return h.hexdigest(), records


def load_clip(path: Path, skeleton_path: Path) -> Motion:
    """The first motion of a clip file (SmartBody ``.skm`` played on the pack's ``.sk``)."""
    options = {"skeleton": str(skeleton_path)} if path.suffix.lower() == ".skm" and skeleton_path.suffix.lower() == ".sk" else {}
    asset = fileio.load(path, **options)
    if not asset.motions:
        raise InputError(path, None, "the clip file has no motion")
    return next(iter(asset.motions.values()))


def on_skeleton(motion: Motion, skeleton: Skeleton, file=None) -> Motion:
    """``motion`` moved onto ``skeleton`` (same joint names), so a pack's clips share one Skeleton."""
    if motion.skeleton is skeleton:
        return motion
    if motion.skeleton.names != skeleton.names:
        raise UnusableInputError(file, "the clip's joints differ from the pack skeleton's")
    return motion.replace(skeleton=skeleton)


@dataclass
class Pack:
    """A loaded pack: ``manifest``, ``analysis`` (the builder's JSON document, or None when unbuilt)."""

    manifest: Manifest
    analysis: dict | None

    @property
    def name(self) -> str:
        return self.manifest.name

    @property
    def version(self) -> str:
        return self.manifest.version

    @property
    def kind(self) -> str:
        return self.manifest.kind

    @property
    def built(self) -> bool:
        return self.analysis is not None

    def require_built(self) -> dict:
        if self.analysis is None:
            raise UsageError(f"pack {self.name!r} is not built (or its files changed): run 'infuse pack build {self.manifest.folder}'")
        return self.analysis

    @property
    def npz_path(self) -> Path:
        return self.manifest.analysis.with_suffix(".npz")

    @cached_property
    def _arrays(self):
        self.require_built()
        with np.load(self.npz_path, allow_pickle=False) as z:
            data = {k: z[k] for k in z.files}
        sk = Skeleton(tuple(str(n) for n in data["names"]), data["parents"], data["rest_translations"], data["rest_rotations"],
                      data["end_site_parents"], data["end_site_offsets"])
        return sk, data

    @property
    def skeleton(self) -> Skeleton:
        return self._arrays[0]

    @cached_property
    def motions(self) -> dict[str, Motion]:
        """Clip name -> Motion on :attr:`skeleton` (from the built arrays)."""
        sk, data = self._arrays
        out = {}
        bounds = data["bounds"]
        jt = data.get("joint_translations")
        for k, clip in enumerate(self.require_built()["clips"]):
            a, b = int(bounds[k]), int(bounds[k + 1])
            out[clip["name"]] = Motion(sk, float(clip["fps"]), data["rotations"][a:b], data["roots"][a:b],
                                       None if jt is None else jt[a:b], name=clip["name"])
        return out

    @cached_property
    def mapping(self) -> Mapping:
        doc = self.require_built()["mapping"]
        return Mapping.build(self.skeleton, doc["joints"], doc.get("confidence"), mapper=doc.get("mapper", "saved"))

    def clip_info(self, name: str) -> dict:
        for c in self.require_built()["clips"]:
            if c["name"] == name:
                return c
        raise KeyError(name)

    def tessellations(self) -> dict[str, Tessellation]:
        return {g: Tessellation.from_dict(t) for g, t in self.require_built()["tessellations"].items()}


def load_pack(source) -> Pack:
    """A :class:`Pack` from a manifest path, a pack folder, or an installed pack's name.

    Its analysis is loaded when the pack was built and none of its files changed since.
    """
    if isinstance(source, Pack):
        return source
    path = Path(source)
    if not path.exists():
        table = installed_packs()
        if str(source) not in table:
            raise UsageError(f"no pack {str(source)!r}: not a path and not installed; installed: {', '.join(sorted(table)) or 'none'}")
        path = Path(table[str(source)].manifest)
    manifest = read_manifest(path)
    analysis = None
    if manifest.analysis.is_file() and manifest.analysis.with_suffix(".npz").is_file():
        try:
            doc = json.loads(manifest.analysis.read_text(encoding="utf-8"))
        except (json.JSONDecodeError, UnicodeDecodeError) as exc:
            raise InputError(manifest.analysis, None, f"not a pack analysis: {exc}") from None
        if doc.get("format") == FORMAT_VERSION:
            digest, _ = fingerprint(manifest, doc.get("files"))
            if digest == doc.get("fingerprint"):
                analysis = doc
    return Pack(manifest, analysis)


def installed_packs() -> dict:
    """Installed behaviour packs: name -> :class:`~infuse.plugin_types.BehaviourPack`."""
    return registry.table("behaviour-pack")
