"""``infuse.live.LiveScene`` in process: a block shows on the next frame, soon after on the wall clock; a moved target is aimed at from the next frame; REPLACE stops speech (and its lip sync)
at the frame it starts; memory stays bounded; a full queue says so at once."""
from __future__ import annotations

import threading
import time

import numpy as np
import pytest

import infuse_gaze.controller as gaze_controller
from infuse import quaternions as quat
from infuse.errors import BusyError, InputError, UsageError
from infuse.kinematics import forward_kinematics
from infuse.live import LiveScene
from infuse.scene import Scene
from infuse.speech import tts_engine
from infuse_manipulation.pointing import PointingState

from corpus_data import corpus_file
from live_support import BML_NS

FPS = 60


def _scene(idle: bool = True) -> Scene:
    scene = Scene(fps=FPS, quiet=True, idle=idle)
    scene.add_character(corpus_file("talkinghead/avatars/brunette-t.glb"), "ann", position=(0, 0, 2), facing=(0, 0, 0))
    scene.add_character(corpus_file("runxaway-models/Xbot.glb"), "bob", facing="ann")
    return scene


class Frames:
    """Every frame a live scene shows: index -> (wall time, {character: (rotations, morphs, root)})."""

    def __init__(self, live: LiveScene):
        self.shown: dict[int, tuple[float, dict]] = {}
        self.event = threading.Condition()
        live.on_frame(self._keep)

    def _keep(self, frame):
        with self.event:
            self.shown[frame.index] = (frame.wall_s, {n: (c.rotations, c.morphs, c.root) for n, c in frame.characters.items()})
            self.event.notify_all()

    def wait(self, index: int, timeout_s: float = 5.0):
        """The first frame shown at or after ``index`` (a frame evaluated too late is skipped, not shown)."""
        with self.event:
            assert self.event.wait_for(lambda: any(i >= index for i in self.shown), timeout_s), index
            return self.shown[min(i for i in self.shown if i >= index)]


def evaluated(live: LiveScene, name: str) -> dict:
    """Stop the loop; every frame of ``name`` it evaluated and still keeps, shown or skipped:
    index -> (rotations (J, 4), morphs (M,))."""
    live.stop()
    runtime = live.scene.runtime
    rotations, _, morphs = runtime.last_poses(name, runtime.frame)
    first = runtime.frame - len(rotations)
    return {first + k: (rotations[k], morphs[k]) for k in range(len(rotations))}


def test_a_block_shows_on_the_next_frame():
    with LiveScene(_scene()) as live:
        frames = Frames(live)
        time.sleep(0.3)
        latencies = []
        for k in range(12):
            time.sleep(0.013 * (k % 5))  # at various points of a frame
            shown = max(frames.shown)
            submitted = time.perf_counter()
            block = live.bml("bob", f'<bml xmlns="{BML_NS}" id="nod{k}"><head id="h" lexeme="NOD"/></bml>')
            start = live.scene.scheduler.blocks[block[0]].start_s
            index = round(start * FPS)
            assert index <= shown + 2  # the next frame (or the one after, if one was being shown meanwhile)
            wall, _ = frames.wait(index)
            latencies.append(wall - submitted)
        # wall-clock time depends on the machine's load (tests run beside other test workers): the median is
        # held within a frame of the target (one frame and 10 ms), which benchmarks/live.py measures
        assert np.median(latencies) <= 2 / FPS + 0.010, latencies


def test_gaze_follows_a_moved_target_from_the_next_frame():
    with LiveScene(_scene()) as live:
        frames = Frames(live)
        head = live.scene.runtime.rig("bob").joint("skullbase")
        live.move_target("ball", (0.8, 1.6, 1.0))
        live.gaze("bob", "ball")
        time.sleep(1.5)  # settled on the ball
        moved_at = live.move_target("ball", (-0.8, 1.2, 1.0))
        index = round(moved_at * FPS)
        frames.wait(index + 2)
        poses = evaluated(live, "bob")
        turn = [quat.angle_between(poses[i][0][head], poses[i - 1][0][head]) for i in (index - 2, index - 1, index, index + 1)]
        assert max(turn[:2]) < 1e-4, turn  # still, before the move
        assert turn[2] > 1e-3, turn        # turning on the frame the move applies to


def test_replace_stops_speech_and_lip_sync_at_its_frame():
    with LiveScene(_scene(idle=False)) as live:  # no blinks: the morphs that move are the speech's
        frames = Frames(live)
        live.say("ann", "This is a rather long sentence that will never be finished by anyone at all.")
        time.sleep(0.8)
        ids = live.bml("ann", f'<bml xmlns="{BML_NS}" id="cut" composition="REPLACE"><head id="h" lexeme="NOD"/></bml>')
        cut = round(live.scene.scheduler.blocks[ids[0]].start_s * FPS)
        frames.wait(cut + 3)
        poses = evaluated(live, "ann")
        morphs = np.array([poses[i][1] for i in range(cut - 20, cut + 4)])
        speaking = morphs[:20]
        assert np.abs(speaking).max() > 0.05  # the mouth moved while speaking
        mouth = np.abs(speaking).max(axis=0) > 1e-6  # the morphs the speech drove
        assert np.abs(morphs[20:][:, mouth]).max() < 1e-6  # and none of them from the cut on


def test_memory_stays_bounded_and_a_full_queue_says_so():
    live = LiveScene(_scene(idle=False), keep_s=0.5)
    with live:
        frames = Frames(live)
        live.say("ann", "Hi.")
        time.sleep(3.2)
        kept = len(live.scene.runtime.motion("bob").local_rotations)
        assert kept <= int(1.5 * FPS) + 1, kept  # half a second kept, forgotten once a second
        assert live.scene.runtime.frame >= 2.5 * FPS
        assert live.scene.speech.utterances == [None]  # said, then let go
        assert len(live.scene.activities) == 0 and len(live.scene.runtime.activities) <= 2
        assert len(live.scene.scheduler.blocks) == 0  # the block said, let go
        block = live.say("ann", "Hi.")  # said again: synthesized anew, lip-synced
        start = round(live.scene.scheduler.blocks[block].start_s * FPS)
        frames.wait(start + 20)
        poses = evaluated(live, "ann")
        assert max(np.abs(poses[i][1]).max() for i in range(start, start + 20)) > 0.05
    with pytest.raises(UsageError, match="stopped"):
        live.submit(print)
    waiting = LiveScene(_scene(), queue_size=2)  # not started: nothing takes commands
    waiting.submit(print)
    waiting.submit(print)
    with pytest.raises(BusyError, match="2 commands are waiting"):
        waiting.submit(print)


class CountingTTS:
    """espeak, counting what it is asked to synthesize and on which thread; with ``replay`` (an earlier
    one), the utterances that one made for the same texts, instead (espeak's timing varies slightly
    between calls)."""

    def __init__(self, replay: "CountingTTS | None" = None):
        self.engine = tts_engine("espeak")
        self.calls: list[tuple[str, str]] = []
        self.made: dict[str, object] = {}
        self.replay = replay

    def synthesize(self, text):
        self.calls.append((threading.current_thread().name, text))
        if self.replay is not None:
            return self.replay.made[text]
        utterance = self.made[text] = self.engine.synthesize(text)
        return utterance

    def __getattr__(self, name):
        return getattr(self.engine, name)


def test_speech_is_synthesized_once_with_the_nonverbal_generator_on():
    """With the nonverbal generator on, BML speech and ``say`` are put through the generator on the
    caller's thread and synthesized once there, with the marks it adds (none on the loop thread); the
    blocks scheduled are those an offline scene schedules from the same input, to the same times."""
    def generating(tts) -> Scene:
        scene = Scene(fps=FPS, quiet=True, tts=tts, generators=("nonverbal",))
        scene.add_character(corpus_file("talkinghead/avatars/brunette-t.glb"), "ann", position=(0, 0, 2), facing=(0, 0, 0))
        scene.add_character(corpus_file("runxaway-models/Xbot.glb"), "bob", facing="ann")
        return scene
    talk = (f'<bml xmlns="{BML_NS}" id="talk"><speech id="s1"><text>I really think the big red barn should be '
            'painted before winter comes.</text></speech></bml>')
    reply = "Well, the paint costs more than the whole barn is worth these days."
    tts = CountingTTS()
    with LiveScene(generating(tts)) as live:
        ids = live.bml("ann", talk) + [live.say("bob", reply)]
        live_blocks = {i: live.scene.scheduler.blocks[i] for i in ids}
    offline = generating(CountingTTS(replay=tts))  # the same texts, marks included, or KeyError
    offline.bml("ann", talk)
    offline.say("bob", reply)
    assert len(tts.calls) == 2, tts.calls  # one synthesis per utterance
    assert all(thread != "infuse-live" for thread, _ in tts.calls), tts.calls
    assert all("<mark" in text for _, text in tts.calls)  # with the generator's marks
    for block_id, record in live_blocks.items():
        expected = offline.scheduler.blocks[block_id]
        assert len(record.activations) > 1  # the speech and what the generator added to it
        assert [(a.behaviour, a.element) for a in record.activations] == [(a.behaviour, a.element) for a in expected.activations]
        for mine, theirs in zip(record.activations, expected.activations):
            assert mine.sync_times.keys() == theirs.sync_times.keys()
            for sync, at in mine.sync_times.items():
                assert abs((at - record.start_s) - (theirs.sync_times[sync] - expected.start_s)) < 1e-9, (block_id, sync)


def test_ended_gazes_stop_costing():
    """Bob looks at a new point every 0.4 s for 4.8 s, every third time in a REPLACE block, Ann at him
    throughout: a gaze another has taken over from (once blended in, in 0.3 s) is no longer evaluated (it
    would settle for 3.5 s, 9 of them at a time), so Bob's gazes evaluated are the one leading and the one
    blending in. A gaze a REPLACE ends with no gaze after it returns to rest, and is evaluated no more
    once there (not for the rest of its 3.5 s settle)."""
    def gazes(live: LiveScene, name: str) -> list:
        runtime = live.scene.runtime
        return [a for a in list(runtime.activities)
                if a.rig.name == name and a.controller.kind == "gaze" and a.active_between(runtime.time, runtime.time)]
    with LiveScene(_scene()) as live:
        live.gaze("ann", "bob")
        counts, rng = [], np.random.default_rng(3)
        for k in range(12):
            point = " ".join(f"{v:.3f}" for v in (rng.uniform(-1.5, 1.5), rng.uniform(1.0, 1.8), rng.uniform(0.5, 2.5)))
            live.move_target(f"p{k}", [float(v) for v in point.split()])
            composition = ' composition="REPLACE"' if k % 3 == 2 else ""
            live.bml("bob", f'<bml xmlns="{BML_NS}" id="look{k}"{composition}><gazeShift id="g" target="p{k}"/></bml>')
            time.sleep(0.4)
            counts.append(len(gazes(live, "bob")))
        assert max(counts) <= 2 and min(counts) >= 1, counts
        assert len(gazes(live, "ann")) == 1
        cut = live.bml("bob", f'<bml xmlns="{BML_NS}" id="cut" composition="REPLACE"><head id="h" lexeme="NOD"/></bml>')[0]
        cut_s = live.scene.scheduler.blocks[cut].start_s
        settling = gazes(live, "bob")
        assert len(settling) == 1 and settling[0].end_s is not None  # cut: blending out, then back to rest
        end_s = settling[0].end_s
        assert live.scene.time < end_s
        while live.scene.time < end_s + 1.5:
            time.sleep(0.1)
        # back at rest within a second and a half of its end, not evaluated for the rest of its settle
        assert gazes(live, "bob") == [] and settling[0].controller.settle_s == 3.5 and end_s > cut_s


def test_a_gaze_cut_short_is_evaluated_until_back_at_rest():
    """Timed gazes cut by REPLACE blocks (speech), one every 1.5 s: each blends out and the character's
    turn comes back to rest within about a second; from then on it is not evaluated (its settle would
    last 3.5 s). The frames are those evaluated with every gaze kept for its whole settle, to 1e-6 m."""
    def cut_gazes() -> tuple[Scene, list[int]]:
        scene = Scene(fps=30, quiet=True)
        scene.add_character(corpus_file("runxaway-models/Xbot.glb"), "bob")
        counts = []
        for k in range(6):
            scene.add_target(f"t{k}", ((-1.5, 1.5)[k % 2], 1.0 + 0.1 * k, 1.0))
            scene.bml("bob", f'<bml xmlns="{BML_NS}" id="look{k}"><gaze id="g" target="t{k}" influence="WAIST" '
                             'start="0" end="3"/></bml>')
            scene.step(24)
            scene.bml("bob", f'<bml xmlns="{BML_NS}" id="cut{k}" composition="REPLACE"><speech id="s"><text>Right.'
                             '</text></speech></bml>')
            for _ in range(7):
                scene.step(3)
                now = scene.runtime.time
                counts.append(sum(a.controller.kind == "gaze" and a.active_between(now, now) for a in scene.runtime.activities))
        scene.step(60)
        now = scene.runtime.time
        counts.append(sum(a.controller.kind == "gaze" and a.active_between(now, now) for a in scene.runtime.activities))
        return scene, counts
    ended, counts = cut_gazes()
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(gaze_controller, "_end_settled", lambda rows, states, block: None)
        kept, kept_counts = cut_gazes()
    assert max(counts) == 1 and counts[-1] == 0, counts  # the last gaze, cut 2.7 s ago, back at rest
    assert max(kept_counts) == 3 and kept_counts[-1] == 1, kept_counts  # each settling 3.5 s
    skeleton = ended.runtime.rig("bob").skeleton
    mine, theirs = (forward_kinematics(skeleton, *s.runtime.last_frames("bob", s.runtime.frame))[1] for s in (ended, kept))
    assert mine.shape == theirs.shape and np.ptp(theirs, axis=0).max() > 0.05  # it did look around
    assert np.abs(mine - theirs).max() < 1e-6


def test_bad_bml_and_names_are_refused_before_the_loop():
    with LiveScene(_scene()) as live:
        with pytest.raises(InputError, match="line 1"):
            live.bml("ann", "<bml id='x'><head></bml>")
        with pytest.raises(UsageError, match="no character 'zed'"):
            live.bml("zed", f'<bml xmlns="{BML_NS}" id="n"><head id="h" lexeme="NOD"/></bml>')
        with pytest.raises(UsageError, match="three finite numbers"):
            live.move_target("ball", (0, float("nan"), 1))
        assert live.stats.commands == 0 and live.running


def test_a_character_joins_the_running_scene():
    with LiveScene(_scene()) as live:
        frames = Frames(live)
        time.sleep(0.3)
        name = live.add_character(corpus_file("runxaway-models/Xbot.glb"), "carl", position=(1.5, 0.0, 1.0), facing="ann")
        assert name == "carl" and "carl" in live.scene.characters
        block = live.nod("carl", amount=0.8)
        start = round(live.scene.scheduler.blocks[block].start_s * FPS)
        frames.wait(start + 30)
        head = live.scene.runtime.rig("carl").joint("skullbase")
        poses = evaluated(live, "carl")
        turns = [quat.angle_between(poses[i][0][head], poses[start][0][head]) for i in range(start, start + 30)]
        assert max(turns) > np.radians(3)  # it nods


def test_point_grab_and_release_as_live_calls():
    """``call`` messages name point, grab and release (checked by the protocol, run by the live scene): Bob
    points with the hand asked for, takes the cup, carries it and lets it go where his hand leaves it."""
    import asyncio
    import json

    from infuse_live.hub import Hub

    scene = _scene(idle=False)
    scene.add_object("cup", (-0.2, 1.3, 0.3), size=0.08)  # before Bob (at the origin, facing Ann: +z)
    with LiveScene(scene) as live:
        frames = Frames(live)

        async def calls():
            hub = Hub(live, asyncio.get_running_loop())
            try:
                replies, hands = {}, None
                for method, args in (("point", {"target": [0.0, 1.0, 2.0], "hand": "left"}),
                                     ("grab", {"obj": "cup", "hand": "right"}), ("release", {"obj": "cup"})):
                    message = {"type": "call", "method": method, "character": "bob", "args": args}
                    (replies[method],) = await hub.handle(None, json.dumps(message))
                    await asyncio.sleep(1.0)
                    if method == "point":  # while it points (ended activities are forgotten later)
                        hands = live.call(lambda: [a.state_of(PointingState).hands for (b, _), a in scene.activities.items()
                                                   if b == replies["point"]["blocks"][0]])
                    await asyncio.sleep(1.5)
                (wrong,) = await hub.handle(None, json.dumps({"type": "call", "method": "grab", "character": "bob",
                                                              "args": {"object": "cup"}}))
                return replies, hands, wrong
            finally:
                hub.close()
        replies, hands, wrong = asyncio.run(calls())
        assert all(r["type"] == "accepted" for r in replies.values()), replies
        assert wrong["type"] == "error" and "args.object" in wrong["message"] and "grab takes hand, obj" in wrong["message"]
        released = replies["release"]["frame"]
        frames.wait(released + 30)
        live.stop()
        assert hands == [("left",)]
        cup = scene.object_track("cup")
        grabbed = replies["grab"]["frame"]
        assert np.linalg.norm(cup[released - 1] - cup[grabbed]) > 0.1  # carried
        assert np.allclose(cup[released:released + 30], cup[released])  # left where the hand let it go


def test_frames_stand_on_the_ground_as_exported_files_do():
    """SmartBody's Brad has his hips at the origin (a metre below the ground in the runtime), Ann's soles
    reach below her foot joints: the frames shown stand both on y = 0, soles included, at the height of
    the scene's exported clip (forward kinematics on the shown frames)."""
    from infuse.contacts import feet, lowest_points
    from infuse.grounding import sole_depth
    from infuse.kinematics import forward_kinematics, motion_fk

    scene = Scene(fps=FPS, quiet=True)
    scene.add_character(corpus_file("smartbody/mesh/brad/Brad.dae"), "brad", position=(-1, 0, 0))
    scene.add_character(corpus_file("talkinghead/avatars/brunette-t.glb"), "ann", position=(1, 0, 0))
    with LiveScene(scene) as live:
        frames = Frames(live)
        live.nod("brad")
        frames.wait(60)
    shown = sorted(frames.shown)
    kept = {name: live.scene.runtime.last_poses(name, live.scene.runtime.frame) for name in scene.characters}
    for name in scene.characters:
        rig = scene.runtime.rig(name)
        asset = rig.character.asset
        rotations = np.array([frames.shown[i][1][name][0] for i in shown])
        roots = np.array([frames.shown[i][1][name][2] for i in shown])
        global_rotations, positions = forward_kinematics(rig.skeleton, rotations, roots)
        pair = feet(rig.skeleton, rig.mapping)
        sole = lowest_points(rig.skeleton, pair, global_rotations, positions).min(axis=-1) - sole_depth(asset, pair)
        assert np.abs(sole.min()) < 1e-3, (name, sole.min())
        exported = scene.runtime.export(name).motions["runtime"]
        first = scene.runtime.frame - len(kept[name][0])
        at = np.array(shown) - first
        assert at.min() >= 0
        offset = positions[:, 0] - motion_fk(exported)[1][at, 0]
        assert np.abs(offset).max() < 1e-3, (name, np.abs(offset).max())
    assert float(scene.runtime.last_poses("brad", 1)[1][0, 1]) < 0.2  # the runtime's own frames: a metre down


def test_finished_blocks_are_let_go_and_the_kept_count_stays_bounded():
    """A scene forgetting as a live one does (every second, two seconds kept) while a nod starts every
    0.1 s for 60 s, every fourth one a REPLACE that cuts the one before: the blocks kept are those that may
    still play or give feedback (a nod lasts about a second), however many ran; every block's progress is
    delivered, start to end; a block let go is unknown to a later bmla:interrupt, which warns as for any
    unknown name."""
    scene = Scene(fps=30, quiet=True, idle=False)
    scene.add_character(corpus_file("runxaway-models/Xbot.glb"), "bob")
    ended, warnings, kept = set(), [], []
    scene.on("blockProgress", lambda e: ended.add(e.block) if e.sync == "end" else None)
    scene.on("warningFeedback", warnings.append)
    for k in range(600):
        composition = ' composition="REPLACE"' if k % 4 == 3 else ""
        scene.bml("bob", f'<bml xmlns="{BML_NS}" id="nod{k}"{composition}><head id="h" lexeme="NOD"/></bml>')
        scene.step(3)
        if k % 10 == 9:
            scene.forget(2.0)
            kept.append(len(scene.scheduler.blocks))
            assert all(min(r.end_s, r.interrupted_at or np.inf) >= scene.time - 3.0 for r in scene.scheduler.blocks.values())
    assert max(kept) <= 45, kept
    scene.step(90)
    scene.forget(2.0)
    assert len(scene.scheduler.blocks) == 0 and len(scene._interrupted) == 0
    assert ended == {f"nod{k}" for k in range(600)}
    scene.bml("bob", f'<bml xmlns="{BML_NS}" id="late" bmla:interrupt="nod599" '
                     f'xmlns:bmla="http://www.asap-project.org/bmla"><head id="h" lexeme="NOD"/></bml>')
    assert "bmla:interrupt names unknown block 'nod599'" in warnings[-1].description


def test_a_failing_frame_callback_stops_the_scene_with_its_error():
    """Frames are shown on their own thread: a callback that raises stops both threads, and callers get
    the error from then on instead of waiting on a loop that is gone."""
    live = LiveScene(_scene(idle=False))
    with live:
        shown = Frames(live)
        shown.wait(5)

        def broken(frame):
            raise RuntimeError(f"no screen for frame {frame.index}")
        live.on_frame(broken)
        deadline = time.monotonic() + 5.0
        while live.error is None and time.monotonic() < deadline:
            try:
                live.nod("bob")  # waits for the loop: refused once it stops, not left waiting
            except UsageError as exc:
                assert "no screen for frame" in str(exc)
        assert isinstance(live.error, RuntimeError) and "no screen for frame" in str(live.error)
        live._thread.join(2.0)
        assert not live.running
        with pytest.raises(UsageError, match="stopped: no screen for frame"):
            live.nod("bob")


def test_a_walk_planned_ahead_is_used_only_from_the_same_inputs(monkeypatch):
    """LiveScene.parse plans walks ahead (on the caller's thread: LiveScene.prepare). Realizing a walk takes
    its plan when the walk starts where it was planned from; a walk planned before another walk of the
    character was realized starts elsewhere and is planned again. Either way the frames are those of a
    scene that planned nothing ahead, to the bit."""
    import infuse_locomotion.controller as locomotion

    calls = []
    plan = locomotion.Locomotion.plan

    def counted(self, *args, **kwargs):
        calls.append(threading.current_thread().name)
        return plan(self, *args, **kwargs)
    monkeypatch.setattr(locomotion.Locomotion, "plan", counted)
    walks = [f'<bml xmlns="{BML_NS}" id="w{k}"><locomotion id="l1" target="{x} {z}"/></bml>'
             for k, (x, z) in enumerate([(0.5, 1.5), (-0.5, 0.5)])]
    motions = []
    for ahead in (False, True):
        scene = Scene(fps=FPS, quiet=True)
        scene.add_character(corpus_file("runxaway-models/Xbot.glb"), "bob", packs=["locomotion-male"])
        calls.clear()
        if ahead:
            for text in walks:
                LiveScene(scene).parse("bob", text)
            assert len(calls) == 2  # both planned here, from where bob stands now
        scene.bml("bob", walks[0])  # ahead: its plan taken, planned from the same start
        scene.step(60)
        scene.bml("bob", walks[1])  # starts where the first walk leaves bob: planned again
        scene.step(120)
        assert len(calls) == (3 if ahead else 2), calls
        motions.append(scene.motion("bob"))
    assert np.array_equal(motions[0].local_rotations, motions[1].local_rotations)
    assert np.array_equal(motions[0].root_translations, motions[1].root_translations)


def test_a_say_is_lip_synced_on_the_callers_thread(monkeypatch):
    """A live say works out its lip sync where it is parsed (LiveScene.prepare, on the caller's thread); the
    loop's thread only binds what was worked out."""
    from infuse_lipsync import controllers

    threads = []
    lipsync = controllers.lipsync
    monkeypatch.setattr(controllers, "lipsync",
                        lambda *args, **kwargs: threads.append(threading.current_thread()) or lipsync(*args, **kwargs))
    with LiveScene(_scene(idle=False)) as live:
        frames = Frames(live)
        block = live.say("ann", "Hello there.")
        frames.wait(round(live.scene.scheduler.blocks[block].end_s * FPS))
        assert "ann" in {a.rig.name for a in live.scene.runtime.activities if a.controller.speaks}
    assert threads == [threading.current_thread()]


def test_builder_calls_are_written_ahead_unless_the_loop_must_make_them():
    """LiveScene.prepare_call writes and parses a nod, an expression and a gaze at a named character on the
    caller's thread, for builder_call to schedule as they are; a gaze at a point (a scene target is made
    for it), a call given ``at`` and a wrong argument are left to the loop, which makes them (and raises
    the error) as the scene does. The frames are those of the scene's own builder calls, to the bit."""
    calls = [("nod", "bob", {"repeats": 2.0}, True), ("expression", "ann", {"lexeme": "smile"}, True),
             ("gaze", "bob", {"target": "ANN"}, True), ("gaze", "ann", {"target": [0.5, 1.6, 1.0]}, False),
             ("shake", "ann", {"at": 1.5}, False)]
    motions = []
    for ahead in (False, True):
        scene = _scene()
        live = LiveScene(scene)
        for method, name, arguments, written in calls:
            if ahead:
                prepared = live.prepare_call(method, name, arguments)
                assert (prepared is not None) == written, method
                live.builder_call(method, name, arguments, prepared)
            else:
                getattr(scene, method)(name, **arguments)
            scene.step(20)
        with pytest.raises(TypeError, match="bogus"):
            if ahead:
                prepared = live.prepare_call("nod", "bob", {"bogus": 1})
                assert prepared is None
                live.builder_call("nod", "bob", {"bogus": 1}, prepared)
            else:
                scene.nod("bob", bogus=1)
        scene.step(60)
        motions.append({name: scene.motion(name) for name in ("ann", "bob")})
    for name in ("ann", "bob"):
        assert np.array_equal(motions[0][name].local_rotations, motions[1][name].local_rotations), name
        assert np.array_equal(motions[0][name].morph_weights, motions[1][name].morph_weights), name


def test_a_walk_given_a_time_starts_then():
    """A live walk_to given ``at`` is left to the loop, which makes it as the scene's walk_to does: it starts
    at that time, not on the next frame."""
    scene = Scene(fps=FPS, quiet=True)
    scene.add_character(corpus_file("runxaway-models/Xbot.glb"), "bob", packs=["locomotion-male"])
    live = LiveScene(scene)
    arguments = {"target": [0.5, 1.0], "at": 1.0}
    prepared = live.prepare_call("walk_to", "bob", arguments)
    assert prepared is None
    block = live.builder_call("walk_to", "bob", arguments, prepared)
    assert live.scene.scheduler.blocks[block].start_s == pytest.approx(1.0)


def test_only_blocks_a_controller_prepares_for_are_scheduled_ahead(monkeypatch):
    """LiveScene.parse schedules a block on a scratch planner (speech synthesis, walks planned ahead) only
    when it may have something to prepare: a nod once (to learn that no controller prepares nods), then no
    more; a walk every time (the locomotion controller prepares its path)."""
    import infuse.live

    scheduled = []

    class Counting(infuse.live.Scheduler):
        def schedule_block(self, block, at, character=None):
            scheduled.append(block.id)
            return super().schedule_block(block, at, character)
    monkeypatch.setattr(infuse.live, "Scheduler", Counting)
    live = LiveScene(_scene())
    for k in range(3):
        live.parse("bob", f'<bml xmlns="{BML_NS}" id="n{k}"><head id="h" lexeme="NOD"/></bml>')
    for k in range(2):
        live.parse("bob", f'<bml xmlns="{BML_NS}" id="w{k}"><locomotion id="l1" target="1.0 1.0"/></bml>')
    assert scheduled == ["n0", "w0", "w1"], scheduled
