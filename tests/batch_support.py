"""Inputs shared by the batch tests: a few corpus clips on two skeleton families onto two characters."""
from __future__ import annotations

from pathlib import Path

from corpus_data import corpus_file

BANDAI = "bandai/Bandai-Namco-Research-Motiondataset-1/data/dataset-1_{}_001.bvh"
UTAH_MOTIONS = "smartbody/behaviorsets/MaleLocomotion/motions/{}.skm"
MOTIONS = [BANDAI.format(s) for s in ("walk_normal", "walk_feminine", "run_normal")] + \
          [UTAH_MOTIONS.format(s) for s in ("ChrUtah_Walk001", "ChrUtah_Run001", "ChrUtah_WalkInCircleLeft001")]
XBOT = "runxaway-models/Xbot.glb"
UTAH = "smartbody/behaviorsets/MaleLocomotion/skeletons/test_utah.sk"
CHARACTERS = [XBOT, UTAH]


def motion_files() -> list[str]:
    return [str(corpus_file(m)) for m in MOTIONS]


def character_files() -> list[str]:
    return [str(corpus_file(c)) for c in CHARACTERS]


def tree(root: Path) -> dict[str, bytes]:
    """Every output file below ``root`` (relative POSIX path -> bytes), the manifest left out."""
    return {p.relative_to(root).as_posix(): p.read_bytes() for p in sorted(root.rglob("*"))
            if p.is_file() and not p.name.startswith(".")}


def expected_outputs() -> set[str]:
    """Output paths for every character x motion of the shared inputs."""
    names = [Path(m).stem for m in MOTIONS]
    return {f"Xbot/{n}.glb" for n in names} | {f"test_utah/{n}.bvh" for n in names}
