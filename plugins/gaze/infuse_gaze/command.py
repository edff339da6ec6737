"""``infuse gaze CHARACTER -o gaze.gif``: a character following a moving target with its gaze, rendered.

The target moves along ``--target-path`` (points ``x,y,z`` in metres, core frame, separated by ``;``,
visited at constant speed and back to the first) or, by default, along an ellipse in front of the
character at eye height. The render draws the target (a sphere), where the eyes (or the head) actually
point (a cross at the target's distance) and the gaze ray. Other controllers can run at the same time
(``--saccades``, ``--blink``, ``--breathing``) when their plugins are installed.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from infuse import Character, fileio, quaternions as quat
from infuse.cli.builtin import add_read_options, read_options
from infuse.cli.map_command import add_mapping_options, mapping_from_args
from infuse.errors import InputError, UsageError
from infuse.plugin_types import Command
from infuse.render import Camera, Figure, Marker, render, sides_from_mapping
from infuse.render.command import parse_size
from infuse.render.camera import VIEWS
from infuse.runtime import Clip, Runtime, TrackTarget, controller
from infuse.runtime.rig import reference_pose

from .controller import Gaze
from .model import INFLUENCES


def parse_path(text: str) -> np.ndarray:
    """``"x,y,z; x,y,z; ..."`` -> (K, 3) metres; :class:`UsageError` unless there are at least two finite points."""
    points = []
    for k, item in enumerate(p for p in text.replace("\n", ";").split(";") if p.strip()):
        try:
            values = [float(v) for v in item.replace(" ", ",").split(",") if v]
        except ValueError:
            values = []
        if len(values) != 3 or not np.all(np.isfinite(values)):
            raise UsageError(f"--target-path point {k + 1} ({item.strip()!r}): expected three numbers x,y,z in metres")
        points.append(values)
    if len(points) < 2:
        raise UsageError("--target-path needs at least two points")
    return np.array(points)


def path_track(points: np.ndarray, duration_s: float, fps: float) -> np.ndarray:
    """(F, 3) positions at ``fps`` over ``duration_s`` moving at constant speed along the closed polyline ``points``."""
    loop = np.vstack((points, points[:1]))
    lengths = np.linalg.norm(np.diff(loop, axis=0), axis=1)
    along = np.concatenate(([0.0], np.cumsum(lengths)))
    frames = int(round(duration_s * fps)) + 1
    s = np.linspace(0.0, along[-1], frames)
    return np.stack([np.interp(s, along, loop[:, k]) for k in range(3)], axis=1)


def default_path(rig, duration_s: float, fps: float, distance_m: float = 1.5) -> np.ndarray:
    """(F, 3): an ellipse in front of the character's eyes (or head), 60 degrees to each side and 20 up
    and down, at ``distance_m``, taken once over ``duration_s``."""
    _, positions, _ = reference_pose(rig.character, rig.joints)
    origin = positions[_look_joints(rig)].mean(axis=0)
    phase = np.linspace(0.0, 2 * np.pi, int(round(duration_s * fps)) + 1)
    heading, pitch = np.radians(60.0) * np.sin(phase), np.radians(20.0) * np.sin(2 * phase)
    local = np.stack((np.cos(pitch) * np.sin(heading), np.sin(pitch), np.cos(pitch) * np.cos(heading)), axis=1)
    return origin + distance_m * quat.rotate(rig.body, local)


def _look_joints(rig) -> list[int]:
    eyes = [rig.joint("eyeball_left"), rig.joint("eyeball_right")]
    if None not in eyes:
        return eyes
    head = next((rig.joint(n) for n in ("skullbase", "spine5", "spine4") if rig.joint(n) is not None), None)
    if head is None:
        raise UsageError(f"{rig.name}: no eyes or head joint is mapped")
    return [head]


def _arguments(p) -> None:
    p.add_argument("file", metavar="CHARACTER", help="character file (glTF/VRM, BVH, SmartBody .sk, ...)")
    p.add_argument("-o", "--output", required=True, help="render: .gif, .mp4 or .png (a filmstrip with --strip)")
    p.add_argument("--target-path", help="target positions 'x,y,z;x,y,z;...' in metres (default: an ellipse in front of the eyes)")
    p.add_argument("--duration", type=float, default=6.0, help="seconds (default 6)")
    p.add_argument("--influence", choices=list(INFLUENCES), default="WAIST", help="how far down the body the gaze turns")
    p.add_argument("--clip", help="a clip of the file to play, looping, under the gaze (default: stand still)")
    p.add_argument("--saccades", choices=["talk", "listen", "think"], help="add saccades in this mode (saccade plugin)")
    p.add_argument("--blink", action="store_true", help="add blinks (blink plugin)")
    p.add_argument("--breathing", action="store_true", help="add breathing (breathing plugin)")
    p.add_argument("--save", metavar="OUT", help="also write the animation (.glb, .bvh...)")
    p.add_argument("--strip", type=int, metavar="N", help="PNG output: a filmstrip of N frames")
    p.add_argument("--view", choices=list(VIEWS), default="three-quarter")
    p.add_argument("--size", help="WIDTHxHEIGHT of the image")
    p.add_argument("--fps", type=float, default=30.0, help="animation frame rate (default 30)")
    add_mapping_options(p)
    add_read_options(p)


def _run(args) -> int:
    if not (np.isfinite(args.duration) and 0 < args.duration <= 600):
        raise UsageError("--duration must be between 0 and 600 seconds")
    if not (np.isfinite(args.fps) and 1 <= args.fps <= 120):
        raise UsageError("--fps must be between 1 and 120")
    size = parse_size(args.size) if args.size else None
    path = Path(args.file)
    asset = fileio.load(path, format=args.read_format, **read_options(args))
    mapping = mapping_from_args(args, asset)
    rt = Runtime(fps=args.fps)
    name = rt.add_character(Character(path.stem, asset), mapping=mapping)
    rig = rt.rig(name)
    base = _base_motion(asset, rig, args.clip)
    if base is not None:
        rt.activate(name, Clip(base, loop=True), 0.0)
    track = path_track(parse_path(args.target_path), args.duration, args.fps) if args.target_path \
        else default_path(rig, args.duration, args.fps)
    rt.activate(name, Gaze(TrackTarget(track), influence=args.influence), 0.0)
    for flag, kind, settings in ((args.saccades, "saccade", {"mode": args.saccades}), (args.blink, "blink", {}),
                                 (args.breathing, "breathing", {})):
        if flag:
            rt.activate(name, controller(kind, **settings), 0.0)
    rt.run(args.duration)
    motion = rt.motion(name, "gaze")
    if args.save:
        fileio.save(rt.export(name, "gaze"), args.save)
    figure = gaze_figure(motion, rig, track, mapping)
    render([figure], args.output, strip=args.strip, size=size, camera=Camera(view=args.view, follow=False),
           title=f"{path.name}: gaze ({args.influence.lower()})")
    print(f"wrote {args.output}" + (f" and {args.save}" if args.save else ""))
    return 0


def _base_motion(asset, rig, clip_name):
    """The clip to play under the gaze: the one asked for, else the first frame when the rest pose lies down."""
    if clip_name is not None:
        if clip_name not in asset.motions:
            known = ", ".join(repr(n) for n in asset.motions) or "none"
            raise InputError(asset.path, f"clip {clip_name!r}", f"no such clip; clips: {known}")
        return asset.motions[clip_name]
    if rig.reference == "rest":
        return None
    first = next(m for m in asset.motions.values() if m.num_frames)
    jt = None if first.joint_translations is None else first.joint_translations[:1]
    return first.replace(local_rotations=first.local_rotations[:1], root_translations=first.root_translations[:1],
                         joint_translations=jt)


def gaze_figure(motion, rig, track: np.ndarray, mapping) -> Figure:
    """A figure of ``motion`` with the target (a sphere) and where the gaze points (a cross and a ray)."""
    from infuse import motion_fk

    g_rot, g_pos = motion_fk(motion)
    joints = _look_joints(rig)
    forward_local = quat.rotate(quat.conjugate(rig.reference_rotations[joints]), quat.rotate(rig.body, np.array([0.0, 0.0, 1.0])))
    origin = g_pos[:, joints].mean(axis=1)
    forward = quat.rotate(g_rot[:, joints], forward_local).mean(axis=1)
    forward /= np.linalg.norm(forward, axis=1, keepdims=True)
    target = track[np.minimum(np.arange(motion.num_frames), len(track) - 1)]
    distance = np.linalg.norm(target - origin, axis=1, keepdims=True)
    looking_at = origin + forward * distance
    ray_joint = rig.skeleton.names[joints[0]]
    markers = [Marker(target, "target", color=(200, 30, 90), style="sphere", size=0.06),
               Marker(looking_at, "gaze", color=(20, 120, 200), style="cross", size=0.05, ray_from=ray_joint)]
    return Figure.from_motion(motion, label=rig.name, sides=sides_from_mapping(rig.skeleton, mapping), markers=markers)


def gaze_command() -> Command:
    return Command("gaze", "render a character following a moving target with its gaze (eyes, head, spine)",
                   _arguments, _run)
