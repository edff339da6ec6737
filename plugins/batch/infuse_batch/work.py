"""The worker side of a batch: run one unit, write its outputs, report what was done and what failed.

Everything here runs where the unit lands (in the job's own process, a pool process or a Dask
worker) and reads and writes files by path, so the inputs and the output folder must be visible
there at the same paths. A worker keeps the last :data:`~.jobs.CHARACTER_BLOCK` characters it
loaded, with their mappings, for the units that follow. Nothing raised by one character or one
clip stops the others: it becomes a :class:`Failure`.

Within a unit the clips of the chunk are grouped by skeleton; each group is mapped once (from its
first clip) and each (group, character) pair gets one retarget plan (the retargeter's
``prepare``, with the group's first clip for the default pose), which then serves every clip.
"""
from __future__ import annotations

import dataclasses
import hashlib
import os
import re
import socket
import time
from collections import OrderedDict
from dataclasses import dataclass, field
from pathlib import Path, PurePosixPath

import numpy as np

from infuse import fileio, registry
from infuse.asset import Asset, Character
from infuse.contacts import feet
from infuse.errors import InfuseError, InputError, MissingFeatureError, UnusableInputError
from infuse.grounding import foot_height, grounded, sole_depth
from infuse.mapping import Mapping, map_skeleton, sample_poses
from infuse.motion import carry_morph_weights
from infuse.plugin_types import normalized_extension

from .jobs import CHARACTER_BLOCK, PackUnit, Settings, Source, Unit
from .manifest import signature

#: The infusion cache of a character with packs, in its output folder.
INFUSION_FILE = "infusion.npz"


@dataclass
class Failure:
    """Something that was not produced: the ``file`` at fault, why, and the exit code that kind
    of problem has on the command line (2 malformed input, 3 unusable input, 1 a bug)."""

    file: str
    reason: str
    exit_code: int
    clip: str | None = None


@dataclass
class UnitResult:
    """What one unit did: ``done`` manifest entries, ``failures``, ``written`` output files,
    ``clips`` and ``frames`` (source clip-frames, counted once per character) retargeted,
    motion files without any clip (``empty``), the unit's wall and CPU seconds and the ``worker``
    that ran it (host:process id)."""

    pairs: int
    done: list[dict] = field(default_factory=list)
    failures: list[Failure] = field(default_factory=list)
    written: int = 0
    clips: int = 0
    frames: int = 0
    empty: list[str] = field(default_factory=list)
    wall: float = 0.0
    cpu: float = 0.0
    worker: str = ""


@dataclass
class _Loaded:
    """A character ready to receive clips."""

    asset: Asset
    mapping: Mapping
    signature: dict
    sole: float  # how far its soles reach below its feet's joints (infuse.grounding.sole_depth)


_characters: OrderedDict = OrderedDict()


def warm() -> None:
    """Load the plugins now (a pool process runs this once, before its first unit)."""
    for table in (registry.readers, registry.writers, registry.mappers, registry.retargeters):
        table()


def failure(file, exc: BaseException, clip: str | None = None) -> Failure:
    """A :class:`Failure` from an exception: the file the error names (else ``file``) and its problem."""
    if isinstance(exc, InputError):
        return Failure(exc.file or str(file), ": ".join(p for p in (exc.place, exc.problem) if p), 2, clip)
    if isinstance(exc, UnusableInputError):
        return Failure(exc.file or str(file), exc.problem, exc.exit_code, clip)
    if isinstance(exc, InfuseError):
        return Failure(str(file), str(exc), exc.exit_code, clip)
    return Failure(str(file), f"internal error (a bug): {type(exc).__name__}: {exc}", 1, clip)


def _character(source: Source, settings: Settings) -> _Loaded:
    st = os.stat(source.path)
    key = (source.path, st.st_size, st.st_mtime_ns, settings.mapper)
    if key in _characters:
        _characters.move_to_end(key)
        return _characters[key]
    sig = signature(source.path)
    asset = fileio.load(source.path)
    mapping = map_skeleton(asset, mapper=settings.mapper)
    loaded = _Loaded(asset, mapping, sig, sole_depth(asset, feet(asset.skeleton, mapping, file=asset.path)))
    _characters[key] = loaded
    while len(_characters) > CHARACTER_BLOCK:
        _characters.popitem(last=False)
    return loaded


def _keeps_mesh(path: str) -> bool:
    """Whether the writer of .glb files also reads this file's type (so it can write the character
    back with its mesh)."""
    glb = next((w for w in registry.writers().values() if ".glb" in w.extensions), None)
    return glb is not None and normalized_extension(path) in glb.extensions


def _fingerprint(skeleton) -> str:
    h = hashlib.sha256("\0".join(skeleton.names).encode())
    for a in (skeleton.parents, skeleton.rest_translations, skeleton.rest_rotations, skeleton.end_site_parents,
              skeleton.end_site_offsets):
        h.update(np.ascontiguousarray(a).tobytes())
    return h.hexdigest()


def _source_mapping(asset: Asset, mapper: str | None) -> Mapping:
    """A motion file's mapping over its whole skeleton, as ``infuse retarget`` makes it: a file
    animating only some joints still moves the others through them."""
    return map_skeleton(asset.skeleton, mapper=mapper, pose=sample_poses(asset), meta=asset.meta, humanoid=asset.humanoid,
                        file=asset.path)


def _retargeter(name: str | None):
    if not registry.retargeters():
        raise MissingFeatureError(None, "no retargeter installed: install infuse-anim-retarget")
    return registry.get("retargeter", name)


def _planner(retargeter, clip, src_map, loaded: _Loaded, source_file, target_file):
    """``(motion) -> Motion`` for clips on ``clip``'s skeleton onto a loaded character."""
    target_clip = next(iter(loaded.asset.motions.values()), None)
    if retargeter.prepare is not None:
        return retargeter.prepare(clip.skeleton, src_map, loaded.asset.skeleton, loaded.mapping, source_motion=clip,
                                  target_motion=target_clip, source_file=source_file, target_file=target_file,
                                  target_meshes=_meshes_if_readable(loaded.asset))
    return lambda motion: retargeter.retarget(motion, src_map, loaded.asset.skeleton, loaded.mapping)


def _meshes_if_readable(asset: Asset) -> tuple:
    """The character's meshes (soles of feet without a ball joint), or none when they cannot be decoded."""
    try:
        return asset.meshes
    except (InputError, UnusableInputError):  # malformed, or compressed with a codec not installed
        return ()


def _file_name(name: str) -> str:
    return re.sub(r"[^\w.\-]+", "_", name).strip("._") or "clip"


def _writable(loaded: _Loaded, name: str, motion) -> Asset:
    """The character with only this clip (its own clips left out), the clip standing on the ground
    (its feet's lowest point at y = 0)."""
    motion = grounded(motion, foot_height(loaded.asset, loaded.mapping, motion, loaded.sole))
    return dataclasses.replace(loaded.asset, motions={name: motion})


def run_unit(unit: Unit | PackUnit) -> UnitResult:
    """Run one unit (see :mod:`.jobs`); never raises for a bad input."""
    wall, cpu = time.perf_counter(), time.process_time()
    result = UnitResult(unit.pairs, worker=f"{socket.gethostname()}:{os.getpid()}")
    try:
        if isinstance(unit, PackUnit):
            _infuse(unit, result)
        else:
            _retarget(unit, result)
    except Exception as exc:  # a failure outside any one input (e.g. no retargeter): every pair fails
        result.failures.append(failure(unit.character.path if isinstance(unit, PackUnit) else unit.out, exc))
    result.wall, result.cpu = time.perf_counter() - wall, time.process_time() - cpu
    return result


def _once(cache: dict, key, make):
    """``make()`` once per key; an exception it raised is kept and raised again on every later use."""
    if key not in cache:
        try:
            cache[key] = make()
        except Exception as exc:
            cache[key] = exc
    if isinstance(cache[key], Exception):
        raise cache[key]
    return cache[key]


def _retarget(unit: Unit, result: UnitResult) -> None:
    settings = unit.settings
    retargeter = _retargeter(settings.retargeter)
    characters: dict[int, _Loaded] = {}
    for k in sorted({k for k, _ in unit.todo}):
        try:
            characters[k] = _character(unit.characters[k], settings)
        except Exception as exc:
            result.failures.append(failure(unit.characters[k].path, exc))
    wanted = {m for k, m in unit.todo if k in characters}
    if not wanted:
        return
    # Every file of the chunk is read, wanted or not, so that each group's first clip (its
    # mapping and default pose) is the same on every run.
    assets: dict[int, Asset] = {}
    signatures: dict[int, dict] = {}
    for m, source in enumerate(unit.motions):
        try:
            if m in wanted:
                signatures[m] = signature(source.path)
            assets[m] = fileio.load(source.path)
        except Exception as exc:
            if m in wanted:
                result.failures.append(failure(source.path, exc))
    first_of: dict[str, int] = {}  # skeleton fingerprint -> first file of the chunk with it
    group_of: dict[int, str] = {}
    for m, asset in assets.items():
        if not asset.motions:
            if m in wanted:
                result.empty.append(unit.motions[m].path)
            continue
        key = _fingerprint(asset.skeleton) + _fingerprint(next(iter(asset.motions.values())).skeleton)
        first_of.setdefault(key, m)
        group_of[m] = key
    made: dict = {}  # source mappings per group, plans per (character, group)
    for k, m in unit.todo:
        if k not in characters or m not in group_of:
            continue
        key = group_of[m]
        first = assets[first_of[key]]
        try:
            src_map = _once(made, key, lambda: _source_mapping(first, settings.mapper))
            plan = _once(made, (k, key), lambda: _planner(retargeter, next(iter(first.motions.values())), src_map,
                                                          characters[k], first.path, unit.characters[k].path))
        except Exception as exc:
            result.failures.append(failure(unit.motions[m].path, exc))
            continue
        _write_clips(unit, k, m, characters[k], assets[m], plan, signatures[m], result)


def _write_clips(unit: Unit, k: int, m: int, loaded: _Loaded, asset: Asset, plan, sig: dict, result: UnitResult) -> None:
    character, source, out = unit.characters[k], unit.motions[m], Path(unit.out)
    fmt = unit.settings.format or ("glb" if _keeps_mesh(character.path) else "bvh")
    outputs, frames, ok = [], 0, True
    for clip_name, clip in asset.motions.items():
        name = clip.name or clip_name or Path(source.path).stem
        stem = source.name if len(asset.motions) == 1 else f"{source.name}/{_file_name(name)}"
        rel = f"{character.name}/{stem}.{fmt}"
        try:
            motion = carry_morph_weights(plan(clip).replace(name=name), clip, loaded.asset.morph_targets)
            fileio.save(_writable(loaded, name, motion), out / rel)
        except Exception as exc:
            result.failures.append(failure(source.path, exc, clip=name))
            ok = False
            continue
        outputs.append(rel)
        frames += clip.num_frames
        result.written += 1
        result.clips += 1
    result.frames += frames
    if ok:
        result.done.append({"character": character.name, "input": source.name, "settings": unit.settings.key(),
                            "files": {"character": loaded.signature, "input": sig}, "outputs": outputs, "frames": frames})


def _infuse(unit: PackUnit, result: UnitResult) -> None:
    from infuse.packs import infuse_character

    from .manifest import packs_input

    settings, source = unit.settings, unit.character
    try:
        loaded = _character(source, settings)
        rel = f"{source.name}/{INFUSION_FILE}"
        infusion = infuse_character(Character(Path(source.path).stem, loaded.asset), list(settings.packs),
                                    mapping=loaded.mapping, cache=Path(unit.out) / rel, retargeter=settings.retargeter)
    except Exception as exc:
        result.failures.append(failure(source.path, exc))
        return
    clips = [c for space in infusion.spaces.values() for c in space.clips.values()]
    frames = sum(c.motion.num_frames for c in clips)
    outputs = [rel, str(PurePosixPath(rel).with_suffix(".json"))]
    result.written += len(outputs)
    result.clips += len(clips)
    result.frames += frames
    result.done.append({"character": source.name, "input": packs_input(settings), "settings": settings.key(),
                        "files": {"character": loaded.signature, "packs": unit.fingerprints}, "outputs": outputs,
                        "frames": frames})
