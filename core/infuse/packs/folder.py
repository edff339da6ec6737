"""A self-contained pack folder: the skeleton and clips copied beside the manifest, named by relative paths.

A pack written this way can be moved, zipped or shipped in a wheel as it is: its manifest names no
file outside its folder. Clips go to ``clips/``, the skeleton beside the manifest (unless it is one
of the clips, as when a BVH clip's own hierarchy is the pack skeleton).
"""
from __future__ import annotations

import shutil
from pathlib import Path

from ..errors import UsageError
from .manifest import read_manifest, write_manifest

CLIPS = "clips"


def _unique_name(name: str, taken: set[str]) -> str:
    """``name``, or ``stem-2.ext``, ``stem-3.ext``... when two source files share a name."""
    path = Path(name)
    candidate, k = name, 1
    while candidate.lower() in taken:
        k += 1
        candidate = f"{path.stem}-{k}{path.suffix}"
    taken.add(candidate.lower())
    return candidate


def write_pack_folder(dest: str | Path, pack: dict, clips: list[dict]) -> Path:
    """Copy the files a manifest names into ``dest`` and write ``dest/manifest.toml``; returns its path.

    ``pack["skeleton"]`` and each ``clip["file"]`` are paths of existing files (absolute, or relative
    to the working folder); every other key is written as given. ``dest`` must not be the folder
    the files come from.
    """
    dest = Path(dest)
    sources = [Path(pack["skeleton"]).resolve()] + [Path(c["file"]).resolve() for c in clips]
    if any(s.parent == dest.resolve() for s in sources):
        raise UsageError(f"{dest}: the pack folder must not be the folder its clips come from; choose another output folder")
    (dest / CLIPS).mkdir(parents=True, exist_ok=True)
    taken: set[str] = {"manifest.toml", "analysis.json", "analysis.npz"}
    copied: dict[Path, str] = {}
    new_clips = []
    for clip, source in zip(clips, sources[1:]):
        if source not in copied:
            copied[source] = f"{CLIPS}/{_unique_name(source.name, taken)}"
            shutil.copyfile(source, dest / copied[source])
        new_clips.append({**clip, "file": copied[source]})
    skeleton = sources[0]
    if skeleton not in copied:
        copied[skeleton] = _unique_name(f"skeleton{skeleton.suffix.lower()}", taken)
        shutil.copyfile(skeleton, dest / copied[skeleton])
    return write_manifest(dest / "manifest.toml", {**pack, "skeleton": copied[skeleton]}, new_clips)


def copy_pack(source: str | Path, dest: str | Path, **changes) -> Path:
    """Copy the pack at ``source`` (folder or manifest) into ``dest`` as a self-contained folder.

    ``changes`` replace keys of the ``[pack]`` table (``name``, ``version``, ``description``...).
    The analysis is not copied: build the new folder. Returns the new manifest's path.
    """
    m = read_manifest(source)
    pack = {"name": m.name, "version": m.version, "kind": m.kind, "skeleton": str(m.skeleton),
            "analysis": m.analysis.name, "description": m.description or None, **m.extra}
    pack.update({k: v for k, v in changes.items() if v is not None})
    clips = [{"name": c.name, "file": str(c.file), "role": c.role, "tags": list(c.tags), "loop": c.loop, "hand": c.hand}
             for c in m.clips]
    return write_pack_folder(dest, pack, clips)
