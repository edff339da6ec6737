"""The main demo: load a character from the test corpus, print its joint tree, render a preview.

Writes into ``out/demo/``: a preview PNG of the character, and a GIF plus a filmstrip PNG of a
corpus walk. The corpus is found through env ``INFUSE_CORPUS``, else ``../shared/corpus`` beside
the repository. Run it with ``make demo`` (or ``.venv/bin/python examples/demo.py``).
"""
from __future__ import annotations

import os
import sys
from pathlib import Path

import infuse
from infuse.errors import InfuseError
from infuse.render import Camera, Figure, render

REPO = Path(__file__).resolve().parents[1]
OUT = REPO / "out" / "demo"

# Tried in order; the first one an installed reader can load is used.
CHARACTERS = (
    "runxaway-models/Xbot.glb",
    "smartbody/ChrBrad/ChrBrad.sk",
    "smartbody/ChrRachel/ChrRachel.sk",
    "bandai/Bandai-Namco-Research-Motiondataset-1/data/dataset-1_walk_normal_001.bvh",
)
WALKS = (
    "smartbody/behaviorsets/MaleLocomotion/motions/ChrUtah_Walk001.skm",
    "bandai/Bandai-Namco-Research-Motiondataset-1/data/dataset-1_walk_normal_001.bvh",
    "bandai/Bandai-Namco-Research-Motiondataset-2/data/dataset-2_walk_normal_001.bvh",
)


def find_corpus() -> Path | None:
    root = Path(os.environ.get("INFUSE_CORPUS", REPO.parent / "shared" / "corpus"))
    return root if root.is_dir() else None


def first_loadable(corpus: Path, candidates: tuple[str, ...], need_motion: bool):
    """(path, asset) of the first candidate that exists and loads (with a clip of several frames if asked)."""
    for rel in candidates:
        path = corpus / rel
        if not path.exists():
            continue
        try:
            asset = infuse.load(path)
        except InfuseError as exc:
            print(f"  (skipping {rel}: {exc})")
            continue
        if need_motion and not any(m.num_frames > 1 for m in asset.motions.values()):
            continue
        return path, asset
    return None, None


def main() -> int:
    corpus = find_corpus()
    if corpus is None:
        print("demo: the test corpus was not found; set INFUSE_CORPUS to its folder "
              "(or place it at ../shared/corpus beside the repository)", file=sys.stderr)
        return 2
    OUT.mkdir(parents=True, exist_ok=True)

    path, character = first_loadable(corpus, CHARACTERS, need_motion=False)
    if character is None:
        print("demo: no corpus character could be loaded; run 'make setup' to install the readers", file=sys.stderr)
        return 2
    sk = character.skeleton
    print(f"character: {path.relative_to(corpus)} ({character.format}, {sk.num_joints} joints, "
          f"height {sk.height():.2f} m, units {character.source_units} ({character.units_detected_by}))")
    print(sk.describe_tree(max_lines=80))
    preview = render([Figure.from_skeleton(sk, label="rest pose")], OUT / "character.png", camera=Camera(view="three-quarter"),
                     size=(520, 640), title=path.name)
    print(f"\npreview:   {preview}")

    walk_path, walk_asset = first_loadable(corpus, WALKS, need_motion=True)
    if walk_asset is None:
        print("demo: no corpus walk could be loaded; skipping the animation", file=sys.stderr)
        return 0
    motion = next(m for m in walk_asset.motions.values() if m.num_frames > 1)
    figure = Figure.from_motion(motion)
    print(f"walk:      {walk_path.relative_to(corpus)} ({motion.num_frames} frames at {motion.fps:g} fps)")
    gif = render([figure], OUT / "walk.gif", end=min(motion.duration, 4.0), fps=20, size=(480, 400), title=walk_path.name)
    strip = render([figure], OUT / "walk_strip.png", strip=6, title=f"{walk_path.name}: 6 frames")
    print(f"animation: {gif}")
    print(f"strip:     {strip}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
