"""Every BML document of the corpus through parse, schedule and realize.

Prints, per source folder: documents parsed and scheduled without a warning, with warnings, and invalid
(refused with a clear error); documents realized on a character (the Ready Player Me avatar, one
scene per document, every frame evaluated to the end of its blocks) and the behaviours that became
runtime activities, and of the ``<gesture>`` behaviours how many are played; the time taken; and how many of the expected timings stated in the OpenBMLParser
documents' header comments the scheduler reproduces. Then the scheduled behaviours played on the
character: those that became activities, those with nothing to show (a wait, an event), and every one not
played with the warning that says why, those naming an object, character or clip the scene does not have apart.

    python benchmarks/bml_corpus.py [--verbose] [--no-realize] [--fps 30] [--nonverbal]

``--nonverbal`` realizes every document with the ``nonverbal`` generator on (docs/nonverbal.md) and
counts the behaviours it added and how many of those play.

The corpus is read from INFUSE_CORPUS (default ../shared/corpus from the repository root).
"""
from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from collections import Counter
from pathlib import Path

from infuse.bml import Scheduler, parse_bml_file
from infuse.bml.expectations import check, expectations_from_comments
from infuse.errors import InputError

REPO = Path(__file__).resolve().parents[1]
CORPUS = Path(os.environ.get("INFUSE_CORPUS", REPO.parent / "shared" / "corpus")).resolve()
#: The character every document is realized on (a face with visemes and expressions, eyes, a full body).
CHARACTER = "talkinghead/avatars/brunette-t.glb"
#: Longest stretch of a document evaluated, seconds.
MAX_SECONDS = 60.0
#: Words of a realization warning that names an object, character or clip absent from the scene.
ABSENT = ("no character or object named", "no object named", "no target or character named", "has no joint",
          "no character, object or target named", "no character '", "no clip named")
#: The behaviour packs the character is infused with, those installed: walks, reaches and postures.
PACKS = ("locomotion-female", "reaching", "postures")


def shared_character(corpus: Path):
    """The realizing character, loaded and mapped once."""
    import infuse
    from infuse.mapping import map_skeleton

    asset = infuse.load(corpus / CHARACTER)
    return infuse.Character("character", asset, map_skeleton(asset))


def installed_packs() -> tuple[str, ...]:
    from infuse import registry

    return tuple(p for p in PACKS if p in registry.table("behaviour-pack"))


def realize(document, character, fps: float, packs=(), pack_cache=None, generators=()) -> dict:
    """Realize ``document`` on ``character`` (infused with ``packs``, with BML ``generators`` on) in a scene
    of its own and evaluate it to its end: counts of activities and warnings, frames evaluated, CPU seconds
    spent synthesizing speech, the behaviours with nothing to show and those not played (with the warning
    saying why), and of the behaviours generators added, how many and how many play."""
    from infuse.bml import parse_bml
    from infuse.scene import Scene

    scene = Scene(fps=fps, quiet=True, pack_cache=pack_cache, generators=generators)
    scene.add_character(character, "character", packs=packs)
    scene.bml("character", document)
    scene.run(min(scene.end_time, MAX_SECONDS) + 1.0 / fps)
    scene.motion("character")
    scene.audio("character")
    warnings = [e for e in scene.feedback.log if e.kind == "warningFeedback"]
    added = {(block.id, b.id) for e in scene.feedback.log if e.kind == "generatedBml"
             for block in parse_bml(e.bml).blocks for b in block.behaviours if b.element != "speech"}
    own = [a for record in scene.scheduler.blocks.values() for a in record.activations
           if (a.block, a.behaviour) not in added]
    gestures = [(a.block, a.behaviour) for a in own if a.element == "gesture"]
    reasons = {}
    for w in warnings:
        reasons[w.id] = w  # the last warning about a behaviour is what realizing it said
    silent, missed = 0, []
    for a in own:
        if (a.block, a.behaviour) in scene.activities:
            continue
        why = reasons.get(f"{a.block}:{a.behaviour}")
        if why is None:
            silent += 1
        else:
            missed.append((f"{a.block}:{a.behaviour}", a.element, why.description,
                           any(words in why.description for words in ABSENT) or why.type == "NO_SUCH_TARGET"))
    return {"activities": sum((a.block, a.behaviour) in scene.activities for a in own), "warnings": warnings,
            "frames": scene.runtime.frame,
            "generated": len(added), "generated_played": sum(key in scene.activities for key in added),
            "synthesis_s": scene.speech.synthesis_s, "gestures": len(gestures),
            "gestures_played": sum(key in scene.activities for key in gestures), "silent": silent, "missed": missed}


def run(corpus: Path, verbose: bool = False, realize_fps: float | None = 30.0, generators=()) -> dict:
    """Counts per folder, oracle outcomes and timings; also printed. ``realize_fps`` None: no realizing;
    ``generators``: BML generators on while realizing."""
    files = sorted((corpus / "bml").glob("*/*.xml"))
    if not files:
        raise SystemExit(f"no BML documents under {corpus / 'bml'} (set INFUSE_CORPUS)")
    counts: dict[str, Counter] = {}
    outcomes = []
    realized = []
    started = time.perf_counter()
    for path in files:
        folder = path.parent.name
        tally = counts.setdefault(folder, Counter())
        try:
            document = parse_bml_file(path)
        except InputError as exc:
            tally["invalid"] += 1
            if verbose:
                print(f"  invalid  {exc}")
            continue
        scheduler = Scheduler()
        records = scheduler.submit(document)
        scheduler.flush()
        warnings = [e for e in scheduler.feedback.log if e.kind == "warningFeedback"]
        tally["warnings" if warnings else "ok"] += 1
        tally["behaviours"] += sum(len(r.activations) for r in records)
        if verbose:
            for w in warnings:
                print(f"  warning  {folder}/{path.name}: {w.id} {w.type}: {w.description}")
        if folder == "openbmlparser":
            expectations = expectations_from_comments(document.comments)
            outcomes += [(path.name, o) for o in check(expectations, document.blocks[0], records[0])]
        if realize_fps:
            realized.append((folder, path, document))
    elapsed = time.perf_counter() - started

    realize_s = synthesis_s = 0.0
    frames = 0
    missed = []
    packs = installed_packs()
    cache = tempfile.TemporaryDirectory(prefix="infuse-bml-corpus-")
    if realized:
        character = shared_character(corpus)
        cpu = time.process_time()
        for folder, path, document in realized:
            tally = counts[folder]
            try:
                outcome = realize(document, character, realize_fps, packs, cache.name, generators)
            except Exception as exc:  # a crash: the benchmark counts it and goes on
                tally["crashed"] += 1
                print(f"  CRASH    {folder}/{path.name}: {type(exc).__name__}: {exc}")
                continue
            tally["realized"] += 1
            tally["activities"] += outcome["activities"]
            tally["gestures"] += outcome["gestures"]
            tally["gestures played"] += outcome["gestures_played"]
            tally["silent"] += outcome["silent"]
            tally["generated"] += outcome["generated"]
            tally["generated played"] += outcome["generated_played"]
            tally["generated documents"] += outcome["generated"] > 0
            missed += [(f"{folder}/{path.name}", *m) for m in outcome["missed"]]
            frames += outcome["frames"]
            synthesis_s += outcome["synthesis_s"]
            if verbose:
                for w in outcome["warnings"]:
                    print(f"  realize  {folder}/{path.name}: {w.id} {w.type}: {w.description}")
        realize_s = time.process_time() - cpu
    cache.cleanup()

    print(f"{'folder':<15}{'documents':>10}{'ok':>6}{'warnings':>10}{'invalid':>9}{'behaviours':>12}"
          + (f"{'realized':>10}{'crashed':>9}{'activities':>12}" if realized else ""))
    for folder, tally in sorted(counts.items()):
        total = tally["ok"] + tally["warnings"] + tally["invalid"]
        print(f"{folder:<15}{total:>10}{tally['ok']:>6}{tally['warnings']:>10}{tally['invalid']:>9}{tally['behaviours']:>12}"
              + (f"{tally['realized']:>10}{tally['crashed']:>9}{tally['activities']:>12}" if realized else ""))
    print(f"{len(files)} documents parsed and scheduled in {elapsed * 1000:.0f} ms "
          f"({elapsed / len(files) * 1000:.2f} ms per document)")
    if realized:
        print(f"{len(realized)} documents realized on {CHARACTER} (packs: {', '.join(packs) or 'none'}) at "
              f"{realize_fps:g} fps: {frames} frames "
              f"({frames / realize_fps:.0f} s of animation) in {realize_s:.1f} CPU s, of which speech synthesis "
              f"{synthesis_s:.1f} s")
        gestures = sum(t["gestures"] for t in counts.values())
        print(f"<gesture> behaviours played: {sum(t['gestures played'] for t in counts.values())} of {gestures}")
        scheduled = sum(t["behaviours"] for t in counts.values())
        silent = sum(t["silent"] for t in counts.values())
        absent = [m for m in missed if m[4]]
        print(f"behaviours played on the character: {scheduled - len(missed)} of {scheduled} "
              f"({sum(t['activities'] for t in counts.values())} as activities, {silent} with nothing to show); "
              f"not played: {len(missed)}, of which {len(absent)} name an object, character or clip the scene does not have")
        for where, behaviour, element, why, is_absent in sorted(missed, key=lambda m: (not m[4], m[0], m[1])):
            print(f"  {'absent' if is_absent else 'not played'}  {where} {behaviour} <{element}>: {why}")
        if generators:
            total = {key: sum(t[key] for t in counts.values()) for key in ("generated", "generated played",
                                                                             "generated documents")}
            print(f"behaviours added by {', '.join(generators)}: {total['generated']} in {total['generated documents']} "
                  f"documents, {total['generated played']} played (the others, and the behaviours not played above, "
                  "include those tied to speech the document's own timing drops)")

    status = Counter(o.status for _, o in outcomes)
    checkable = status["matched"] + status["mismatched"]
    print(f"OpenBMLParser header expectations: {len(outcomes)} stated, {status['matched']} matched, "
          f"{status['mismatched']} not matched, {status['conflict']} contradict their own document")
    if checkable:
        print(f"share matched: {status['matched'] / checkable:.1%} of those consistent with their document "
              f"({status['matched'] / len(outcomes):.1%} of all)")
    for name, o in outcomes:
        if o.status != "matched":
            print(f"  {o.status:<10} {name}: {o.expectation.text!r}: {o.detail}")
    return {"counts": counts, "outcomes": outcomes, "seconds": elapsed}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--verbose", action="store_true", help="print every warning and error")
    parser.add_argument("--no-realize", action="store_true", help="parse and schedule only")
    parser.add_argument("--fps", type=float, default=30.0, help="frame rate of the realized animation (default 30)")
    parser.add_argument("--nonverbal", action="store_true", help="realize with the nonverbal generator on")
    args = parser.parse_args(argv)
    run(CORPUS, args.verbose, None if args.no_realize else args.fps, ("nonverbal",) if args.nonverbal else ())
    return 0


if __name__ == "__main__":
    sys.exit(main())
