"""A speaker's living body: the idle that ``infuse speak`` plays under the face.

A scene (:class:`infuse.scene.Scene`) stands the character in the idle clip of a behaviour pack
(weight on both feet, arms down, however the file's rest pose holds them), with its default
breathing and blinks, talk-mode saccades and a small nod on the speech's beats. The speech itself
is laid over the result (:func:`with_face`): its face joints replace the idle's and a morph target
both drive takes the larger weight, so the mouth says exactly what the lip sync made and the eyes
still blink.
"""
from __future__ import annotations

import numpy as np

from infuse.asset import Asset
from infuse.errors import UnusableInputError
from infuse.motion import Motion
from infuse.packs import installed_packs
from infuse.runtime import controller
from infuse.scene import Scene

#: The behaviour pack whose ``idle`` clip the body stands in (when installed and the body has legs).
IDLE_PACK = "locomotion-female"
#: A beat: a nod of this amount (1 = 30°) and frequency at a word that starts at least
#: ``BEAT_GAP_S`` after the previous beat.
BEAT_AMOUNT = 0.12
BEAT_HZ = 1.2
BEAT_GAP_S = 1.5


def beats(words, gap_s: float = BEAT_GAP_S) -> list[float]:
    """Start times (s) of the words that carry a nod: the first word, then each word starting at
    least ``gap_s`` after the previous beat. ``words``: ``(start_s, end_s, word)``."""
    out: list[float] = []
    for start, _, _ in words:
        if not out or start - out[-1] >= gap_s:
            out.append(float(start))
    return out


def idle_body(asset: Asset, frames: int, fps: float, words=(), pack: str | None = IDLE_PACK, map_file=None,
              seed: int = 0, clip: str = "speech", ground: bool = True) -> tuple[Asset | None, str]:
    """The character ``asset`` idling for ``frames`` frames at ``fps``, written as the clip ``clip``
    (standing on the ground unless ``ground`` is false), and a phrase saying what moves it; ``None``
    for a character that is not a humanoid (nothing to idle but its face).

    ``words`` (``(start_s, end_s, word)``) place the nods; ``pack``: the behaviour pack whose idle
    clip the body stands in (``None``: the rest pose); ``map_file``: a saved joint map.
    """
    scene = Scene(fps=fps, quiet=True, seed=seed)
    packs = (pack,) if pack is not None and pack in installed_packs() else ()
    try:
        name = scene.add_character(asset, "speaker", packs=packs, map=map_file)
        stance = f"the {pack} idle" if packs else "its rest pose"
    except UnusableInputError:  # a pack needs legs to stand on: a bust keeps its rest pose
        try:
            name = scene.add_character(asset, "speaker", map=map_file)
        except UnusableInputError as exc:  # not a humanoid (a head alone): only its face moves
            return None, f"face only ({exc.problem})"
        stance = "its rest pose"
    runtime = scene.runtime
    runtime.activate(name, controller("saccade", mode="talk", seed=seed), 0.0)
    for start in beats(words):
        runtime.activate(name, controller("head", lexeme="NOD", amount=BEAT_AMOUNT, velocity_hz=BEAT_HZ), start)
    scene.run(frames / scene.fps)
    nods = len(beats(words))
    return runtime.export(name, clip, ground=ground), f"{stance}, breathing, blinks, saccades, {nods} nod{'s' * (nods != 1)}"


def with_face(body: Motion, face: Motion | None) -> Motion:
    """``body`` with the speech clip ``face`` laid over it (same skeleton and frame rate; the first
    frames of both when their lengths differ): the joints ``face`` animates take its local rotations
    and, where it has them, local translations; a morph target both drive takes the larger weight
    (the speech writes its neutral channels at 0, which must not hold the eyelids open through a
    blink)."""
    if face is None:
        return body
    n = min(body.num_frames, face.num_frames)
    index = np.nonzero(face.animated_mask)[0]
    rotations = body.local_rotations[:n].copy()
    rotations[:, index] = face.local_rotations[:n, index]
    translations = None if body.joint_translations is None else body.joint_translations[:n]
    if face.joint_translations is not None:
        translations = body.local_translations()[:n]
        translations[:, index] = face.joint_translations[:n, index]
    names = tuple(dict.fromkeys(body.morph_names + face.morph_names))
    weights = np.zeros((n, len(names)))
    weights[:, [names.index(m) for m in body.morph_names]] = body.morph_weights[:n]
    spoken = [names.index(m) for m in face.morph_names]
    weights[:, spoken] = np.maximum(weights[:, spoken], face.morph_weights[:n])
    return body.replace(local_rotations=rotations, root_translations=body.root_translations[:n],
                        joint_translations=translations, morph_names=names, morph_weights=weights)
