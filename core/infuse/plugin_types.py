"""The small descriptor objects plugins hand to infuse through the hooks in :mod:`infuse.hookspecs`."""
from __future__ import annotations

from dataclasses import dataclass
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
    skeleton, for its default pose), ``target_motion``, ``source_file``, ``target_file`` and
    ``target_meshes`` (the target's skinned meshes, for the soles of feet without a ball joint): accept
    ``**options`` to take those you do not use.
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
class ControllerFactory:
    """A controller kind of the runtime: ``factory(**settings) -> Controller`` builds one (usually the
    :class:`~infuse.runtime.Controller` subclass itself).

    Realizing BML (see :mod:`infuse.stage`; :func:`infuse.registry.realizer` picks the controller of a
    behaviour kind):

    - ``realizes``: the behaviour kinds (an :class:`~infuse.bml.Activation`'s ``controller``) it
      realizes; empty: the kind of its own name. Listing a kind named after another controller
      replaces that one.
    - ``realize(activation, stage) -> Activity | None`` (optional): realizes an activation in a scene
      through the :class:`~infuse.stage.Stage`: builds controllers, asks where things are, starts
      activities, reports what it cannot show.
    - ``from_bml(parameters, runtime, character, activation) -> Controller | None`` (optional) builds it
      from an activation when there is no ``realize``, played from the activation's start to its end;
      without it the activation's parameters go to ``factory``.
    - ``idle(index, seed) -> dict`` (optional) makes it an idle default: every character of a scene
      plays it from the start with these settings (``index``: the character's place in the scene,
      ``seed``: the scene's), until BML realizes the same controller on it.
    - ``prepare(activation, stage)`` (optional): works out ahead, on another thread, what realizing the
      activation will cost most (a walk's path plan), from what the stage holds now, and keeps it where
      ``realize`` finds it; a live scene calls it as BML arrives, so that its loop only looks it up. It
      only reads the stage, and ``realize`` gives the same result whether it ran or not (it uses what was
      kept only when it was worked out from the very same inputs).
    - ``warm_up(stage, character) -> Controller | None`` (optional): a controller whose short play on a
      scratch copy of the character prepares what its first real activity would (pack bindings, clip
      tables); a live scene plays it before it starts, so that the first one does not stall a frame.
    """

    name: str
    factory: Callable[..., Any]
    description: str = ""
    from_bml: Callable[..., Any] | None = None
    realize: Callable[..., Any] | None = None
    realizes: tuple[str, ...] = ()
    idle: Callable[[int, int], dict] | None = None
    warm_up: Callable[[Any, str], Any] | None = None
    prepare: Callable[[Any, Any], None] | None = None

    @property
    def behaviour_kinds(self) -> tuple[str, ...]:
        """The behaviour kinds it realizes (``realizes``, else its own name)."""
        return self.realizes or (self.name,)


@dataclass(frozen=True)
class BehaviourPack:
    """An installed behaviour pack: ``manifest`` is the path of its ``manifest.toml``; ``load() -> Pack``."""

    name: str
    load: Callable[[], Any]
    description: str = ""
    manifest: str = ""


@dataclass(frozen=True)
class TTSEngine:
    """A text-to-speech engine: ``factory(**settings)`` builds one, with
    ``synthesize(text, wav_path=None) -> infuse.speech.Utterance``; ``settings`` names what it accepts."""

    name: str
    factory: Callable[..., Any]
    description: str = ""
    settings: tuple[str, ...] = ()


@dataclass(frozen=True)
class BMLBehaviour:
    """Handles the BML ``elements`` (names as :mod:`infuse.bml.names` writes them: ``"head"``,
    ``"sbm:reach"``, ``"{uri}local"``): ``plan(behaviour, context) -> BehaviourPlan``.

    ``attributes``: the attribute names it understands (others are reported as unsupported; ``None``
    accepts all). ``priority``: the highest takes an element several plugins handle (default 0).
    """

    name: str
    plan: Callable[..., Any]
    description: str = ""
    elements: tuple[str, ...] = ()
    attributes: frozenset[str] | None = None
    priority: int = 0


@dataclass(frozen=True)
class BMLGenerator:
    """Adds behaviours to a BML block before it is scheduled (nonverbal behaviour from speech...):
    ``generate(block, context) -> infuse.bml.Generation``, see :mod:`infuse.bml.generate`.

    A block turns it on or off with the attribute ``infuse:NAME="true"``/``"false"`` in the namespace
    ``urn:infuse:bml`` (a scheduler or scene may turn it on for every block); ``attributes``: the other
    ``infuse:`` block attributes it reads (names without the prefix).
    """

    name: str
    generate: Callable[..., Any]
    description: str = ""
    attributes: frozenset[str] = frozenset()


def normalized_extension(path: str | Path) -> str:
    """The lower-case suffix of ``path`` (``".glb"``), with ``".skeleton.xml"`` style double suffixes kept;
    a name that is only a suffix (``".bvh"``) has that suffix."""
    name = Path(path).name.lower()
    for double in (".skeleton.xml",):
        if name.endswith(double):
            return double
    return Path(name).suffix or (name if name.count(".") == 1 and name.startswith(".") and len(name) > 1 else "")
