"""Finding the ``.sk`` skeleton an ``.skm`` motion plays on (an ``.skm`` holds no hierarchy).

Candidates, in order of preference: ``.sk`` files in a ``skeletons/`` folder beside the motion's
folder (SmartBody behaviour sets: ``X/motions/*.skm`` and ``X/skeletons/*.sk``), then in the
motion's own folder, then one folder up (``ChrBrad/face/*.skm`` and ``ChrBrad/ChrBrad.sk``). The
candidate holding most of the motion's channel joints wins; ties keep that order.
"""
from __future__ import annotations

from functools import lru_cache
from pathlib import Path

from infuse.errors import InfuseError

from .sk import SkFile, parse_sk

PLACES = (
    ("behaviour-set skeletons folder", lambda folder: folder.parent / "skeletons"),
    ("same folder", lambda folder: folder),
    ("parent folder", lambda folder: folder.parent),
)


def load_sk(path: Path) -> SkFile:
    """Parse ``path`` (cached while the file is unchanged)."""
    st = path.stat()
    return _load_sk(str(path.absolute()), st.st_mtime_ns, st.st_size)


@lru_cache(maxsize=32)
def _load_sk(path: str, mtime_ns: int, size: int) -> SkFile:
    return parse_sk(Path(path), Path(path).read_text(encoding="utf-8", errors="replace"))


def find_skeleton(skm_path: Path, joints: list[str]) -> tuple[SkFile | None, dict]:
    """The best ``.sk`` for a motion animating ``joints``, and a record of the search for ``Asset.meta``."""
    wanted = set(joints)
    folder = skm_path.absolute().parent
    best: tuple[int, SkFile, str] | None = None
    tried: list[str] = []
    skipped: dict[str, str] = {}
    seen: set[Path] = set()
    for place, where in PLACES:
        base = where(folder)
        if not base.is_dir():
            continue
        for candidate in sorted(base.glob("*.sk")):
            if candidate in seen or not candidate.is_file():
                continue
            seen.add(candidate)
            tried.append(str(candidate))
            try:
                sk = load_sk(candidate)
            except (InfuseError, OSError, ValueError) as exc:
                skipped[str(candidate)] = str(exc)
                continue
            covered = len(wanted.intersection(sk.names))
            if covered and (best is None or covered > best[0]):
                best = (covered, sk, place)
    record: dict = {"skeleton_candidates": tried}
    if skipped:
        record["skeleton_candidates_unreadable"] = skipped
    if best is None:
        return None, record
    record["skeleton_found_in"] = best[2]
    return best[1], record
