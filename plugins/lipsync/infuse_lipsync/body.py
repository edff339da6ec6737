"""A speaker's living body: the idle that ``infuse speak`` plays under the face.

A scene (:class:`infuse.scene.Scene`) stands the character in the idle clip of a behaviour pack
(weight on both feet, arms down, however the file's rest pose holds them), with its default
breathing and blinks, talk-mode saccades and a small nod on the speech's beats. The speech itself
is laid over the result: its face joints replace the idle's (:func:`with_face`) and a morph
target both drive takes the larger weight (:func:`merged_tracks`), so the mouth says exactly what
the lip sync made and the eyes still blink.
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


def with_face(body: Motion, face: Motion | None, joints) -> Motion:
    """``body`` with the face joints ``joints`` (names) taken from ``face`` (same skeleton and frame
    count; its local rotations and, where it has them, local translations)."""
    if face is None or not joints:
        return body
    sk = body.skeleton
    index = [sk.index[j] for j in joints]
    rotations = body.local_rotations.copy()
    rotations[:, index] = face.local_rotations[:, index]
    translations = body.joint_translations
    if face.joint_translations is not None:
        translations = body.local_translations().copy()
        translations[:, index] = face.joint_translations[:, index]
    return body.replace(local_rotations=rotations, joint_translations=translations)


def merged_tracks(body: dict | None, face: dict | None) -> dict | None:
    """One morph-weight track (``{"times", "weights"}``) from the idle's and the speech's on the same
    frames; a target both drive takes the larger weight (the speech writes its neutral channels
    at 0, which must not hold the eyelids open through a blink)."""
    if not body or not body.get("weights"):
        return face
    if not face or not face.get("weights"):
        return body
    n = min(len(body["times"]), len(face["times"]))
    weights = {k: np.asarray(v)[:n] for k, v in body["weights"].items()}
    for k, v in face["weights"].items():
        v = np.asarray(v)[:n]
        weights[k] = np.maximum(weights[k], v) if k in weights else v
    return {"times": np.asarray(face["times"])[:n], "weights": weights}
