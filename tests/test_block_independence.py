"""A scene gives the same frames whatever block size it is evaluated in: frame by frame (``step(1)``, as
the live server does), in blocks of 7 frames, in the default blocks of :meth:`Scene.run`, or, for a
live scene of ten characters, in blocks of varying sizes.

Joint positions are compared by forward kinematics on every frame of the written motion, morph weights
on every frame. The bound, 1e-9 m (and 1e-9 of a weight), is rounding: state carried from block to
block (position, heading, phase, planted feet) is summed in other groupings, which moves the last
bits of a float (at most 6e-12 m here). Nothing may decide on such bits or on the block: a foot's
contact share at exactly one half, a clip weighing under 1e-6 on some frames of a block, a time 1e-7
frames off a clip's frame, an IK angle of nearly zero taken from its cosine each set walks 1e-8 m
to 1.8 cm apart.
"""
from __future__ import annotations

import itertools
import warnings
from functools import lru_cache

import numpy as np
import pytest

from infuse.kinematics import motion_fk
from infuse.scene import Scene
from infuse.speech import tts_engine

from corpus_data import corpus_file

FPS = 30.0
#: Frame by frame, a small odd block, and the default (None).
BLOCKS = (1, 7, None)
BOUND_M = 1e-9


class OnceSpoken:
    """The espeak engine, each text synthesized once and its utterance reused: two syntheses of the same
    text may differ by some milliseconds (the library's state), which is not what is compared here."""

    def __init__(self):
        self.engine = tts_engine("espeak")
        self.utterances = {}

    def synthesize(self, text, *args, **kwargs):
        if text not in self.utterances:
            self.utterances[text] = self.engine.synthesize(text, *args, **kwargs)
        return self.utterances[text]


@lru_cache(maxsize=1)
def once_spoken() -> OnceSpoken:
    return OnceSpoken()


def evaluate(build, block: int | None, seconds: float) -> Scene:
    """The scene ``build(scene)`` makes, evaluated for ``seconds`` in blocks of ``block`` frames
    (1: :meth:`Scene.step` frame by frame; None: :meth:`Scene.run` with the default block size)."""
    options = dict(fps=FPS, quiet=True, tts=once_spoken())
    scene = Scene(**options) if block is None else Scene(**options, block_frames=block)
    build(scene)
    frames = int(round(seconds * FPS))
    if block == 1:
        for _ in range(frames):
            scene.step(1)
    else:
        scene.run(seconds)
    return scene


def joint_positions(scene: Scene, name: str) -> np.ndarray:
    """(F, J, 3) world joint positions, metres, of a character's scene motion."""
    return motion_fk(scene.motion(name))[1]


def largest_difference(runs: dict, name: str, block: int) -> tuple[float, int]:
    """The largest joint distance (metres) between the run in blocks of ``block`` and the default run,
    and the first frame where it exceeds :data:`BOUND_M` (-1: none)."""
    default, other = joint_positions(runs[None], name), joint_positions(runs[block], name)
    assert default.shape == other.shape
    per_frame = np.linalg.norm(default - other, axis=-1).max(axis=1)
    over = np.flatnonzero(per_frame > BOUND_M)
    return float(per_frame.max()), int(over[0]) if over.size else -1


def add_bob(scene: Scene, facing=0.0) -> None:
    scene.add_character(corpus_file("runxaway-models/Xbot.glb"), name="bob", position=(-1.6, 0.0, -1.2),
                        facing=facing, packs=["locomotion-male"])


def turning_walk(scene: Scene) -> None:
    """Bob, facing +Z, walks to a point 55 degrees to his right, turning on the way, and stops there."""
    add_bob(scene)
    scene.walk_to("bob", (0.4, 0.2), at=0.3)


def walk_stop_walk(scene: Scene) -> None:
    """Bob walks ahead, stops and settles into his idle, then walks back behind him (a turn from standing)."""
    add_bob(scene, facing=(0.0, 0.0, 0.9))
    scene.walk_to("bob", (0.0, 0.6), at=0.3)
    scene.walk_to("bob", (-1.0, -1.0), at=5.5)


def walk_handed_over(scene: Scene) -> None:
    """Bob turns toward a point, and on the way a second walk takes him elsewhere while he looks at a cup."""
    add_bob(scene)
    scene.add_object("cup", (1.0, 1.0, 1.0))
    scene.walk_to("bob", (0.4, 0.2), at=0.3)
    scene.gaze("bob", "cup", at=1.0)
    scene.walk_to("bob", (-2.0, 1.0), at=2.0)


WALKS = {"turning_walk": (turning_walk, 5.5), "walk_stop_walk": (walk_stop_walk, 11.5),
         "walk_handed_over": (walk_handed_over, 9.0)}


@pytest.fixture(scope="module", params=sorted(WALKS))
def walk_runs(request):
    build, seconds = WALKS[request.param]
    return request.param, {block: evaluate(build, block, seconds) for block in BLOCKS}


@pytest.mark.parametrize("block", [b for b in BLOCKS if b is not None])
def test_a_walk_does_not_depend_on_the_block_size(walk_runs, block):
    label, runs = walk_runs
    difference, frame = largest_difference(runs, "bob", block)
    assert difference < BOUND_M, f"{label} in blocks of {block}: {difference:.3g} m apart from frame {frame} on"


def test_the_walks_walk_and_stop(walk_runs):
    """The compared walks cover ground, turn and come to a stand (else the test would show nothing)."""
    label, runs = walk_runs
    scene = runs[None]
    hips = joint_positions(scene, "bob")[:, 0]
    travel = np.linalg.norm(np.diff(hips[:, [0, 2]], axis=0), axis=1)
    assert travel.sum() > 1.5, f"{label}: bob walked only {travel.sum():.2f} m"
    assert travel[-15:].max() < 0.01, f"{label}: bob still moves at the end ({travel[-15:].max() * FPS:.2f} m/s)"
    walks = scene.stagehands["locomotion"].walks["bob"]
    assert walks[-1].settled is not None, f"{label}: the last walk never handed over to the idle"
    heading = np.degrees(np.ptp([w.final.heading for w in walks] + [0.0]))
    assert heading > 30.0, f"{label}: the walks turned only {heading:.1f} degrees"


def conversation(scene: Scene) -> None:
    """Ann and Bob face each other (blinking, breathing, saccades); they gaze at each other, Bob nods,
    Ann speaks (lip sync), reaches for a cup, glances at it and gestures."""
    add_bob(scene, facing="ann")
    scene.add_character(corpus_file("talkinghead/avatars/brunette-t.glb"), name="ann", position=(0.0, 0.0, 0.6),
                        facing="bob", packs=["locomotion-female", "reaching", "gestures"])
    scene.add_object("cup", (0.25, 1.0, 0.15), size=0.09)
    scene.bml("bob", """
<bml xmlns="http://www.bml-initiative.org/bml/bml-1.0" xmlns:sbm="http://ict.usc.edu" id="bob_look">
  <gazeShift id="g1" target="ann" influence="HEAD"/>
  <sbm:saccade id="sc1" mode="listen"/>
  <head id="nod" lexeme="NOD" repetition="2" amount="0.6" start="1.2"/>
</bml>""", at=0.0)
    scene.bml("ann", """
<bml xmlns="http://www.bml-initiative.org/bml/bml-1.0" xmlns:sbm="http://ict.usc.edu" id="ann_talk">
  <gazeShift id="g1" target="bob" influence="SHOULDER"/>
  <sbm:saccade id="sc1" mode="talk"/>
  <speech id="speech" start="0.5"><text>Could you pass me that <sync id="cup"/>cup? Never mind.</text></speech>
  <sbm:reach id="reach" target="cup" sbm:action="touch" sbm:reach-type="right" start="speech:cup"/>
  <gaze id="look_cup" target="cup" influence="HEAD" start="speech:cup" end="reach:stroke+0.4"/>
  <gesture id="beat" lexeme="BEAT" stroke="1.2"/>
</bml>""", at=0.0)


CONVERSATION_S = 6.0


@pytest.fixture(scope="module")
def conversation_runs():
    return {block: evaluate(conversation, block, CONVERSATION_S) for block in BLOCKS}


@pytest.mark.parametrize("block", [b for b in BLOCKS if b is not None])
def test_the_other_controllers_do_not_depend_on_the_block_size(conversation_runs, block):
    runs = conversation_runs
    for name in ("ann", "bob"):
        difference, frame = largest_difference(runs, name, block)
        assert difference < BOUND_M, f"{name} in blocks of {block}: {difference:.3g} m apart from frame {frame} on"
        weights, other = runs[None].runtime.morph_weights(name), runs[block].runtime.morph_weights(name)
        assert weights.shape == other.shape
        if weights.size:
            assert np.abs(weights - other).max() < BOUND_M, f"{name}'s morph weights in blocks of {block}"


def test_the_conversation_moves_the_body_and_the_face(conversation_runs):
    """Every controller compared above shows (else the test would show nothing for it)."""
    scene = conversation_runs[None]
    kinds = {a.controller.kind for a in scene.runtime.activities}
    for kind in ("gaze", "head", "reach", "blink", "breathing", "saccade", "speech", "clip"):
        assert kind in kinds, f"no {kind} activity in the conversation: {sorted(kinds)}"
    weights = scene.runtime.morph_weights("ann")
    assert np.ptp(weights, axis=0).max() > 0.2, "ann's face hardly moved: no lip sync or blinks to compare"
    hand = joint_positions(scene, "ann")
    assert np.ptp(hand, axis=0).max() > 0.2, "ann hardly moved: no reach or gesture to compare"


#: A live scene's cast: ten characters at 60 fps, X Bot and a Ready Player Me avatar by turns.
RING_FPS, RING_COUNT, RING_S = 60.0, 10, 5.5
RING_CAST = (("runxaway-models/Xbot.glb", "locomotion-male"), ("talkinghead/avatars/brunette-t.glb", "locomotion-female"))
#: Frame by frame against blocks of these sizes in turn (a live loop's blocks vary with the load).
MIXED_BLOCKS = ((7, 3, 16, 1, 2), (32, 5, 11))


def walking_ring(fps: float = RING_FPS) -> Scene:
    """Ten characters in a ring facing its centre, each gazing at the next with listening saccades
    (blinking, breathing); four walk from standing: toward the middle, across the ring, outward, and
    sideways (turning on the spot first); at 3.5 s the first two are sent on to the middle (the first
    has come to a stand by then, the second is still walking). Walks start and stop as the idle
    fades out and in, where a foot's contact share passes through one half."""
    scene = Scene(fps=fps, quiet=True)
    radius = 1.5 + 0.25 * RING_COUNT
    for k in range(RING_COUNT):
        path, pack = RING_CAST[k % len(RING_CAST)]
        angle = 2.0 * np.pi * k / RING_COUNT
        scene.add_character(corpus_file(path), name=f"c{k}", position=(radius * np.sin(angle), 0.0, radius * np.cos(angle)),
                            facing=(0.0, 0.0, 0.0), packs=[pack])
    names = list(scene.characters)
    for k, name in enumerate(names):
        scene.bml(name, f'<bml xmlns="http://www.bml-initiative.org/bml/bml-1.0" xmlns:sbm="http://ict.usc.edu" '
                        f'id="look{k}"><gazeShift id="g" target="{names[(k + 1) % RING_COUNT]}"/>'
                        f'<sbm:saccade id="s" mode="listen"/></bml>')
    for k, name in enumerate(names[:4]):
        x, _, z = (float(v) for v in scene.runtime.rig(name).position)
        goals = ((0.2 * x, 0.2 * z), (-0.5 * x, -0.5 * z), (1.6 * x, 1.6 * z), (x + 2.0 * z / radius, z - 2.0 * x / radius))
        scene.walk_to(name, goals[k])
    for name in names[:2]:
        scene.walk_to(name, (0.0, 0.0), at=3.5)
    return scene


def stepped(blocks: tuple[int, ...], fps: float = RING_FPS, seconds: float = RING_S) -> Scene:
    """:func:`walking_ring` at ``fps`` evaluated for ``seconds`` in blocks of ``blocks`` frames in turn."""
    scene = walking_ring(fps)
    left = int(round(seconds * fps))
    for size in itertools.cycle(blocks):
        if left <= 0:
            return scene
        scene.step(min(size, left))
        left -= size
    raise AssertionError("unreachable")


@pytest.fixture(scope="module")
def ring_runs():
    """Each partition's scene, and the RuntimeWarnings (a division by zero, a NaN...) raised running them."""
    with warnings.catch_warnings(record=True) as raised:
        warnings.simplefilter("always", RuntimeWarning)
        runs = {blocks: stepped(blocks) for blocks in ((1,), *MIXED_BLOCKS)}
    return runs, [w for w in raised if issubclass(w.category, RuntimeWarning)]


@pytest.mark.parametrize("blocks", MIXED_BLOCKS, ids=lambda b: "-".join(map(str, b)))
def test_a_live_scene_gives_the_same_frames_in_any_blocks(ring_runs, blocks):
    """Every joint of every character, by FK on every frame, and every morph weight, as frame by frame."""
    single, mixed = ring_runs[0][(1,)], ring_runs[0][blocks]
    for name in single.characters:
        one, other = joint_positions(single, name), joint_positions(mixed, name)
        assert one.shape == other.shape == (int(round(RING_S * RING_FPS)), one.shape[1], 3)
        apart = np.linalg.norm(one - other, axis=-1)
        frame, joint = np.unravel_index(np.argmax(apart), apart.shape)
        assert apart.max() < BOUND_M, (f"{name} in blocks of {blocks}: {apart.max():.3g} m from frame by frame "
                                             f"at frame {frame}, joint {single.motion(name).skeleton.names[joint]}")
        weights, weights_mixed = single.runtime.morph_weights(name), mixed.runtime.morph_weights(name)
        assert weights.shape == weights_mixed.shape
        if weights.size:
            assert np.abs(weights - weights_mixed).max() < BOUND_M, f"{name}'s morph weights in blocks of {blocks}"


def test_the_live_scene_walks_stops_and_looks(ring_runs):
    """The compared scene does what it is meant to (else the test above would show nothing): four
    characters cover ground, the others stand, the first comes to a stand and walks on, and the
    walks, gazes, saccades, blinks and breathing all play."""
    scene = ring_runs[0][(1,)]
    names = list(scene.characters)
    for k, name in enumerate(names):
        positions = joint_positions(scene, name)
        travel = np.linalg.norm(np.diff(positions[:, 0, [0, 2]], axis=0), axis=1)
        if k < 4:
            assert travel.sum() > 1.0, f"{name} walked only {travel.sum():.2f} m"
        else:
            assert travel.sum() < 0.2, f"{name} should stand, moved {travel.sum():.2f} m"
        if k == 0:  # from the ring toward the middle, it stops before the middle and walks on to it
            still = travel[int(3.0 * RING_FPS):int(3.6 * RING_FPS)].min() * RING_FPS
            assert still < 0.05, f"{name} did not stop before walking on (at least {still:.2f} m/s)"
            assert travel[int(3.6 * RING_FPS):].sum() > 0.5, f"{name} did not walk on"
    kinds = {a.controller.kind for a in scene.runtime.activities}
    for kind in ("locomotion", "gaze", "saccade", "blink", "breathing"):
        assert kind in kinds, f"no {kind} activity in the scene: {sorted(kinds)}"


def test_the_live_scene_raises_no_runtime_warning(ring_runs):
    """Evaluating the scene in any blocks divides by no zero and makes no NaN."""
    raised = ring_runs[1]
    assert not raised, "; ".join(f"{w.filename}:{w.lineno}: {w.message}" for w in raised)
    for scene in ring_runs[0].values():
        for name in scene.characters:
            assert np.isfinite(joint_positions(scene, name)).all(), f"{name}: joint positions not finite"


def test_a_saccade_of_no_duration_is_at_its_offset_from_its_start():
    """A held saccade row of no duration (a placeholder row, or a saccade that takes no time) gives
    the offset before it until its start and its offset from then on, with no division by zero."""
    from infuse_saccade.controller import SaccadeState

    # start, duration, offset (2), offset before (2); the second row: no saccade yet.
    held = np.array([[0.1, 0.0, 3.0, -2.0, 1.0, 1.0], [-np.inf, 1.0, 5.0, 5.0, 5.0, 5.0], [0.0, 0.05, 4.0, 0.0, 0.0, 0.0]])
    t = np.array([[0.0, 0.1, 0.2], [0.0, 0.1, 0.2], [0.0, 0.025, 0.2]])
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        path = SaccadeState.path(held, t)
    assert np.array_equal(path[0], [[1.0, 1.0], [3.0, -2.0], [3.0, -2.0]])
    assert np.array_equal(path[1], np.zeros((3, 2)))
    # A saccade with a duration still eases out: none of its way at its start, all of it at its end.
    assert np.array_equal(path[2, [0, 2]], [[0.0, 0.0], [4.0, 0.0]]) and 0.0 < path[2, 1, 0] < 4.0


def test_a_live_scene_at_120_fps_gives_the_same_frames_in_any_blocks():
    """At 120 fps a foot let go holds its ball for more frames of a block: the frames after one still
    held take its heel's rise and ball as frame by frame (the first 1.5 s: starts and a turn on the spot)."""
    seconds, fps = 1.5, 120.0
    single, mixed = stepped((1,), fps, seconds), stepped(MIXED_BLOCKS[0], fps, seconds)
    for name in single.characters:
        apart = np.linalg.norm(joint_positions(single, name) - joint_positions(mixed, name), axis=-1)
        frame, joint = np.unravel_index(np.argmax(apart), apart.shape)
        assert apart.max() < BOUND_M, (f"{name} at {fps:g} fps in blocks of {MIXED_BLOCKS[0]}: {apart.max():.3g} m from "
                                       f"frame by frame at frame {frame}, joint {single.motion(name).skeleton.names[joint]}")
