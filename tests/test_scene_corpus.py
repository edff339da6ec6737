"""Every corpus BML document realized on a character: parsed, scheduled, turned into runtime activities and
evaluated to its end without a crash. Every behaviour is either played or reported (warningFeedback
naming it); the malformed document is refused with a clear error. One character, loaded and mapped once,
serves every document (each in a scene of its own); frames are evaluated at 10 fps to keep this quick."""
from __future__ import annotations

import numpy as np
import pytest

import infuse
from infuse.errors import InputError
from infuse.mapping import map_skeleton
from infuse.scene import Scene

from corpus_data import CORPUS, require_corpus

FILES = sorted((CORPUS / "bml").glob("*/*.xml"))
MALFORMED = {"openbmlparser/testinvalidxml.xml"}
FPS = 10.0
MAX_SECONDS = 60.0
#: Behaviours with nothing to show: their sync points give feedback, no activity plays.
SILENT = {"wait", "event"}


def _rel(path) -> str:
    return f"{path.parent.name}/{path.name}"


@pytest.fixture(scope="module")
def character():
    require_corpus()
    asset = infuse.load(CORPUS / "talkinghead/avatars/brunette-t.glb")
    return infuse.Character("ann", asset, map_skeleton(asset))


@pytest.fixture(scope="module")
def realized(character):
    out = {}
    for path in FILES:
        scene = Scene(fps=FPS, quiet=True)
        scene.add_character(character, "ann")
        try:
            scene.bml("ann", path)
        except InputError as exc:
            out[_rel(path)] = exc
            continue
        scene.run(min(scene.end_time, MAX_SECONDS) + 1.0 / FPS)
        out[_rel(path)] = scene
    return out


def test_the_corpus_is_all_there():
    require_corpus()
    assert len(FILES) == 147


def _not_shown_on_purpose(activation) -> bool:
    p = activation.parameters
    if activation.controller in SILENT:
        return True
    if activation.controller == "saccade" and p.get("enabled") is False:
        return True  # stops saccades; plays nothing itself
    if activation.controller == "posture" and p.get("stance") in (None, "STANDING") and not p.get("poses") \
            and not p.get("clip"):
        return True  # the character stands already
    return False


@pytest.mark.parametrize("rel", [_rel(p) for p in FILES])
def test_document_is_realized(realized, rel):
    result = realized[rel]
    if rel in MALFORMED:
        assert isinstance(result, InputError) and result.place.startswith("line ") and result.problem
        return
    assert not isinstance(result, InputError), str(result)
    scene = result
    warned = {e.id for e in scene.feedback.log if e.kind == "warningFeedback"}
    activations = [a for r in scene.scheduler.blocks.values() for a in r.activations]
    for a in activations:
        key = (a.block, a.behaviour)
        assert key in scene.activities or f"{a.block}:{a.behaviour}" in warned or _not_shown_on_purpose(a), \
            f"<{a.element}> {a.behaviour!r} ({a.controller}) neither played nor reported"
    motion = scene.motion("ann")
    assert motion.num_frames == scene.runtime.frame >= 1
    assert np.all(np.isfinite(motion.local_rotations)) and np.all(np.isfinite(motion.root_translations))
    spoken = [a for a in activations if a.controller == "speech" and (a.block, a.behaviour) in scene.activities]
    audio = scene.audio("ann")
    if spoken:
        samples, rate = audio
        assert len(samples) == round(scene.runtime.frame / FPS * rate)
        first = min(a.start for a in spoken)
        if first < scene.runtime.frame / FPS:
            assert samples[max(int(first * rate), 0):].any()  # the speech is heard from its start
    blocks = [r for r in scene.scheduler.blocks.values() if not r.failed and r.start_s <= (scene.runtime.frame - 1) / FPS]
    starts = {e.block for e in scene.feedback.log if e.kind == "blockProgress" and e.sync == "start"}
    assert {r.id for r in blocks} <= starts


def test_most_behaviours_play(realized):
    played = scheduled = 0
    for result in realized.values():
        if isinstance(result, InputError):
            continue
        scheduled += sum(len(r.activations) for r in result.scheduler.blocks.values())
        played += len(result.activities)
    # gestures and postures need clips no pack here provides; gaze, head, speech, face and saccades play
    assert played >= 0.5 * scheduled
