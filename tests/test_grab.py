"""``sbm:grab`` in a scene, measured by forward kinematics on the written motion and the recorded object
track: the hand at the object at ``ready`` (the wrist half a hand short of it, the object by the palm),
the fingers closed by the stroke, the object carried at a
fixed place in the hand from the stroke to the release and left where the hand let it go; with the
reaching pack (the reach controller) and without one (arm IK, with the reason said)."""
from __future__ import annotations

import numpy as np
import pytest

import infuse
from infuse import quaternions as quat
from infuse.bml.model import CANNOT_CREATE_BEHAVIOR, NO_SUCH_TARGET
from infuse.errors import UsageError
from infuse.scene import Scene

from corpus_data import require_corpus
from runtime_characters import corpus_character

pytest.importorskip("infuse_manipulation")

FPS = 30.0
CUP = (-0.2, 1.3, 0.3)  # inside the reaching pack's right-hand examples on X Bot
GRAB = '<act><bml id="{id}"><sbm:grab id="g" target="{target}"{extra}/></bml></act>'


def _placed(cup, position, facing_deg):
    """``cup`` (in front of a character at the origin facing +Z) for one at ``position`` facing ``facing_deg``."""
    a = np.radians(facing_deg)
    x, y, z = cup
    return (position[0] + x * np.cos(a) + z * np.sin(a), y, position[2] - x * np.sin(a) + z * np.cos(a))


def _grab_scene(key: str, packs=(), release_at=3.5, position=(0.0, 0.0, 0.0), facing=0.0):
    require_corpus()
    scene = Scene(fps=FPS, idle=False, quiet=True)
    warnings = []
    scene.on("warningFeedback", warnings.append)
    scene.add_character(corpus_character(key), name="bob", packs=packs, position=position, facing=facing)
    scene.add_object("cup", _placed(CUP, position, facing), size=0.08)
    scene.bml("bob", GRAB.format(id="take", target="cup", extra=""), at=0.5)
    scene.bml("bob", GRAB.format(id="drop", target="cup", extra=' sbm:grab-state="release"'), at=release_at)
    scene.run(release_at + 1.5)
    return scene, warnings


@pytest.mark.parametrize("key, packs, position, facing", [("xbot", ("reaching",), (0.0, 0.0, 0.0), 0.0),
                                                          ("xbot", (), (0.0, 0.0, 0.0), 0.0),
                                                          ("rpm", (), (0.0, 0.0, 0.0), 0.0),
                                                          ("xbot", ("reaching",), (1.0, 0.0, 2.0), 90.0),
                                                          ("rpm", (), (-1.5, 0.0, 0.5), -135.0)])
def test_grab_carries_and_releases(key, packs, position, facing):
    scene, warnings = _grab_scene(key, packs, position=position, facing=facing)
    cup_at = np.array(_placed(CUP, position, facing))
    messages = [w.description for w in warnings]
    if packs:
        assert not messages, messages
    else:  # the real reason, once
        assert messages == ["<sbm:grab>: no reaching pack infused: the arm reaches by IK alone"]
    activation = scene.activities[("take", "g")].source
    ready, stroke = (int(round(activation.time(k) * FPS)) for k in ("ready", "stroke"))
    release = int(round(3.5 * FPS))
    motion = scene.motion("bob")
    g_rot, g_pos = infuse.motion_fk(motion)
    ix = scene.runtime.rig("bob").mapping.indices(motion.skeleton)
    wrist, middle = ix["r_wrist"], (ix["r_middle1"], ix["r_middle4"])
    cup = scene.object_track("cup")
    # the wrist stops half a hand short of the cup, which lies along the palm (wrist to middle knuckle)
    w, m = g_pos[ready, wrist], g_pos[ready, middle[0]]
    half_hand = 0.5 * np.linalg.norm(motion.skeleton.rest_global_positions[middle[0]] - motion.skeleton.rest_global_positions[wrist])
    t = np.clip((cup_at - w) @ (m - w) / ((m - w) @ (m - w)), 0.0, 1.0)
    palm = np.linalg.norm(cup_at - (w + t * (m - w)))
    print(key, packs, f"wrist {np.linalg.norm(w - cup_at) * 100:.2f} cm from the cup at ready (half a hand: "
                      f"{half_hand * 100:.2f} cm), the cup {palm * 100:.2f} cm from the palm line")
    assert abs(np.linalg.norm(w - cup_at) - half_hand) < 0.01 and palm < 0.05
    # the fingers close by the stroke and open again after the release
    span = np.linalg.norm(g_pos[:, middle[1]] - g_pos[:, middle[0]], axis=1)
    assert span[stroke] < 0.8 * span[0] and span[-1] == pytest.approx(span[0], abs=1e-6)
    # before the stroke the cup stays; from it to the release it keeps its place in the hand
    assert np.allclose(cup[:stroke], cup_at)
    in_hand = quat.rotate(quat.conjugate(g_rot[stroke:release, wrist]), cup[stroke:release] - g_pos[stroke:release, wrist])
    assert np.abs(in_hand - in_hand[0]).max() < 1e-6
    assert np.linalg.norm(cup[release - 1] - cup[stroke]) > 0.3  # carried back with the arm
    # from the release on it stays where the hand let it go
    assert np.allclose(cup[release:], cup[release], atol=1e-9)
    let_go = g_pos[release, wrist] + quat.rotate(g_rot[release, wrist], in_hand[0])
    assert np.linalg.norm(cup[release] - let_go) < 1e-6


def test_out_of_reach_is_not_taken():
    require_corpus()
    scene = Scene(fps=FPS, idle=False, quiet=True)
    warnings = []
    scene.on("warningFeedback", warnings.append)
    scene.add_character(corpus_character("xbot"), name="bob")
    scene.add_object("far", (0.0, 1.0, 1.5))
    scene.bml("bob", GRAB.format(id="take", target="far", extra=""), at=0.2)
    scene.run(3.0)
    messages = [w.description for w in warnings]
    assert any("out of reach" in m and "it is not taken" in m for m in messages), messages
    assert np.allclose(scene.object_track("far"), (0.0, 1.0, 1.5))


def test_grab_warnings_name_the_reason():
    require_corpus()
    scene = Scene(fps=FPS, idle=False, quiet=True)
    warnings = []
    scene.on("warningFeedback", warnings.append)
    scene.add_character(corpus_character("xbot"), name="bob")
    scene.add_character(corpus_character("rpm"), name="ann", position=(0.0, 0.0, 1.0))
    scene.bml("bob", GRAB.format(id="a", target="nothing", extra=""), at=0.0)
    scene.bml("bob", GRAB.format(id="b", target="ann", extra=""), at=0.0)
    scene.bml("bob", GRAB.format(id="c", target="cup", extra=' sbm:grab-state="release"'), at=0.0)
    got = {w.id: (w.type, w.description) for w in warnings}
    assert got["a:g"][0] == NO_SUCH_TARGET and "'nothing'" in got["a:g"][1]
    assert got["b:g"][0] == CANNOT_CREATE_BEHAVIOR and "is a character" in got["b:g"][1]
    assert got["c:g"][0] == CANNOT_CREATE_BEHAVIOR and "holds no 'cup'" in got["c:g"][1]
    assert not any("reaching pack" in d for _, d in got.values())


def test_frames_do_not_depend_on_the_block_size():
    """A grab, a pointing and a constraint give the same frames and object track in blocks of 1, 7 and 150."""
    require_corpus()
    bml = ('<act><bml id="b1"><sbm:grab id="g" target="cup"/>'
           '<sbm:constraint id="c" effector="l_wrist" target="lamp" start="0.5" end="2.5"/></bml></act>')
    release = GRAB.format(id="drop", target="cup", extra=' sbm:grab-state="release"')
    point = ('<bml xmlns="http://www.bml-initiative.org/bml/bml-1.0" id="b2">'
             '<pointing id="p" target="lamp" mode="RIGHT_HAND" stroke="3.2"/></bml>')
    results = []
    for block in (1, 7, 150):
        scene = Scene(fps=FPS, idle=False, quiet=True, block_frames=block)
        scene.add_character(corpus_character("xbot"), name="bob")
        scene.add_object("cup", CUP, size=0.08)
        scene.add_object("lamp", (0.35, 1.3, 0.3))
        scene.bml("bob", bml, at=0.2)
        scene.bml("bob", release, at=2.2)
        scene.bml("bob", point, at=2.4)
        scene.run(5.0)
        results.append((scene.motion("bob").local_rotations, scene.object_track("cup")))
    assert np.ptp(results[0][1], axis=0).max() > 0.1  # the cup was carried
    for rotations, cup in results[1:]:
        assert np.abs(quat.canonical_sign(rotations) - quat.canonical_sign(results[0][0])).max() < 1e-9
        assert np.abs(cup - results[0][1]).max() < 1e-9


def test_builder_grab_and_release():
    """``scene.grab`` and ``scene.release`` write the same sbm:grab blocks."""
    require_corpus()
    scene = Scene(fps=FPS, idle=False, quiet=True)
    warnings = []
    scene.on("warningFeedback", warnings.append)
    scene.add_character(corpus_character("xbot"), name="bob")
    scene.add_object("cup", CUP, size=0.08)
    scene.grab("bob", "cup", at=0.5, hand="right")
    scene.release("bob", "cup", at=3.0)
    scene.run(4.0)
    assert [w.description for w in warnings] == ["<sbm:grab>: no reaching pack infused: the arm reaches by IK alone"]
    cup = scene.object_track("cup")
    assert np.linalg.norm(cup[int(2.5 * FPS)] - CUP) > 0.3 and np.allclose(cup[int(3.0 * FPS):], cup[int(3.0 * FPS)])
    with pytest.raises(UsageError):
        scene.point("bob", "cup", hand="middle")
