"""The pose stream's JSON frames: written vectorized, the same numbers ``json.dumps`` writes for the
rounded poses (to the last bit once parsed, the same text but for numbers under 1e-4, which ``json.dumps``
writes in exponent form), on frames of the live scene and on numbers chosen to catch each case."""
from __future__ import annotations

import json

import numpy as np

from infuse.live import CharacterFrame, LiveFrame
from infuse.scene import Scene
from infuse_live.frames import binary_frame, decimal_texts, frame_text

from corpus_data import corpus_file


def _reference(frame: LiveFrame) -> str:
    """The frame message as ``json.dumps`` writes the rounded arrays' lists."""
    return json.dumps({"type": "frame", "frame": frame.index, "time": frame.time_s,
                       "characters": {name: {"rotations": np.round(c.rotations, 6).ravel().tolist(),
                                             "root": np.round(c.root, 6).tolist(),
                                             "morphs": np.round(c.morphs, 4).tolist()}
                                      for name, c in frame.characters.items()}},
                      ensure_ascii=False, separators=(",", ":"))


def _same(text: str, reference: str) -> None:
    """Parsed, ``text`` equals ``reference`` to the last bit (signs of zeros included)."""
    mine, theirs = json.loads(text), json.loads(reference)
    assert mine == theirs
    np.testing.assert_array_equal(np.signbit(_numbers(mine)), np.signbit(_numbers(theirs)))


def _numbers(doc: dict) -> np.ndarray:
    """Every pose number of a parsed frame message, flat."""
    return np.concatenate([np.asarray(v, dtype=np.float64).ravel() for c in doc["characters"].values() for v in c.values()])


def test_the_numbers_json_dumps_writes_for_each_case():
    cases = np.array([0.0, -0.0, 1.0, -1.0, 0.5, -0.25, 0.707107, 0.7071067811865476, -0.9999995, 0.9999995,
                      0.9999994, 1e-7, -1e-7, 5e-6, -4.9e-6, 1.5e-5, 0.0001, 0.00012345, 12.3456789, -123.0000004,
                      1234.56789, -98765.4321, 2.5e-7, 0.0000005, 0.1 + 0.2, 3.0000005, 999.9999996])
    for decimals in range(7):
        text, = decimal_texts([cases], [decimals])
        reference = json.dumps(np.round(cases, decimals).tolist(), separators=(",", ":"))
        assert json.loads(text) == json.loads(reference), (decimals, text, reference)
        np.testing.assert_array_equal(np.signbit(json.loads(text)), np.signbit(json.loads(reference)))
        ordinary = np.round(cases, decimals)
        ordinary = (ordinary == 0) | (np.abs(ordinary) >= 1e-4)  # json.dumps writes the others as 5e-06
        plain, = decimal_texts([cases[ordinary]], [decimals])
        assert plain == json.dumps(np.round(cases[ordinary], decimals).tolist(), separators=(",", ":"))
    # random numbers of every size, and empty parts between full ones
    rng = np.random.default_rng(7)
    values = rng.standard_normal(20_000) * 10.0 ** rng.integers(-8, 6, 20_000)
    parts = [values[:0], values[:9000], values[9000:9000], values[9000:], np.zeros((0, 4))]
    texts = decimal_texts(parts, [6, 6, 4, 4, 6])
    for text, part, decimals in zip(texts, parts, [6, 6, 4, 4, 6]):
        assert json.loads(text) == np.round(part.ravel(), decimals).tolist()
    # what JSON cannot hold and what is too large to be a pose go the way json.dumps takes them
    assert decimal_texts([np.array([1e13, 0.5])], [6]) == ["[10000000000000.0,0.5]"]
    assert decimal_texts([np.array([np.nan])], [6]) == ["[NaN]"]


def test_live_frames_as_json_dumps_writes_them():
    """Ten characters (Ready Player Me avatars with 67 morph targets and Mixamo X Bots with none) a
    second into a scene: the text parses to what json.dumps of the rounded lists parses to, to the bit."""
    scene = Scene(fps=60, quiet=True)
    for k in range(10):
        path = "talkinghead/avatars/brunette-t.glb" if k % 2 else "runxaway-models/Xbot.glb"
        scene.add_character(corpus_file(path), f"c{k}", position=(k - 4.5, 0.0, 0.0))
    scene.say("c1", "Hello there, how are you?")
    scene.run(1.0)
    characters = {}
    for name in scene.characters:
        rotations, root, morphs = scene.runtime.last_poses(name, 1)
        characters[name] = CharacterFrame(rotations[0], root[0], morphs[0])
    frame = LiveFrame(60, 1.0, 0.0, characters)
    assert sum(len(c.morphs) for c in characters.values()) > 0
    text = frame_text(frame)
    _same(text, _reference(frame))
    # the binary stream holds the same numbers, unrounded, as float32
    header = int.from_bytes(binary_frame(frame)[:4], "little")
    assert json.loads(binary_frame(frame)[4:4 + header])["characters"][1] == ["c1", len(characters["c1"].rotations),
                                                                              len(characters["c1"].morphs)]
