"""``infuse render``: previews of character and motion files as PNG, GIF or MP4: the character's
shaded skinned mesh when the file has one, else a stick figure (``--style``)."""
from __future__ import annotations

import re
from pathlib import Path
from typing import TYPE_CHECKING

from .. import fileio, registry
from ..cli.builtin import add_read_options, read_options
from ..errors import InfuseError, InputError, UsageError
from ..hookspecs import hookimpl
from ..mapping import DEFAULT_MAPPER, map_skeleton
from ..plugin_types import Command
from .camera import VIEWS, Camera
from .output import check_suffix, render
from .scene import STYLES, Figure, drawable_meshes, sides_from_mapping

if TYPE_CHECKING:
    from ..motion import Motion

MAX_SIDE = 8192
#: Mapping entries below this confidence are ringed by ``--canonical``.
LOW_CONFIDENCE = 0.5


def parse_size(text: str) -> tuple[int, int]:
    """``"640x480"`` -> (640, 480); :class:`UsageError` unless both sides are 16..8192 pixels."""
    match = re.fullmatch(r"\s*(\d+)\s*[xX]\s*(\d+)\s*", text or "")
    if not match:
        raise UsageError(f"--size {text!r}: expected WIDTHxHEIGHT in pixels, e.g. 640x480")
    w, h = int(match[1]), int(match[2])
    if not (16 <= w <= MAX_SIDE and 16 <= h <= MAX_SIDE):
        raise UsageError(f"--size {text}: each side must be between 16 and {MAX_SIDE} pixels")
    return w, h


def _arguments(p) -> None:
    p.add_argument("files", nargs="+", metavar="FILE", help="character or motion files; several render side by side")
    p.add_argument("-o", "--output", required=True, help="output file: .png (still or --strip), .gif or .mp4")
    p.add_argument("--style", choices=STYLES, default="auto",
                   help="mesh: the shaded skinned mesh; stick: the skeleton; auto (default): the mesh when the file has one")
    p.add_argument("--clip", help="name of the clip to play (default: each file's first clip, or its rest pose)")
    p.add_argument("--frame", type=int, help="PNG: the frame to draw (0-based, of the first file)")
    p.add_argument("--start", type=float, help="first time to draw, seconds")
    p.add_argument("--end", type=float, help="last time to draw, seconds")
    p.add_argument("--strip", type=int, metavar="N", help="PNG: a filmstrip of N frames spread over the clip")
    p.add_argument("--names", action="store_true", help="label every joint with its name")
    p.add_argument("--canonical", action="store_true",
                   help=f"label mapped joints with their canonical names and ring those mapped with confidence < {LOW_CONFIDENCE}")
    p.add_argument("--mapper", help=f"mapper plugin for left/right colours and --canonical (default {DEFAULT_MAPPER}, when installed)")
    p.add_argument("--map", dest="map_file", metavar="MAP.json", help="saved joint map to use instead of (or to complete) the mapper's")
    p.add_argument("--highlight", action="append", default=[], metavar="JOINT",
                   help="ring a joint (repeatable, or comma-separated names)")
    p.add_argument("--view", choices=list(VIEWS), default="three-quarter", help="where the camera looks from")
    p.add_argument("--perspective", action="store_true", help="perspective instead of orthographic projection")
    p.add_argument("--size", help="WIDTHxHEIGHT of the image (of one tile with --strip)")
    p.add_argument("--fps", type=float, help="GIF/MP4 frame rate (default: the clip's; GIF at most 25)")
    follow = p.add_mutually_exclusive_group()
    follow.add_argument("--follow", dest="follow", action="store_true", default=None,
                        help="keep the root centred (default: when it travels more than twice its height; half of it for --strip)")
    follow.add_argument("--no-follow", dest="follow", action="store_false", help="a still camera framing every frame")
    p.add_argument("--overlay", action="store_true", help="draw all files in one panel instead of side by side")
    p.add_argument("--title", help="text at the top (default: the file name)")
    p.add_argument("--progress", action="store_true", default=None, help="show a progress bar even when stderr is not a terminal")
    add_read_options(p)


def _mapping(asset, args):
    """The asset's canonical mapping: required when asked for, else best effort (``None`` when unavailable).

    Without a mapping, left and right come from geometry (see :func:`~infuse.render.scene.default_sides`).
    """
    if args.canonical or args.mapper or args.map_file:
        return map_skeleton(asset, mapper=args.mapper, saved_map=args.map_file)
    if registry.default_name("mapper")[0] not in registry.mappers():
        return None
    try:
        return map_skeleton(asset)
    except (InfuseError, ValueError):  # not a humanoid, or a rig the mapper cannot read: colour by geometry
        return None


def _figure(path: Path, args, many: bool, highlight: list[str]) -> Figure:
    asset = fileio.load(path, format=args.read_format, **read_options(args))
    if args.clip is not None:
        if args.clip not in asset.motions:
            known = ", ".join(repr(n) for n in asset.motions) or "none"
            raise InputError(path, f"clip {args.clip!r}", f"no such clip; clips: {known}")
        motion: Motion | None = asset.motions[args.clip]
    else:
        motion = next(iter(asset.motions.values()), None)
    if motion is not None and motion.num_frames == 0:
        motion = None  # an empty clip: show the rest pose
    clip = motion.name if motion is not None and motion.name else ("rest pose" if motion is None else "clip")
    label = (path.name if clip == path.stem else f"{path.name}: {clip}") if many else clip
    ringed = [n for n in highlight if n in asset.skeleton.index]
    names: bool | dict[str, str] | None = True if args.names else None
    mapping = _mapping(asset, args)
    sides = None
    if mapping is not None:
        sides = sides_from_mapping(asset.skeleton, mapping)
        if args.canonical:
            mapped = mapping.mapped()
            names = {joint: canonical for canonical, joint in reversed(list(mapped.items()))}
            ringed += [joint for canonical, joint in mapped.items() if mapping.confidence.get(canonical, 1.0) < LOW_CONFIDENCE]
    options = dict(label=label, names=names, highlight=ringed or None, sides=sides)
    meshes = drawable_meshes(asset, asset.skeleton if motion is None else motion.skeleton, args.style, path)
    if motion is None:
        return Figure.from_skeleton(asset.skeleton, meshes=meshes, **options)
    return Figure.from_motion(motion, meshes=meshes, **options)


def _run(args) -> int:
    out = Path(args.output)
    kind = check_suffix(out)
    if args.frame is not None and (args.start is not None or args.end is not None):
        raise UsageError("--frame and --start/--end exclude each other")
    if args.frame is not None and kind != ".png":
        raise UsageError("--frame draws one still image: use a .png output")
    if args.strip is not None and kind != ".png":
        raise UsageError("--strip makes a filmstrip image: use a .png output")
    if args.strip is not None and not 1 <= args.strip <= 64:
        raise UsageError("--strip N: N must be between 1 and 64")
    size = parse_size(args.size) if args.size else None
    highlight = [n.strip() for item in args.highlight for n in item.split(",") if n.strip()]
    paths = [Path(f) for f in args.files]
    figures = [_figure(p, args, len(paths) > 1, highlight) for p in paths]
    known = {n for f in figures for n in f.skeleton.names}
    missing = [n for n in highlight if n not in known]
    if missing:
        raise UsageError(f"--highlight: no file has a joint named {missing[0]!r}")
    camera = Camera(view=args.view, projection="perspective" if args.perspective else "orthographic", follow=args.follow)
    title = args.title if args.title is not None else (paths[0].name if len(paths) == 1 else "")
    render(figures, out, frame=args.frame, start=args.start, end=args.end, strip=args.strip, fps=args.fps, size=size,
           camera=camera, overlay=args.overlay, title=title, progress=args.progress)
    print(f"wrote {out}")
    return 0


@hookimpl
def infuse_commands():
    return [Command("render", "draw the mesh or skeleton of character/motion files as PNG, filmstrip, GIF or MP4",
                    _arguments, _run)]
