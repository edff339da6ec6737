"""The small descriptor objects plugins hand to infuse through the hooks in :mod:`infuse.hookspecs`."""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable


@dataclass(frozen=True)
class Reader:
    """Reads files with one of ``extensions`` (lower case, with the dot) into an :class:`~infuse.asset.Asset`.

    ``read(path: Path, **options) -> Asset``. Options every reader accepts: ``units`` (override the
    file's length unit, a key of :data:`infuse.conventions.UNIT_SCALES`) and ``up_axis`` ("Y"/"Z").
    Malformed input raises :class:`~infuse.errors.InputError`.
    """

    name: str
    extensions: tuple[str, ...]
    read: Callable[..., Any]
    description: str = ""


@dataclass(frozen=True)
class Writer:
    """Writes an :class:`~infuse.asset.Asset` to a file with one of ``extensions``.

    ``write(asset, path: Path, **options) -> None``. infuse passes a temporary path with the same
    suffix and renames it when ``write`` returns, so writers need not be atomic themselves.
    """

    name: str
    extensions: tuple[str, ...]
    write: Callable[..., None]
    description: str = ""


@dataclass(frozen=True)
class Mapper:
    """Maps a skeleton to canonical joint names: ``map(skeleton, **options) -> Mapping``."""

    name: str
    map: Callable[..., Any]
    description: str = ""


@dataclass(frozen=True)
class Retargeter:
    """Transfers a motion between skeletons through their mappings.

    ``retarget(motion, source_mapping, target_skeleton, target_mapping, **options) -> Motion``.

    ``prepare`` (optional) does the per-pair work once for many clips on one source skeleton:
    ``prepare(source_skeleton, source_mapping, target_skeleton, target_mapping, **options)`` returns
    a callable ``(motion) -> Motion``; ``options`` may name ``source_motion`` (a clip on the source
    skeleton, for its default pose), ``target_motion``, ``source_file`` and ``target_file``.
    """

    name: str
    retarget: Callable[..., Any]
    description: str = ""
    prepare: Callable[..., Any] | None = None


@dataclass(frozen=True)
class Command:
    """A CLI sub-command: ``add_arguments(parser)`` declares it, ``run(args) -> int`` executes it."""

    name: str
    help: str
    add_arguments: Callable[[Any], None]
    run: Callable[[Any], int]


@dataclass(frozen=True)
class Component:
    """A named runtime part (controller, behaviour pack, TTS engine, BML behaviour).

    ``factory`` builds it; ``info`` holds kind-specific facts (a pack's manifest path, the BML
    element names a behaviour handles...).
    """

    name: str
    factory: Callable[..., Any]
    description: str = ""
    info: dict = field(default_factory=dict)


def normalized_extension(path: str | Path) -> str:
    """The lower-case suffix of ``path`` (``".glb"``), with ``".skeleton.xml"`` style double suffixes kept;
    a name that is only a suffix (``".bvh"``) has that suffix."""
    name = Path(path).name.lower()
    for double in (".skeleton.xml",):
        if name.endswith(double):
            return double
    return Path(name).suffix or (name if name.count(".") == 1 and name.startswith(".") and len(name) > 1 else "")
