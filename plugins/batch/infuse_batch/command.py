"""``infuse batch CHARACTER... [--motions DIR] [--packs a,b] -o OUTDIR``: many characters at once.

Exit codes: 0 when every output was produced; otherwise the summary lists each failure (file,
reason) and the code is 2 when some input was malformed, 3 when the failed inputs were well formed
but could not be used (not a humanoid, a skeleton that cannot be retargeted), 1 when only internal
errors failed.
"""
from __future__ import annotations

from .jobs import FORMATS
from .run import run_batch, summary


def add_arguments(p) -> None:
    p.add_argument("characters", nargs="+", metavar="CHARACTER", help="character files, folders or globs")
    p.add_argument("--motions", action="append", metavar="DIR",
                   help="motion files, folders (searched recursively) or globs to retarget onto every character (repeatable)")
    p.add_argument("--packs", metavar="a,b", help="behaviour packs to infuse every character with (one cache per character)")
    p.add_argument("-o", "--output", required=True, metavar="OUTDIR", help="output tree: OUTDIR/CHARACTER/MOTION.glb|bvh")
    p.add_argument("--workers", type=int, metavar="N", help="local worker processes (default: the cores; 0: this process)")
    p.add_argument("--cluster", metavar="tcp://HOST:PORT", help="run on this Dask scheduler instead (needs infuse-anim-batch[dask])")
    p.add_argument("--format", choices=FORMATS, dest="out_format",
                   help="output format (default: glb for glTF characters, keeping the mesh; bvh for the others)")
    p.add_argument("--mapper", help="joint mapper plugin (default heuristic)")
    p.add_argument("--retargeter", help="retargeter plugin (default: default)")
    p.add_argument("--no-resume", dest="resume", action="store_false", help="redo outputs an earlier run already wrote")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress bar")


def run(args) -> int:
    result = run_batch(args.characters, out=args.output, motions=args.motions, packs=args.packs, workers=args.workers,
                       cluster=args.cluster, format=args.out_format, mapper=args.mapper, retargeter=args.retargeter,
                       resume=args.resume, progress=not args.quiet)
    summary(result)
    return result.exit_code
