"""The main demo: load a character from the test corpus, print its joint tree, render a preview; then a
scene of two characters from two sources, realized from BML.

Writes into ``out/demo/``: a preview PNG of the character, a GIF plus a filmstrip PNG of a corpus walk,
and in ``out/demo/scene/`` the scene of ``examples/scenes/demo.toml`` (the same as ``infuse run
examples/scenes/demo.toml -o out/demo/scene``): Bob (the Mixamo Xbot) walks up to Ann (a Ready Player
Me avatar), they look at each other, Bob nods, Ann says a sentence with lip sync and reaches for a cup.
Each character is exported as a glb with its animation (Ann's with morph-weight tracks and her WAV
beside it), with the BML feedback log and preview renders. Then, in ``out/demo/conversation/``, the
conversation of ``examples/scenes/conversation.toml``: Ann explains how a lamp works with the gestures,
pointing, nods, brow raises and gaze the ``nonverbal`` generator adds to her speech, and points at the
lamp; Bob listens with his arms crossed (the ``postures`` pack), nods at the ends of her phrases and
answers; both exported as glb, the feedback (with the generated BML) and a preview. The corpus is found
through env ``INFUSE_CORPUS``, else ``../shared/corpus`` beside the repository. Run it with ``make demo``
(or ``.venv/bin/python examples/demo.py``).
"""
from __future__ import annotations

import os
import sys
from pathlib import Path

import numpy as np

import infuse
from infuse.bml import parse_bml
from infuse.errors import InfuseError
from infuse.render import Camera, Figure, render
from infuse.scene.command import build_scene, write_feedback
from infuse.scene.scenefile import read_scene_file

REPO = Path(__file__).resolve().parents[1]
OUT = REPO / "out" / "demo"
SCENE = REPO / "examples" / "scenes" / "demo.toml"
CONVERSATION = REPO / "examples" / "scenes" / "conversation.toml"

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
    print(sk.describe_tree(max_lines=24))
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
    return scene_demo() or conversation_demo()


def scene_demo() -> int:
    """Realize the demo scene file, export each character with its audio, write the feedback and previews.
    The scene file finds the corpus the same way (``INFUSE_CORPUS``, else ``../shared/corpus``)."""
    out = OUT / "scene"
    print(f"\nscene:     {SCENE}")
    spec = read_scene_file(SCENE)
    scene = build_scene(spec)  # loads, maps and infuses each character, schedules and realizes the BML
    for entry in scene.characters.values():
        print(f"  {entry.name}: {entry.source.name} ({entry.character.asset.format}, {entry.character.skeleton.num_joints} "
              f"joints), packs {', '.join(entry.packs) or 'none'}")
    scene.on("blockProgress", lambda e: print(f"  {e.global_time:5.2f} s  {e.character}: {e.block} {e.sync}s"))
    scene.run(spec.duration)
    written = write_outputs(scene, out, strip=6)
    written.append(scene.render(out / "scene.gif", fps=15, size=(720, 480)))
    report(scene)
    for path in written:
        print(f"wrote      {path}")
    return 0


def write_outputs(scene, out: Path, strip: int) -> list[Path]:
    """Every character as a glb (with its WAV when it speaks), the feedback, and a preview strip of
    ``strip`` frames, in ``out``."""
    out.mkdir(parents=True, exist_ok=True)
    written = []
    for name in scene.characters:
        written += scene.export(name, out / f"{name}.glb")
    written += write_feedback(scene, out)
    written.append(scene.render(out / "preview.png", strip=strip))
    return written


def report(scene) -> None:
    """What happened, measured on the output: how far Bob walked, Ann's speech and audio, the mutual gaze."""
    bob = infuse.motion_fk(scene.motion("bob"))[1][:, 0]
    print(f"  bob walked {np.linalg.norm(bob[-1, [0, 2]] - bob[0, [0, 2]]):.2f} m")
    talk = next(a for r in scene.scheduler.blocks.values() for a in r.activations if a.controller == "speech")
    samples, rate = scene.audio("ann")
    print(f"  ann said {talk.parameters['text']!r} from {talk.start:.2f} s to {talk.end:.2f} s; "
          f"her WAV lasts {len(samples) / rate:.2f} s, her clip {scene.runtime.frame / scene.fps:.2f} s")
    warnings = [e for e in scene.feedback.log if e.kind == "warningFeedback"]
    print(f"  {len(scene.feedback.log)} feedback events, {len(warnings)} warnings"
          + "".join(f"\n    {e.id}: {e.description}" for e in warnings))


def conversation_demo() -> int:
    """Realize the conversation scene file; export both characters, the feedback (with the generated BML)
    and a preview."""
    out = OUT / "conversation"
    print(f"\nconversation: {CONVERSATION}")
    spec = read_scene_file(CONVERSATION)
    scene = build_scene(spec)
    scene.run(spec.duration)
    written = write_outputs(scene, out, strip=8)
    conversation_report(scene)
    for path in written:
        print(f"wrote      {path}")
    return 0


def conversation_report(scene) -> None:
    """What the generator added, and on the output (FK): where Ann's index finger aims at her pointing's
    stroke, and Bob's right wrist against his left elbow while he listens and once he answers."""
    for event in (e for e in scene.feedback.log if e.kind == "generatedBml"):
        for block in parse_bml(event.bml).blocks:
            added = ", ".join(f"{b.element} {b.attributes.get('lexeme') or b.attributes.get('target') or ''}".strip()
                              for b in block.behaviours if b.element != "speech")
            print(f"  generated for {block.character_id} ({block.id}): {added}")
    pointing = next(a for a in scene.scheduler.activations("ann") if a.element == "pointing"
                    and a.parameters.get("target") in scene.objects)
    rig = scene.runtime.rig("ann")
    _, positions = infuse.motion_fk(scene.motion("ann"))
    at = positions[int(round(pointing.time("stroke") * scene.fps))]
    target = np.asarray(scene.objects[pointing.parameters["target"]].position)
    misses = []
    for side in ("l", "r"):
        wrist, tip = at[rig.joint(f"{side}_wrist")], at[rig.joint(f"{side}_index3")]
        ray = (tip - wrist) / np.linalg.norm(tip - wrist)
        misses.append(np.linalg.norm((target - wrist) - ray * max(np.dot(target - wrist, ray), 0.0)))
    print(f"  ann points at the {pointing.parameters['target']} at {pointing.time('stroke'):.2f} s: her index "
          f"finger's ray passes {100 * min(misses):.1f} cm from it")
    rig = scene.runtime.rig("bob")
    _, positions = infuse.motion_fk(scene.motion("bob"))
    gap = np.linalg.norm(positions[:, rig.joint("r_wrist")] - positions[:, rig.joint("l_elbow")], axis=1)
    answer = scene.scheduler.blocks["bob_answer"]
    listening = gap[int(2.0 * scene.fps):int(answer.start_s * scene.fps)]
    print(f"  bob listens with his arms crossed (2.0-{answer.start_s:.1f} s): right wrist {100 * listening.mean():.0f} cm "
          f"from the left elbow; {100 * gap[-1]:.0f} cm once he has answered")
    warnings = [e for e in scene.feedback.log if e.kind == "warningFeedback"]
    print(f"  {len(scene.feedback.log)} feedback events, {len(warnings)} warnings"
          + "".join(f"\n    {e.id}: {e.description}" for e in warnings))


if __name__ == "__main__":
    sys.exit(main())
