"""What controllers keep for a character is owned by what it serves: a gaze's turn and the face channels
a face expression detects by the runtime that plays the character, the packs a gesture, a posture or a
walk infuses and what a walk prepares of its pack by the character's asset (every scene playing a
character made of it shares them), a clip's
interpolation table by the clip. When the runtime and the character go, all of it goes, and no module of
infuse holds more than before."""
from __future__ import annotations

import gc
import sys
import weakref

import numpy as np

from infuse import Character, Motion, quaternions as quat
from infuse.packs import InfusedSpaces
from infuse.runtime import Clip, Runtime
from infuse.runtime.clip import continuous_rotations
from infuse_gaze import Gaze
from infuse_gaze.binding import GazeState
from infuse_gestures.controller import Gesture
from infuse_lipsync.controllers import FaceChannelsByMap, FaceExpression, face_channels
from infuse_locomotion import Locomotion
from infuse_locomotion.controller import PreparedWalks
from infuse_postures.controller import Posture
from infuse_reach.controller import Reach

from runtime_characters import synthetic_character

SMILE = ("mouthSmileLeft", "mouthSmileRight")
#: A map document declaring the smile's channels (the synthetic character's names alone are too few).
FACE_MAP = {"face": {"vocabularies": {"arkit": {name: name for name in SMILE}}}}
SECONDS = 1.5


def sway(skeleton, frames: int = 31, fps: float = 30.0) -> Motion:
    """A clip of ``frames`` frames on ``skeleton``: every joint turning back and forth a little."""
    phase = np.linspace(0.0, 2.0 * np.pi, frames)[:, None]
    angles = 0.1 * np.sin(phase + np.arange(skeleton.num_joints)[None])  # (F, J) radians
    rotations = quat.from_axis_angle(np.array([0.0, 0.0, 1.0]), angles)
    return Motion(skeleton, fps, rotations, np.zeros((frames, 3)), name="sway")


def play(names: tuple[str, ...], characters: dict | None = None) -> Runtime:
    """A runtime at 24 fps (the 30 fps clips are interpolated) whose characters (new ones, or those of
    ``characters`` by name) sway in a clip of their own, walk half a metre, gesture, stand in a posture,
    look at a point and smile, for SECONDS."""
    rt = Runtime(fps=24.0)
    for k, name in enumerate(names):
        character = (characters or {}).get(name) or synthetic_character(name, morphs=SMILE)
        rt.add_character(character, position=(1.5 * k, 0.0, 0.0))
        rt.activate(name, Clip(sway(character.skeleton), loop=True), 0.0)
        rt.activate(name, Locomotion("locomotion-male", target=(0.0, 0.5)), 0.0, priority=1)
        rt.activate(name, Posture("hands_on_hips"), 0.0)
        rt.activate(name, Gesture("beat_small_right"), 0.2)
        rt.activate(name, Gaze((1.0, 1.6, 2.0)), 0.0)
        rt.activate(name, FaceExpression("smile", map_file=dict(FACE_MAP)), 0.0, end_s=1.0)
    rt.run(SECONDS)
    return rt


def test_a_runtime_s_caches_go_when_it_goes():
    rt = play(("ann",))
    assert rt.motion("ann").morph_weights.max() > 0.5  # it smiled
    rig = rt.rig("ann")
    states = [rig.asset_state_of(InfusedSpaces), rig.state_of(GazeState), rig.state_of(FaceChannelsByMap),
              rig.asset_state_of(PreparedWalks)]
    # Filled while playing, not made here.
    assert sorted(states[0]) == ["gestures", "locomotion-male", "postures"] and len(states[2]) == 1 and len(states[3]) == 1
    assert np.any(states[1].groups != 0.0)
    packs = [space for _, space in states[0].values()]
    (walk,) = [a for a in rt.activities if isinstance(a.controller, Locomotion)]
    assert walk.binding is next(iter(states[3].values()))[2]  # the walk played what the asset keeps
    clip = next(a.controller.motion for a in rt.activities if isinstance(a.controller, Clip))
    table = continuous_rotations(clip)
    refs = [weakref.ref(x) for x in (rt, rig, *states, *packs, *states[2].values(), walk.binding, clip, table)]
    del rt, rig, states, packs, walk, clip, table
    gc.collect()
    assert [r() for r in refs if r() is not None] == []


def module_containers() -> dict[str, object]:
    """The containers and caches at the top of every infuse module (core and plugins), by name."""
    found = {}
    for name, module in list(sys.modules.items()):
        if not name.startswith("infuse") or module is None:
            continue
        for attr, value in list(vars(module).items()):
            if isinstance(value, (dict, list, set, weakref.WeakKeyDictionary, weakref.WeakValueDictionary)) \
                    or callable(getattr(value, "cache_info", None)):
                found[f"{name}.{attr}"] = value
    return found


def sizes(containers: dict[str, object]) -> dict[str, int]:
    return {k: v.cache_info().currsize if hasattr(v, "cache_info") else len(v) for k, v in containers.items()}


def test_no_module_holds_more_per_character():
    # As many characters as below first: what is read once for any character (pack documents, registry
    # tables) and what depends on how many play together, not on which (a gaze smoothing filter).
    play(("w1", "w2", "w3"))
    gc.collect()
    before = sizes(module_containers())
    rt = play(("ann", "bob", "cid"))
    # While the characters play, what is kept for them (their clips' tables, their skeletons' chain
    # plans, their infused packs) is held; once they and their runtime go, nothing is.
    assert {k for k, n in sizes(module_containers()).items() if n != before.get(k)}
    del rt
    gc.collect()
    assert {k: (before.get(k), n) for k, n in sizes(module_containers()).items() if n != before.get(k)} == {}


def test_runtimes_playing_characters_of_one_asset_share_its_infused_packs():
    ann = synthetic_character("ann", morphs=SMILE)
    again = Character("ann", ann.asset, mapping=ann.mapping)  # as a scene wraps the character it is given
    first, second = play(("ann",), {"ann": ann}), play(("ann",), {"ann": again})
    spaces = [rt.rig("ann").asset_state_of(InfusedSpaces)["gestures"][1] for rt in (first, second)]
    assert spaces[0] is spaces[1]
    walks = [next(a.binding for a in rt.activities if isinstance(a.controller, Locomotion)) for rt in (first, second)]
    assert walks[0] is walks[1]  # the walk prepared once for the asset
    assert first.rig("ann").state_of(GazeState) is not second.rig("ann").state_of(GazeState)
    kept = weakref.ref(spaces[0])
    prepared = weakref.ref(walks[0])
    del first, second, spaces, walks, ann, again
    gc.collect()
    assert kept() is None and prepared() is None


def test_a_reaching_pack_is_infused_once_for_the_asset():
    ann = synthetic_character("ann")
    again = Character("ann", ann.asset, mapping=ann.mapping)
    runtimes = []
    for character in (ann, again):
        rt = Runtime(fps=30.0)
        rt.add_character(character)
        rt.activate("ann", Reach((-0.2, 1.2, 0.3), hand="right"), 0.0)
        rt.run(0.5)
        runtimes.append(rt)
    spaces = [rt.rig("ann").asset_state_of(InfusedSpaces) for rt in runtimes]
    assert spaces[0] is spaces[1] and list(spaces[0]) == ["reaching"]
    kept = weakref.ref(spaces[0]["reaching"][1])
    del runtimes, spaces, ann, again, rt, character
    gc.collect()
    assert kept() is None


def test_face_channels_tell_map_documents_apart_by_their_content():
    rt = Runtime(fps=30.0)
    rt.add_character(synthetic_character("ann", morphs=SMILE))
    rig = rt.rig("ann")
    declared = face_channels(rig, {"face": {"vocabularies": {"arkit": {"mouthSmileLeft": "mouthSmileRight"}}}})
    same = face_channels(rig, {"face": {"vocabularies": {"arkit": {"mouthSmileLeft": "mouthSmileRight"}}}})
    plain = face_channels(rig, {})
    assert same is declared and plain is not declared
    assert declared.declared == ("arkit",) and plain.declared == ()
    assert face_channels(rig) is face_channels(rig, None) and len(rig.state_of(FaceChannelsByMap)) == 3
