"""BML <gesture> realized with the gestures pack, measured on the output by FK: strokes on their sync
references, the authored stroke pose reached on corpus characters, co-articulation, holds, repeats and
amplitude; unknown lexemes warn at scheduling."""
from __future__ import annotations

import numpy as np
import pytest

from infuse import quaternions as quat
from infuse.bml import Scheduler, parse_bml
from infuse.kinematics import forward_kinematics
from infuse.scene import Scene

from infuse.packs import space_on
from runtime_characters import corpus_character

FPS = 30.0
CACHE = None  # set per session below


@pytest.fixture(autouse=True, scope="module")
def _pack_cache(tmp_path_factory):
    global CACHE
    CACHE = tmp_path_factory.mktemp("infusions")
BML = '<bml xmlns="http://www.bml-initiative.org/bml/bml-1.0" id="{id}" characterId="bob">{body}</bml>'


def play(key: str, body: str, fps: float = FPS):
    """A scene with corpus character ``key`` as "bob" (standing in the male locomotion pack's idle) playing
    BML ``body``; (scene, motion)."""
    scene = Scene(fps=fps, tts=None, quiet=True, idle=False, pack_cache=CACHE)
    scene.add_character(corpus_character(key), "bob", packs=("locomotion-male",))
    scene.bml("bob", BML.format(id="b1", body=body), at=0.0)
    scene.run(scene.end_time + 2.0 / fps)
    return scene, scene.motion("bob")


def chest_wrist(rig, motion, side: str) -> np.ndarray:
    """(F, 3) the wrist in the frame of the joint the arm hangs from (the chest): what the gesture moves."""
    sk = motion.skeleton
    shoulder = rig.joint(f"{side}_acromioclavicular") or rig.joint(f"{side}_shoulder")
    chest = sk.parents[shoulder]
    g_rot, g_pos = forward_kinematics(sk, motion.local_rotations, motion.root_translations, motion.joint_translations)
    wrist = rig.joint(f"{side}_wrist")
    return quat.rotate(quat.conjugate(g_rot[:, chest]), g_pos[:, wrist] - g_pos[:, chest])


def authored_stroke(rig, clip: str, side: str) -> tuple[np.ndarray, float]:
    """The wrist at the authored stroke of ``clip`` retargeted onto the character (chest frame), and the
    authored stroke time."""
    space = space_on(rig, "gestures")
    c = space.clips[clip]
    frame = int(round(c.stroke * c.motion.fps))
    one = c.motion.replace(local_rotations=c.motion.local_rotations[frame:frame + 1],
                           root_translations=c.motion.root_translations[frame:frame + 1],
                           joint_translations=None if c.motion.joint_translations is None
                           else c.motion.joint_translations[frame:frame + 1])
    return chest_wrist(rig, one, side)[0], c.stroke


@pytest.mark.parametrize("key", ["xbot", "rpm"])
def test_beat_strokes_land_within_a_frame_of_their_sync_reference(key):
    body = ('<gesture id="g1" lexeme="BEAT" stroke="1.2"/>'
            '<gesture id="g2" lexeme="BEAT_LARGE" mode="LEFT_HAND" stroke="g1:stroke + 1.37"/>')
    scene, motion = play(key, body)
    rig = scene.runtime.rig("bob")
    for name, side, wanted in (("g1", "r", 1.2), ("g2", "l", 2.57)):
        activation = scene.activities[("b1", name)].source
        assert activation.time("stroke") == pytest.approx(wanted, abs=1e-9)
        wrist = chest_wrist(rig, motion, side)
        target, _ = authored_stroke(rig, activation.parameters["clip"], side)
        # The beat's stroke is the one frame its wrist passes the authored stroke point.
        window = np.arange(int(activation.time("strokeStart") * FPS), int(np.ceil(activation.time("strokeEnd") * FPS)) + 1)
        closest = window[np.argmin(np.linalg.norm(wrist[window] - target, axis=-1))]
        assert abs(closest / FPS - wanted) <= 1.0 / FPS + 1e-9, (name, closest / FPS, wanted)


@pytest.mark.parametrize("key", ["xbot", "rpm", "utah"])
def test_strokes_land_within_a_frame_after_coarticulation_and_at_other_speeds(key):
    """An offer, a large beat entered from the offer's stroke (co-articulated) at speed 1.5, then a slow
    beat (speed 0.7) on the other hand: each stroke is the frame its wrist passes the authored stroke pose."""
    body = ('<gesture id="g1" lexeme="OFFER" stroke="1.0"/>'
            '<gesture id="g2" lexeme="BEAT_LARGE" speed="1.5" stroke="g1:stroke + 0.9"/>'
            '<gesture id="g3" lexeme="BEAT" mode="LEFT_HAND" speed="0.7" stroke="2.73"/>')
    scene, motion = play(key, body)
    rig = scene.runtime.rig("bob")
    assert scene.activities[("b1", "g2")].controller.enter_ready  # it follows on from the offer's stroke
    for name, side, wanted in (("g1", "r", 1.0), ("g2", "r", 1.9), ("g3", "l", 2.73)):
        activation = scene.activities[("b1", name)].source
        assert activation.time("stroke") == pytest.approx(wanted, abs=1e-9)
        wrist = chest_wrist(rig, motion, side)
        target, _ = authored_stroke(rig, activation.parameters["clip"], side)
        window = np.arange(int(activation.time("strokeStart") * FPS), int(np.ceil(activation.time("strokeEnd") * FPS)) + 1)
        distance = np.linalg.norm(wrist[window] - target, axis=-1)
        closest = window[np.argmin(distance)]
        assert abs(closest / FPS - wanted) <= 1.0 / FPS + 1e-9, (name, closest / FPS, wanted)
        assert distance.min() < 0.005, (name, distance.min())  # metres: the authored stroke pose itself


@pytest.mark.parametrize("key", ["xbot", "rpm", "utah"])
@pytest.mark.parametrize("lexeme,mode", [("OFFER", "RIGHT_HAND"), ("REJECT", "LEFT_HAND"), ("THUMBS_UP", "RIGHT_HAND"),
                                         ("THINK", "LEFT_HAND"), ("SHRUG", "BOTH_HANDS")])
def test_wrist_reaches_the_authored_stroke_pose_at_the_stroke(key, lexeme, mode):
    scene, motion = play(key, f'<gesture id="g1" lexeme="{lexeme}" mode="{mode}" stroke="1.5"/>')
    rig = scene.runtime.rig("bob")
    clip = scene.activities[("b1", "g1")].source.parameters["clip"]
    frame = int(round(1.5 * FPS))
    arm = rig.joint("l_elbow")
    arm_m = float(np.linalg.norm(rig.skeleton.rest_translations[arm]) + np.linalg.norm(
        rig.skeleton.rest_global_positions[rig.joint("l_wrist")] - rig.skeleton.rest_global_positions[arm]))
    for side in (("l", "r") if mode == "BOTH_HANDS" else (mode[0].lower(),)):
        wrist = chest_wrist(rig, motion, side)
        target, _ = authored_stroke(rig, clip, side)
        rest = wrist[0]
        assert np.linalg.norm(target - rest) > 0.2 * arm_m  # the stroke is away from rest
        assert np.linalg.norm(wrist[frame] - target) < 0.01, (side, wrist[frame], target)


def test_the_retargeted_stroke_keeps_the_authored_arm_direction():
    """On Xbot and the RPM avatar the shoulder-to-wrist direction at the stroke is the canonical clip's."""
    from infuse.packs import load_pack

    pack = load_pack("gestures")
    canonical = pack.motions["offer_right"]
    sk = canonical.skeleton
    stroke = int(round(pack.require_built()["clips"][[c["name"] for c in pack.require_built()["clips"]].index("offer_right")]
                       ["stroke"] * canonical.fps))
    _, pos = forward_kinematics(sk, canonical.local_rotations[stroke:stroke + 1], canonical.root_translations[stroke:stroke + 1])
    index = pack.mapping.indices(sk)
    authored = pos[0, index["r_wrist"]] - pos[0, index["r_shoulder"]]
    for key in ("xbot", "rpm"):
        scene, motion = play(key, '<gesture id="g1" lexeme="OFFER" stroke="1.5"/>')
        rig = scene.runtime.rig("bob")
        _, out = forward_kinematics(motion.skeleton, motion.local_rotations, motion.root_translations, motion.joint_translations)
        f = int(round(1.5 * FPS))
        got = out[f, rig.joint("r_wrist")] - out[f, rig.joint("r_shoulder")]
        got = quat.rotate(quat.conjugate(rig.rotation), got)
        cos = float(np.dot(got, authored) / np.linalg.norm(got) / np.linalg.norm(authored))
        assert np.degrees(np.arccos(min(cos, 1.0))) < 12.0, key


def wrist_height(rig, motion, side: str) -> np.ndarray:
    """(F,) height of the wrist above the ground, metres (the character stands still)."""
    _, g_pos = forward_kinematics(motion.skeleton, motion.local_rotations, motion.root_translations, motion.joint_translations)
    return g_pos[:, rig.joint(f"{side}_wrist"), 1]


def _lowest_between(scene, motion, first: str, second: str) -> tuple[float, float, float]:
    """Height (metres) of the right wrist at rest, at the first stroke's end, and its lowest between the
    first gesture's stroke end and the second's stroke."""
    rig = scene.runtime.rig("bob")
    wrist = wrist_height(rig, motion, "r")
    a = int(round(scene.activities[("b1", first)].source.time("strokeEnd") * FPS))
    b = int(round(scene.activities[("b1", second)].source.time("stroke") * FPS))
    return float(wrist[0]), float(wrist[a]), float(wrist[a:b + 1].min())


def test_two_gestures_in_a_row_do_not_return_to_rest():
    near = '<gesture id="g1" lexeme="OFFER" stroke="1.2"/><gesture id="g2" lexeme="BEAT" stroke="2.3"/>'
    far = '<gesture id="g1" lexeme="OFFER" stroke="1.2"/><gesture id="g2" lexeme="BEAT" stroke="5.3"/>'
    rest, held, lowest = _lowest_between(*play("xbot", near), "g1", "g2")
    assert held - rest > 0.15  # the offered hand is well above where it hangs
    assert lowest - rest > 0.75 * (held - rest), (rest, held, lowest)
    rest_far, held_far, lowest_far = _lowest_between(*play("xbot", far), "g1", "g2")
    assert lowest_far - rest_far < 0.05 * (held_far - rest_far)  # apart, the hand does go back down


def test_a_later_stroke_end_holds_the_stroke_pose():
    scene, motion = play("xbot", '<gesture id="g1" lexeme="BEAT" stroke="1.0" strokeEnd="2.0"/>')
    rig = scene.runtime.rig("bob")
    activation = scene.activities[("b1", "g1")].source
    assert activation.time("strokeEnd") == pytest.approx(2.0)
    wrist = chest_wrist(rig, motion, "r")
    target, _ = authored_stroke(rig, activation.parameters["clip"], "r")
    authored = scene.activities[("b1", "g1")].controller.authored
    post_stroke_s = authored["strokeEnd"] - authored["stroke"]
    # From the stroke until the authored post-stroke movement must begin, the wrist stays at the stroke.
    held = wrist[int(round(1.0 * FPS)):int((2.0 - post_stroke_s) * FPS) + 1]
    assert len(held) > 20
    assert np.linalg.norm(held - target, axis=-1).max() < 0.005


def test_repeated_strokes():
    scene, motion = play("xbot", '<gesture id="g1" lexeme="BEAT_LARGE" repeats="3" stroke="1.0"/>')
    rig = scene.runtime.rig("bob")
    activation = scene.activities[("b1", "g1")].source
    height = wrist_height(rig, motion, "r")
    a, b = int(activation.time("strokeStart") * FPS), int(np.ceil(activation.time("strokeEnd") * FPS))
    h = height[a:b + 1]
    minima = np.nonzero((h[1:-1] < h[:-2]) & (h[1:-1] <= h[2:]))[0]
    assert len(minima) == 3, minima
    assert abs((a + 1 + minima[0]) / FPS - 1.0) <= 1.0 / FPS


def straight_fingers(rig, motion, side: str, frames: np.ndarray) -> np.ndarray:
    """(len(frames), 4) whether index, middle, ring and pinky are held straight: the knuckle-to-last-joint
    chord over the two bones' lengths above 0.9 (a curled finger's is about 0.75)."""
    _, g_pos = forward_kinematics(motion.skeleton, motion.local_rotations[frames], motion.root_translations[frames],
                                  None if motion.joint_translations is None else motion.joint_translations[frames])
    out = []
    for finger in ("index", "middle", "ring", "pinky"):
        p1, p2, p3 = (g_pos[:, rig.joint(f"{side}_{finger}{k}")] for k in (1, 2, 3))
        bones = np.linalg.norm(p2 - p1, axis=-1) + np.linalg.norm(p3 - p2, axis=-1)
        out.append(np.linalg.norm(p3 - p1, axis=-1) / bones > 0.9)
    return np.stack(out, axis=-1)


@pytest.mark.parametrize("key", ["xbot", "rpm"])
def test_a_count_shows_one_more_finger_with_each_repeated_stroke(key):
    from infuse_gestures.timewarp import stroke_times

    scene, motion = play(key, '<gesture id="g1" lexeme="COUNT" repeats="4" stroke="1.0"/>')
    rig = scene.runtime.rig("bob")
    activity = scene.activities[("b1", "g1")]
    gesture = activity.controller
    strokes = activity.start_s + stroke_times(gesture.phases, gesture.authored, 4)
    assert strokes[0] == pytest.approx(1.0)
    shown = straight_fingers(rig, motion, "r", np.round(strokes * FPS).astype(int))
    # One finger, then two, three, four: index first, each stroke straightening the next.
    assert shown.tolist() == [[k < n for k in range(4)] for n in (1, 2, 3, 4)], shown
    # The hand changes between strokes without a jump: no finger joint turns more than 20 degrees a frame.
    fingers = [rig.joint(f"r_{f}{k}") for f in ("index", "middle", "ring", "pinky") for k in (1, 2)]
    q = motion.local_rotations[:, fingers]
    assert np.degrees(quat.angle_between(q[1:], q[:-1])).max() < 20.0


def test_amplitude_scales_the_stroke():
    def travel(amplitude: float) -> float:
        scene, motion = play("xbot", f'<gesture id="g1" lexeme="CONTRAST" amplitude="{amplitude}" stroke="1.2"/>')
        activation = scene.activities[("b1", "g1")].source
        wrist = chest_wrist(scene.runtime.rig("bob"), motion, "r")
        ready, stroke = (int(round(activation.time(p) * FPS)) for p in ("strokeStart", "stroke"))
        return float(np.linalg.norm(wrist[stroke] - wrist[ready]))

    full, half = travel(1.0), travel(0.5)
    assert 0.35 < half / full < 0.65, (half, full)


def test_unknown_lexemes_warn_at_scheduling_naming_the_lexeme():
    scheduler = Scheduler()
    scheduler.submit(parse_bml(BML.format(id="b1", body='<gesture id="g1" lexeme="JUGGLE_FLAMINGOS" stroke="1"/>'
                                                         '<gesture id="g2" lexeme="greta_beat4" stroke="2"/>')))
    warnings = [e for e in scheduler.feedback.log if e.kind == "warningFeedback"]
    assert any("JUGGLE_FLAMINGOS" in w.description and w.id == "b1:g1" for w in warnings), warnings
    assert not any(w.id == "b1:g2" for w in warnings)


def test_lexemes_map_onto_the_pack_by_word_and_hand():
    from infuse_bml_behaviours import gesture_lexicon

    assert gesture_lexicon.lookup("BEAT", None)[1] == "beat_medium_right"
    assert gesture_lexicon.lookup("greta_beat4", "LEFT_HAND")[1] == "beat_medium_left"
    assert gesture_lexicon.lookup("refuse_Ges_B", None)[1] == "reject_both"
    assert gesture_lexicon.lookup("greet_Ges_L", None)[1] == "wave_left"
    gesture, clip, _, note = gesture_lexicon.lookup("THINK", "BOTH_HANDS")
    assert clip == "chin_touch_right" and "both" in note
    assert gesture_lexicon.lookup("JUGGLE_FLAMINGOS", None) is None


def test_stroke_on_a_word_of_speech_lands_within_a_frame():
    """``stroke="s1:tm1"``: the stroke lands on the synthesized word's time, measured on the wrist."""
    scene = Scene(fps=FPS, quiet=True, idle=False, pack_cache=CACHE)
    scene.add_character(corpus_character("rpm"), "bob", packs=("locomotion-male",))
    if scene.speech.unavailable:
        pytest.skip(f"no speech synthesis: {scene.speech.unavailable}")
    scene.bml("bob", BML.format(id="b1", body='<speech id="s1"><text>I would like to <sync id="tm1"/>offer you '
                                               'this.</text></speech><gesture id="g1" lexeme="BEAT" stroke="s1:tm1"/>'),
              at=0.0)
    scene.run(scene.end_time + 2.0 / FPS)
    word = scene.activities[("b1", "s1")].source.time("tm1")
    activation = scene.activities[("b1", "g1")].source
    assert activation.time("stroke") == pytest.approx(word, abs=1e-9) and word > 0.3
    rig = scene.runtime.rig("bob")
    wrist = chest_wrist(rig, scene.motion("bob"), "r")
    target, _ = authored_stroke(rig, activation.parameters["clip"], "r")
    window = np.arange(int(activation.time("strokeStart") * FPS), int(np.ceil(activation.time("strokeEnd") * FPS)) + 1)
    closest = window[np.argmin(np.linalg.norm(wrist[window] - target, axis=-1))]
    assert abs(closest / FPS - word) <= 1.0 / FPS + 1e-9, (closest / FPS, word)


def test_the_pack_has_every_gesture_for_each_hand_with_its_phases():
    from infuse.packs import load_pack

    doc = load_pack("gestures").require_built()
    clips = {c["name"]: c for c in doc["clips"]}
    for gesture in ("beat_small", "beat_medium", "beat_large", "offer", "reject", "shrug", "count", "wave", "this_big",
                    "cycle", "contrast", "self_point", "chin_touch", "thumbs_up", "past", "future", "here", "tiny", "belly"):
        for hand in ("left", "right"):
            c = clips[f"{gesture}_{hand}"]
            times = [0.0] + [c["sync"][p] for p in ("ready", "strokeStart", "stroke", "strokeEnd", "relax")] + [c["duration"]]
            assert all(b > a for a, b in zip(times, times[1:])), (c["name"], times)
            assert c["hand"] == hand and gesture in c["tags"]
    assert not doc["report"]


@pytest.mark.parametrize("sync,where", [("{ ready = 0.4 }", "clips[0].sync"),
                                        ("{ ready = 0.4, stroke = 0.3 }", "clips[0].sync.stroke"),
                                        ("{ stroke = 0.4, apex = 0.5 }", "clips[0].sync")])
def test_bad_gesture_phases_in_a_manifest_name_the_place(tmp_path, sync, where):
    from infuse.errors import InputError
    from infuse.packs.manifest import read_manifest

    (tmp_path / "manifest.toml").write_text('[pack]\nname = "g"\nversion = "1"\nkind = "gesture"\nskeleton = "s.bvh"\n\n'
                                            f'[[clips]]\nfile = "a.bvh"\nrole = "gesture"\nsync = {sync}\n')
    with pytest.raises(InputError) as caught:
        read_manifest(tmp_path / "manifest.toml")
    assert where in str(caught.value) and "manifest.toml" in str(caught.value)


def test_a_gesture_plays_over_a_walk():
    """The gesture is a layer: the walk goes on below it and the arm still reaches its stroke pose."""
    body = ('<locomotion id="w1" target="0 3" manner="walk"/>'
            '<gesture id="g1" lexeme="OFFER" stroke="2.0"/>')
    scene, motion = play("xbot", body)
    rig = scene.runtime.rig("bob")
    clip = scene.activities[("b1", "g1")].source.parameters["clip"]
    wrist = chest_wrist(rig, motion, "r")
    target, _ = authored_stroke(rig, clip, "r")
    f = int(round(2.0 * FPS))
    assert np.linalg.norm(wrist[f] - target) < 0.01
    _, g_pos = forward_kinematics(motion.skeleton, motion.local_rotations, motion.root_translations, motion.joint_translations)
    pelvis = g_pos[:, rig.joint("base")]
    assert np.linalg.norm(pelvis[f + 15, [0, 2]] - pelvis[f - 15, [0, 2]]) > 0.3  # still walking at the stroke


def test_gestures_of_different_hands_overlap_without_cutting_each_other():
    alone = play("xbot", '<gesture id="g1" lexeme="OFFER" mode="RIGHT_HAND" stroke="1.2"/>')
    both = play("xbot", '<gesture id="g1" lexeme="OFFER" mode="RIGHT_HAND" stroke="1.2"/>'
                        '<gesture id="g2" lexeme="BEAT" mode="LEFT_HAND" stroke="1.5"/>')
    rig = alone[0].runtime.rig("bob")
    right_alone, right_both = (chest_wrist(rig, m, "r") for _, m in (alone, both))
    frames = min(len(right_alone), len(right_both))
    assert np.abs(right_alone[:frames] - right_both[:frames]).max() < 1e-6
    assert both[0].activities[("b1", "g1")].end_s == pytest.approx(alone[0].activities[("b1", "g1")].end_s)


def test_speed_shortens_the_phases_and_the_stroke_still_lands():
    scene, motion = play("xbot", '<gesture id="g1" lexeme="OFFER" speed="2" stroke="1.5"/>'
                                 '<gesture id="g2" lexeme="OFFER" mode="LEFT_HAND" stroke="1.5"/>')
    fast, normal = (scene.activities[("b1", g)].source for g in ("g1", "g2"))
    assert fast.end - fast.start == pytest.approx((normal.end - normal.start) / 2.0)
    rig = scene.runtime.rig("bob")
    target, _ = authored_stroke(rig, fast.parameters["clip"], "r")
    assert np.linalg.norm(chest_wrist(rig, motion, "r")[int(round(1.5 * FPS))] - target) < 0.01


def test_a_lexeme_that_matches_nothing_falls_back_on_its_type():
    scheduler = Scheduler()
    (record,) = scheduler.submit(parse_bml(BML.format(id="b1", body='<gesture id="g1" lexeme="DEICTIC" type="YOU" '
                                                                     'mode="LEFT_HAND" stroke="1"/>')))
    assert record.activations[0].parameters["clip"] == "offer_left" and not record.issues


def test_a_gesture_from_the_characters_own_clip_keeps_its_smartbody_noise():
    """``<gesture name=… sbm:joint-range sbm:frequency sbm:scale>`` naming a clip of the character (not the
    gestures pack): the clip plays as without noise, and the named joints turn over its span."""
    gesture = '<gesture id="g1" name="walk" start="0.5" end="2.5"{extra}/>'
    noisy, motion = play("xbot", gesture.format(extra=' sbm:joint-range="l_shoulder l_elbow" sbm:frequency="1" '
                                                      'sbm:scale="0.1"'))
    plain, below = play("xbot", gesture.format(extra=""))
    said = [e.description for e in noisy.feedback.log if e.kind == "warningFeedback" and e.id == "b1:g1"]
    assert not said, said
    activity = noisy.activities[("b1", "g1")]
    assert activity.source.parameters.get("pack") is None  # the character's clip, not a pack gesture
    rig = noisy.runtime.rig("bob")
    turn = np.degrees(quat.angle_between(motion.local_rotations[:, rig.joint("l_shoulder")],
                                         below.local_rotations[:, rig.joint("l_shoulder")]))
    right = np.degrees(quat.angle_between(motion.local_rotations[:, rig.joint("r_shoulder")],
                                          below.local_rotations[:, rig.joint("r_shoulder")]))
    start, end = int(round(activity.start_s * FPS)), int(round(activity.end_s * FPS))
    assert turn[start:end].max() > 2.0 and turn[:start].max() < 1e-3 and turn[end + 1:].max() < 1e-3
    assert right.max() < 1e-3  # a joint the noise does not name plays the clip as without it (degrees)
