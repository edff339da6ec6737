"""``infuse pack test PACK --on CHARACTER``: what a locomotion pack realizes on a character.

Prints the trials of :func:`infuse.packs.walk_test.trial_pack` (asked and realized speed, heading drift,
walk-to miss and path ratio, foot skate; every figure measured on the output with FK) and draws, beside
``--output`` (a ``.png`` path): the top view of the walks to targets (``NAME.png``), and side-view
filmstrips of the straight walk (``NAME-straight.png``) and of the walk to a target behind
(``NAME-target.png``).
"""
from __future__ import annotations

from pathlib import Path

from ..errors import UsageError

#: Frames in each side-view filmstrip.
STRIP_FRAMES = 8


def add_test_parser(sub) -> None:
    t = sub.add_parser("test", help="walk a locomotion pack on a character: speeds, drift, walks to targets, "
                                    "foot skate; a top view and side strips")
    t.add_argument("pack", help="pack folder, manifest or installed pack name")
    t.add_argument("--on", dest="character", required=True, help="character file (glb, BVH, sk, ...)")
    t.add_argument("-o", "--output", help="top view .png (strips beside it; default PACK-test.png here)")
    t.add_argument("--speeds", help="comma-separated speeds to try, m/s (default five over the pack's forward range)")
    t.add_argument("--no-pictures", action="store_true", help="only print the figures")


def _speeds(text: str | None):
    if text is None:
        return None
    try:
        speeds = [float(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise UsageError(f"--speeds takes numbers separated by commas, got {text!r}") from None
    if not speeds or any(not 0.0 < v < 20.0 for v in speeds):
        raise UsageError(f"--speeds takes speeds above 0 and below 20 m/s, got {text!r}")
    return speeds


def side_strips(trial, stem: Path) -> list[Path]:
    """Side-view filmstrips of the trial's straight walk and walk to a target (skeleton drawing, the
    camera following); returns the files written."""
    from ..render import Camera, Figure, render, sides_from_mapping

    written = []
    for key, start in (("straight", 1.5), ("target", None)):
        motion = trial.motions.get(key)
        if motion is None:
            continue
        sides = sides_from_mapping(motion.skeleton, trial.mapping) if trial.mapping is not None else None
        figure = Figure.from_motion(motion, label=f"{trial.pack}: {key}", sides=sides)
        end = min(start + 3.0, motion.duration) if start is not None else None
        path = stem.with_name(f"{stem.stem}-{key}.png")
        written.append(render([figure], path, strip=STRIP_FRAMES, start=start, end=end,
                              camera=Camera(view="side", follow=True), title=f"{trial.pack} on {trial.character}: {key}",
                              progress=False))
    return written


def run_test(args) -> int:
    from .. import fileio
    from ..asset import Character
    from .pack import load_pack
    from .walk_test import draw_paths, report, trial_pack

    pack = load_pack(args.pack)
    if pack.kind != "locomotion":
        raise UsageError(f"{args.pack}: a {pack.kind} pack; 'pack test' walks locomotion packs")
    speeds = _speeds(args.speeds)
    out = Path(args.output or f"{pack.name}-test.png")
    if not args.no_pictures and out.suffix.lower() != ".png":
        raise UsageError(f"{out}: the top view is a .png")
    asset = fileio.load(args.character)
    trial = trial_pack(Character(Path(args.character).stem, asset), pack.manifest.path, speeds=speeds)
    print(report(trial))
    if not args.no_pictures:
        draw_paths(trial, out)
        for written in [out] + side_strips(trial, out):
            print(f"wrote {written}")
    return 0
