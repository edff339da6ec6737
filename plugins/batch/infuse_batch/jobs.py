"""What a batch is made of: the characters, the motion files, their names in the output tree, and
the work units handed to workers.

A unit is small to send (paths and names, never file contents) and big enough to be worth a task:
a chunk of motion files from one folder (at most :data:`CHUNK_FILES` files and :data:`CHUNK_BYTES`
bytes; clips in one folder usually share a skeleton, so the worker maps it and plans the retarget
once for them all) times a block of at most :data:`CHARACTER_BLOCK` characters. Chunks are cut
from the sorted file list alone, so the same inputs make the same units whatever runs them and
whatever was already done: an output never depends on the number of workers or on a resume.
"""
from __future__ import annotations

import glob
import os
from dataclasses import dataclass
from pathlib import Path, PurePosixPath
from typing import Iterable

from infuse import registry
from infuse.errors import UsageError
from infuse.plugin_types import normalized_extension

#: Most motion files in one unit.
CHUNK_FILES = 8
#: Most bytes of motion files in one unit (a long clip gets a unit of its own).
CHUNK_BYTES = 4 << 20
#: Most characters in one unit (workers keep this many characters loaded and mapped).
CHARACTER_BLOCK = 8
#: Output formats: the character's mesh is kept in glb; bvh carries the character's joints only.
FORMATS = ("glb", "bvh")


@dataclass(frozen=True)
class Source:
    """An input file: ``path`` (absolute) and ``name``, its place in the output tree (POSIX, no suffix)."""

    path: str
    name: str


@dataclass(frozen=True)
class Settings:
    """How every unit of a batch runs: output ``format`` (``None``: glb for glTF characters, bvh for
    the others), ``mapper`` and ``retargeter`` plugin names, behaviour ``packs``."""

    format: str | None = None
    mapper: str | None = None
    retargeter: str | None = None
    packs: tuple[str, ...] = ()

    def key(self) -> dict:
        """What an output depends on besides its input files (stored in the manifest)."""
        return {"format": self.format, "mapper": self.mapper or registry.default_name("mapper")[0],
                "retargeter": self.retargeter or registry.default_name("retargeter")[0], "packs": list(self.packs)}


@dataclass(frozen=True)
class Unit:
    """One task: retarget each ``motions[m]`` onto each ``characters[k]`` for the ``(k, m)`` in
    ``todo`` (every file of the chunk is read, so plans come from the same clips on a resume)."""

    characters: tuple[Source, ...]
    motions: tuple[Source, ...]
    todo: tuple[tuple[int, int], ...]
    settings: Settings
    out: str

    @property
    def pairs(self) -> int:
        return len(self.todo)


@dataclass(frozen=True)
class PackUnit:
    """One task: infuse ``character`` with the settings' packs and cache the result;
    ``fingerprints``: pack name -> version and fingerprint of its analysis (for the manifest)."""

    character: Source
    settings: Settings
    out: str
    fingerprints: dict

    @property
    def pairs(self) -> int:
        return 1


def readable_extensions() -> set[str]:
    return registry.extensions("reader")


def _files_under(folder: Path, extensions: set[str], exclude: Path | None) -> list[Path]:
    found = []
    for root, dirs, files in os.walk(folder):
        here = Path(root)
        dirs[:] = sorted(d for d in dirs if not d.startswith(".") and (exclude is None or (here / d).resolve() != exclude))
        found += [here / f for f in files if not f.startswith(".") and normalized_extension(f) in extensions]
    return sorted(found)


def _expand(spec: str, extensions: set[str], exclude: Path | None, what: str) -> list[tuple[Path, Path]]:
    """(file, root) pairs for a file, a folder (searched recursively) or a glob; ``root`` is what
    the file's output name is relative to."""
    path = Path(spec).expanduser()
    if path.is_dir():
        return [(f, path) for f in _files_under(path, extensions, exclude)]
    if path.is_file():
        return [(path, path.parent)]
    matches = sorted(Path(m) for m in glob.glob(str(path), recursive=True))
    if not matches:
        raise UsageError(f"{spec}: no such {what} file, folder or glob match")
    out = []
    for m in matches:
        out += [(f, m) for f in _files_under(m, extensions, exclude)] if m.is_dir() else [(m, m.parent)]
    return [(f, r) for f, r in out if normalized_extension(f) in extensions]


def _names(files: list[tuple[Path, Path]], prefix_roots: bool) -> list[str]:
    """Output names: paths relative to their roots (under the root's own name with
    ``prefix_roots``) without suffix; with the suffix where two files would otherwise share a name
    (``walk.bvh`` and ``walk.skm``)."""
    def rel(f: Path, root: Path, keep_suffix: bool) -> str:
        r = PurePosixPath(f.relative_to(root).as_posix())
        if not keep_suffix:
            r = r.with_name(r.name[: -len(normalized_extension(r.name))] if normalized_extension(r.name) else r.name)
        return str(PurePosixPath(root.name) / r) if prefix_roots else str(r)

    plain = [rel(f, r, False) for f, r in files]
    counts: dict[str, int] = {}
    for n in plain:
        counts[n] = counts.get(n, 0) + 1
    return [rel(f, r, True) if counts[n] > 1 else n for (f, r), n in zip(files, plain)]


def _sources(specs: Iterable[str], what: str, exclude: Path | None = None) -> list[Source]:
    extensions = readable_extensions()
    files: list[tuple[Path, Path]] = []
    seen: set[Path] = set()
    for spec in specs:
        for f, root in _expand(str(spec), extensions, exclude, what):
            resolved = f.resolve()
            if exclude is not None and exclude in resolved.parents:
                continue
            if resolved not in seen:  # named by where it was found, which may be a link
                seen.add(resolved)
                files.append((f.absolute(), root.absolute()))
    names = _names(files, False)
    if len(set(names)) != len(names):  # the same relative path under two roots
        names = _names(files, True)
    if len(set(names)) != len(names):
        raise UsageError(f"two {what} files would share an output name; give them different names or folders")
    return [Source(str(f), n) for (f, _), n in zip(files, names)]


def character_sources(specs: Iterable[str]) -> list[Source]:
    """Characters from files, folders (every readable file inside) or globs; named by file stem
    (with the folder where two stems clash)."""
    specs = list(specs)
    if not specs:
        raise UsageError("name at least one character file, folder or glob")
    found = _sources(specs, "character")
    stems = [PurePosixPath(s.name).name for s in found]
    if len(set(stems)) == len(stems):
        found = [Source(s.path, stem) for s, stem in zip(found, stems)]
    if not found:
        raise UsageError(f"{', '.join(specs)}: no readable character file")
    return found


def motion_sources(specs: Iterable[str], out: Path) -> list[Source]:
    """Motion files from files, folders (recursively, skipping hidden ones and the output folder)
    or globs; named by their path below the folder given (under the folder's name where two
    folders hold the same path)."""
    specs = list(specs)
    found = _sources(specs, "motion", out.resolve())
    if not found:
        raise UsageError(f"{', '.join(specs)}: no readable motion file")
    return found


def chunks(motions: list[Source]) -> list[tuple[Source, ...]]:
    """Consecutive files of one folder, at most :data:`CHUNK_FILES` files and :data:`CHUNK_BYTES` bytes."""
    out: list[tuple[Source, ...]] = []
    current: list[Source] = []
    size = 0
    for s in motions:
        n = _size(s.path)
        if current and (Path(s.path).parent != Path(current[0].path).parent or len(current) >= CHUNK_FILES
                        or size + n > CHUNK_BYTES):
            out.append(tuple(current))
            current, size = [], 0
        current.append(s)
        size += n
    if current:
        out.append(tuple(current))
    return out


def _size(path: str) -> int:
    try:
        return os.stat(path).st_size
    except OSError:
        return 0


def motion_units(characters: list[Source], motions: list[Source], done, settings: Settings, out: Path) -> list[Unit]:
    """The units of a motion batch, character block by block (workers keep a block's characters
    loaded), the biggest chunks first within a block (so no long unit is left for the end).
    ``done(character, motion) -> bool`` leaves out what an earlier run already wrote."""
    units: list[Unit] = []
    for b in range(0, len(characters), CHARACTER_BLOCK):
        block = characters[b:b + CHARACTER_BLOCK]
        pending = []
        for chunk in chunks(motions):
            todo = tuple((k, m) for k, c in enumerate(block) for m, s in enumerate(chunk) if not done(c, s))
            if not todo:
                continue
            used = sorted({k for k, _ in todo})
            remap = {k: i for i, k in enumerate(used)}
            cost = sum(_size(s.path) for s in chunk) * len(used)
            pending.append((cost, tuple(block[k] for k in used), chunk, tuple((remap[k], m) for k, m in todo)))
        pending.sort(key=lambda p: -p[0])
        units += [Unit(chars, chunk, todo, settings, str(out)) for _, chars, chunk, todo in pending]
    return units


def pack_units(characters: list[Source], done, settings: Settings, out: Path, fingerprints: dict) -> list[PackUnit]:
    """One unit per character not yet infused with the settings' packs."""
    todo = [c for c in characters if not done(c, None)]
    return [PackUnit(c, settings, str(out), fingerprints) for c in todo]
