"""``infuse run SCENE -o OUTDIR``: realize a scene file (:mod:`infuse.scene.scenefile`) and write its results.

Writes into OUTDIR, each file atomically:

- ``<character>.glb`` per character (``--format bvh`` for BVH): its animation as one clip, ``scene``,
  with morph-weight tracks and the mesh kept; ``<character>.wav`` beside it when it speaks;
- ``feedback.xml`` (BML feedback, one element per line inside ``<feedback>``) and ``feedback.jsonl``
  (one JSON object per event), in the order the events happened;
- ``preview.png``: a filmstrip of the scene (``--preview`` .gif or .mp4 for an animation, ``none`` for
  no preview).
"""
from __future__ import annotations

import json
import math
import sys
from contextlib import contextmanager
from dataclasses import asdict
from pathlib import Path

from ..atomic import atomic_path
from ..errors import InputError, UsageError
from ..hookspecs import hookimpl
from ..plugin_types import Command
from ..render import Progress
from .scene import Scene
from .scenefile import SceneSpec, read_scene_file

PREVIEWS = ("png", "gif", "mp4", "none")


def build_scene(spec: SceneSpec, quiet: bool = True) -> Scene:
    """A :class:`Scene` with the characters, objects and blocks of ``spec`` (nothing evaluated yet)."""
    tts = dict(spec.tts)
    engine = tts.pop("engine", "espeak")
    with _place(spec, "generators"):
        scene = Scene(spec.fps, tts=engine, tts_settings=tts, idle=spec.idle, seed=spec.seed, quiet=quiet,
                      generators=spec.generators)
    # A name to face is where that character or object stands (it may come later in the file).
    places = {o.name: o.position for o in spec.objects} | {c.name: c.position for c in spec.characters}
    known = {name.lower() for name in places}
    for k, c in enumerate(spec.characters):
        if isinstance(c.facing, str) and c.facing.lower() not in known:
            raise InputError(spec.path, f"character[{k + 1}].facing", f"no character or object named {c.facing!r} in the scene")
        facing = places.get(c.facing, c.facing) if isinstance(c.facing, str) else c.facing
        with _place(spec, f"character[{k + 1}]"):
            scene.add_character(c.file, c.name, position=c.position, facing=facing, packs=c.packs, map=c.map,
                                mapper=c.mapper, voice=c.voice, idle=c.idle, format=c.format, units=c.units,
                                up_axis=c.up_axis)
    for k, o in enumerate(spec.objects):
        with _place(spec, f"object[{k + 1}]"):
            scene.add_object(o.name, o.position, o.size)
    for b in spec.blocks:
        if b.character is not None and scene.resolve_name(b.character) not in scene.characters:
            raise InputError(spec.path, f"{b.place}.character", f"no character {b.character!r} in the scene")
        with _place(spec, b.place):
            scene.bml(b.character, b.file if b.file is not None else b.bml, at=b.at)
    return scene


@contextmanager
def _place(spec: SceneSpec, place: str):
    """Usage errors and inline-BML errors as input errors at ``place`` of the scene file."""
    try:
        yield
    except UsageError as exc:
        raise InputError(spec.path, place, str(exc)) from None
    except InputError as exc:
        if exc.file not in (None, "<bml>"):
            raise
        raise InputError(spec.path, f"{place}{', ' + exc.place if exc.place else ''}", exc.problem) from None


def _arguments(p) -> None:
    p.add_argument("scene", metavar="SCENE", help="scene file (.toml or .xml)")
    p.add_argument("-o", "--output", required=True, metavar="OUTDIR", help="folder for the results (created if needed)")
    p.add_argument("--format", default="glb", help="character files: glb (default; keeps the mesh, morph tracks) or bvh")
    p.add_argument("--preview", choices=PREVIEWS, default="png", help="preview render: png filmstrip (default), gif, mp4 or none")
    p.add_argument("--strip", type=int, default=6, metavar="N", help="frames in the png filmstrip (default 6)")
    p.add_argument("--duration", type=float, help="seconds to realize (default: the scene file's, else until every block ends)")
    p.add_argument("--quiet", action="store_true", help="do not print warnings (they are in the feedback log)")


def run_scene(args) -> int:
    if args.format.lower().lstrip(".") not in ("glb", "gltf", "bvh"):
        raise UsageError(f"--format {args.format!r}: choose glb, gltf or bvh")
    if not 1 <= args.strip <= 60:
        raise UsageError("--strip must be between 1 and 60")
    spec = read_scene_file(args.scene)
    if args.duration is not None:
        if not (args.duration >= 0 and args.duration < 24 * 3600):
            raise UsageError("--duration must be a number of seconds >= 0")
        spec.duration = args.duration
    out = Path(args.output)
    if out.exists() and not out.is_dir():
        raise UsageError(f"-o {out}: exists and is not a folder")
    scene = build_scene(spec, quiet=args.quiet)
    frames = int(round(spec.duration * scene.fps)) if spec.duration is not None \
        else math.ceil(scene.end_time * scene.fps - 1e-6) + 1
    seconds = frames / scene.fps
    with Progress(frames, "realize") as bar:
        scene.run(seconds, progress=lambda done, total: bar.advance(done - bar.done))
    out.mkdir(parents=True, exist_ok=True)
    written = []
    suffix = "." + args.format.lower().lstrip(".")
    for name in scene.characters:
        written += scene.export(name, out / f"{name}{suffix}")
    written += write_feedback(scene, out)
    if args.preview != "none":
        path = out / f"preview.{args.preview}"
        written.append(scene.render(path, strip=args.strip if args.preview == "png" else None,
                                    fps=min(scene.fps, 20.0) if args.preview == "gif" else None))
    warnings = sum(e.kind == "warningFeedback" for e in scene.feedback.log)
    print(f"realized {Path(args.scene).name}: {len(scene.characters)} characters, {len(scene.scheduler.blocks)} blocks, "
          f"{frames} frames ({seconds:.2f} s at {scene.fps:g} fps), {warnings} warnings")
    for path in written:
        print(f"wrote {path}")
    sys.stdout.flush()
    return 0


def write_feedback(scene: Scene, folder: Path) -> list[Path]:
    """``feedback.xml`` and ``feedback.jsonl`` of everything the scene reported, in order."""
    xml, jsonl = folder / "feedback.xml", folder / "feedback.jsonl"
    with atomic_path(xml) as tmp:
        lines = [e.to_xml() for e in scene.feedback.log]
        tmp.write_text("<feedback>\n" + "".join(f"  {line}\n" for line in lines) + "</feedback>\n", encoding="utf-8")
    with atomic_path(jsonl) as tmp:
        tmp.write_text("".join(json.dumps({"kind": e.kind, **asdict(e)}, ensure_ascii=False) + "\n"
                               for e in scene.feedback.log), encoding="utf-8")
    return [xml, jsonl]


@hookimpl
def infuse_commands():
    return [Command("run", "realize a scene file (characters, objects, timed BML): glb per character, WAVs, "
                           "feedback log, preview", _arguments, run_scene)]
