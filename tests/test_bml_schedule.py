"""BML scheduling: constraints, speech marks, composition, required, feedback and behaviour plugins."""
from __future__ import annotations

import types

import pytest
from lxml import etree

import infuse
from infuse import registry
from infuse.bml import (
    BehaviourPlan, EstimatedSpeechTimer, Scheduler, SpeechTiming, TimingModel, installed_handlers,
)
from infuse.bml.speech import EngineSpeechTimer
from infuse.plugin_types import BMLBehaviour

NS = "http://www.bml-initiative.org/bml/bml-1.0"


def bml(body: str, block_id: str = "b1", **attrs) -> str:
    extra = "".join(f' {k}="{v}"' for k, v in attrs.items())
    return f'<bml xmlns="{NS}" id="{block_id}"{extra}>{body}</bml>'


def schedule(body: str, **kwargs):
    scheduler = Scheduler()
    (record,) = scheduler.submit(bml(body), **kwargs)
    return scheduler, record


def local(record, behaviour, sync):
    return record.local_times()[behaviour][sync]


def test_unconstrained_nod_follows_the_oscillation_model():
    _, r = schedule('<head id="n" lexeme="NOD" repetition="2" velocity="2"/>')
    t = r.local_times()["n"]
    # ready 0.2/v, stroke 0.75/v, relax (floor((r-0.25)/0.5)*0.5+0.25)/v, end r/v
    assert t["start"] == 0 and t["ready"] == pytest.approx(0.1) and t["stroke"] == pytest.approx(0.375)
    assert t["relax"] == pytest.approx(1.75 / 2) and t["end"] == pytest.approx(1.0)
    assert t["stroke:2"] == pytest.approx(1.25 / 2) and t["stroke:3"] == pytest.approx(1.75 / 2)


def test_references_offsets_and_negative_offsets():
    _, r = schedule('<head id="a" lexeme="NOD" start="2"/>'
                    '<head id="b" lexeme="NOD" start="a:end+0.5"/>'
                    '<head id="c" lexeme="NOD" end="b:start-0.25"/>')
    assert local(r, "b", "start") == pytest.approx(local(r, "a", "end") + 0.5)
    assert local(r, "c", "end") == pytest.approx(local(r, "b", "start") - 0.25)


def test_repeated_stroke_reference():
    _, r = schedule('<head id="n" lexeme="NOD" repetition="3"/><gesture id="g" lexeme="BEAT" stroke="n:stroke:2"/>')
    assert local(r, "g", "stroke") == pytest.approx(local(r, "n", "stroke:2"))
    assert local(r, "n", "stroke:2") > local(r, "n", "stroke")


def test_speech_marks_are_sync_points_and_speech_is_rigid():
    _, r = schedule('<speech id="s" start="1"><text>Hello there <sync id="m"/>my friend.</text></speech>'
                    '<gesture id="g" lexeme="BEAT" stroke="s:m"/>')
    timer = EstimatedSpeechTimer()
    text = "Hello there my friend."
    expected_mark = timer.time_speech(text, [("m", 12)]).mark_times_s["m"]
    assert local(r, "s", "m") == pytest.approx(1 + expected_mark)
    assert local(r, "g", "stroke") == pytest.approx(local(r, "s", "m"))
    # Speech cannot stretch: forcing a mark far from its natural place drops it with a warning.
    scheduler, r2 = schedule('<speech id="s" start="0"><text>Hi <sync id="m"/>you</text></speech>'
                             '<constraint><synchronize><sync ref="s:m"/><sync ref="10"/></synchronize></constraint>')
    assert "s" not in r2.local_times()
    assert any(w.id == "b1:s" and w.type == "IMPOSSIBLE_TO_SCHEDULE" for w in scheduler.feedback.log if w.kind == "warningFeedback")


def test_synchronize_constraint_and_free_cluster_starts_at_block_start():
    _, r = schedule('<gesture id="g1" lexeme="BEAT"/><head id="h" lexeme="NOD"/>'
                    '<constraint><synchronize><sync ref="g1:stroke"/><sync ref="h:start-1"/></synchronize></constraint>')
    assert local(r, "g1", "stroke") == pytest.approx(local(r, "h", "start") - 1)
    assert min(local(r, "g1", "start"), local(r, "h", "start")) == pytest.approx(0)


def test_after_and_before_constraints_move_free_behaviours():
    _, r = schedule('<head id="h" lexeme="NOD" start="3"/><gesture id="g" lexeme="BEAT"/>'
                    '<constraint><after ref="h:end"><sync ref="g:start"/></after></constraint>')
    assert local(r, "g", "start") >= local(r, "h", "end") - 1e-9
    _, r = schedule('<speech id="s"><text>one two <sync id="x"/>three</text></speech><gesture id="g" lexeme="BEAT"/>'
                    '<constraint><before ref="s:x"><sync ref="g:stroke+2"/></before></constraint>')
    assert local(r, "g", "stroke") + 2 <= local(r, "s", "x") + 1e-9


def test_violated_inequality_warns_and_required_one_fails_the_block():
    body = ('<head id="h" lexeme="NOD" start="5"/><gesture id="g" lexeme="BEAT" start="1"/>'
            '<{wrap}><constraint><after ref="h:end"><sync ref="g:start"/></after></constraint></{wrap}>')
    scheduler, r = schedule(body.format(wrap="required"))
    assert r.failed and not r.activations
    scheduler, r = schedule(body.replace("<{wrap}>", "").replace("</{wrap}>", ""))
    assert not r.failed and {"h", "g"} <= set(r.local_times())
    assert any("not met" in w.description for w in scheduler.feedback.log if w.kind == "warningFeedback")


def test_invalid_timing_drops_only_that_behaviour():
    scheduler, r = schedule('<head id="bad" lexeme="NOD" start="2" end="0"/><head id="ok" lexeme="NOD" start="1"/>')
    assert set(r.local_times()) == {"ok"}
    warnings = [w for w in scheduler.feedback.log if w.kind == "warningFeedback"]
    assert [w.id for w in warnings] == ["b1:bad"]


def test_reference_to_a_dropped_behaviour_drops_the_dependant():
    _, r = schedule('<head id="bad" lexeme="NOD" start="2" end="0"/><head id="dep" lexeme="NOD" start="bad:end"/>'
                    '<head id="free" lexeme="NOD"/>')
    assert set(r.local_times()) == {"free"}


def test_unknown_element_and_attribute_warn_and_the_rest_runs():
    scheduler, r = schedule('<dance id="d" style="salsa"/><head id="n" lexeme="NOD" wobble="3" start="1"/>'
                            '<gesture id="g" lexeme="BEAT" start="n:end"/>')
    warnings = {(w.id, w.type) for w in scheduler.feedback.log if w.kind == "warningFeedback"}
    assert ("b1:d", "BEHAVIOR_TYPE_NOT_SUPPORTED") in warnings
    assert ("b1:n", "CUSTOM_ATTRIBUTE_NOT_SUPPORTED") in warnings
    assert set(r.local_times()) == {"n", "g"} and local(r, "g", "start") == pytest.approx(local(r, "n", "end"))


def test_required_unknown_element_fails_the_block():
    _, r = schedule('<required><dance id="d"/></required><head id="n" lexeme="NOD"/>')
    assert r.failed and not r.activations


def test_composition_merge_append_replace():
    s = Scheduler()
    (a,) = s.submit(bml('<head id="n" lexeme="NOD" repetition="4"/>', "a", characterId="C"), at=0.0)
    (m,) = s.submit(bml('<head id="n" lexeme="NOD"/>', "m", characterId="C"), at=1.0)
    (p,) = s.submit(bml('<head id="n" lexeme="NOD"/>', "p", characterId="C", composition="APPEND"), at=1.0)
    (other,) = s.submit(bml('<head id="n" lexeme="NOD"/>', "o", characterId="D", composition="APPEND"), at=1.0)
    assert m.start_s == 1.0 and a.end_s == pytest.approx(4.0)
    assert p.start_s == pytest.approx(max(a.end_s, m.end_s))  # after everything of C
    assert other.start_s == 1.0  # another character's blocks do not delay it
    (r,) = s.submit(bml('<head id="n" lexeme="SHAKE"/>', "r", characterId="C", composition="REPLACE"), at=2.0)
    assert r.start_s == 2.0 and s.blocks["a"].interrupted_at == 2.0
    assert all(x.stop_s == 2.0 for x in s.blocks["a"].activations)
    assert s.blocks["o"].interrupted_at is None
    events = s.flush()
    ends = {e.block: e.global_time for e in events if e.kind == "blockProgress" and e.sync == "end"}
    assert ends["a"] == 2.0 and "p" not in [e.block for e in events if e.kind == "blockProgress" and e.sync == "start"]


def test_the_blocks_interrupted_are_taken_once_each():
    """take_interrupted hands over each block cut since the last call once, cut again earlier or not, and
    leaves out those let go since; it names no block when nothing was cut."""
    s = Scheduler()
    for block_id, at in (("a", 0.0), ("b", 0.0), ("c", 0.0)):
        s.submit(bml('<head id="n" lexeme="NOD" repetition="6"/>', block_id, characterId="C"), at=at)
    assert s.take_interrupted() == []
    s.submit(bml('<head id="n" lexeme="NOD"/>', "d", characterId="C", **{"xmlns:bmla": "http://www.asap-project.org/bmla",
                                                                      "bmla:interrupt": "b, a"}), at=3.0)
    s.interrupt("b", 2.0)  # cut again, earlier
    assert [r.id for r in s.take_interrupted()] == ["b", "a"]
    assert s.blocks["b"].interrupted_at == 2.0 and s.take_interrupted() == []
    s.interrupt("c", 1.0)
    s.flush()
    s.forget(before_s=10.0)
    assert "c" not in s.blocks and s.take_interrupted() == []


def test_cross_block_reference():
    s = Scheduler()
    s.submit(bml('<head id="n" lexeme="NOD" start="1"/>', "first"), at=10.0)
    (second,) = s.submit(bml('<gesture id="g" lexeme="BEAT" start="first:n:end+0.5"/>', "second"), at=10.0)
    assert second.activation("g").start == pytest.approx(s.blocks["first"].activation("n").end + 0.5)


def test_feedback_callbacks_order_and_xml():
    s = Scheduler()
    seen = []
    s.feedback.subscribe(seen.append, kinds=["blockProgress", "syncPointProgress"])
    warnings = []
    s.feedback.subscribe(warnings.append, kinds=["warningFeedback"])
    (r,) = s.submit(bml('<head id="n" lexeme="NOD" start="1"/><mystery id="x"/>', "b", characterId="Ann"), at=5.0)
    assert len(warnings) == 1 and not seen  # progress waits for the clock
    delivered = s.advance(6.1)
    assert [e.kind for e in delivered][:2] == ["blockProgress", "syncPointProgress"]
    assert all(e.global_time <= 6.1 for e in delivered)
    s.flush()
    assert seen[-1].kind == "blockProgress" and seen[-1].sync == "end" and seen[-1].global_time == pytest.approx(r.end_s)
    times = [e.global_time for e in seen]
    assert times == sorted(times)
    xml = [etree.fromstring(e.to_xml()) for e in s.feedback.log]
    tags = {etree.QName(x).localname for x in xml}
    assert {"blockProgress", "syncPointProgress", "warningFeedback", "predictionFeedback"} <= tags
    stroke = next(x for x in xml if x.get("id") == "b:n:stroke")
    assert etree.QName(stroke).namespace == NS and stroke.get("characterId") == "Ann"
    assert float(stroke.get("globalTime")) == pytest.approx(float(stroke.get("time")) + 5.0)


def test_activation_records_are_plain_timed_data():
    _, r = schedule('<gaze id="g" target="Bob" influence="NECK" start="1"/><locomotion id="w" target="3 4" manner="walk"/>')
    gaze, walk = r.activation("g"), r.activation("w")
    assert gaze.controller == "gaze" and gaze.parameters["influence"] == "HEAD" and gaze.parameters["target"] == "Bob"
    assert walk.controller == "locomotion" and walk.parameters["distance_m"] == pytest.approx(5.0)
    assert walk.end - walk.start == pytest.approx(5.0 / 1.2 + 0.5)
    assert list(walk.sync_times) == ["start", "ready", "relax", "end"]
    import json
    json.dumps(walk.as_dict())


def test_tts_engine_timings_replace_the_estimate():
    class FakeUtterance:
        def __init__(self, duration, marks):
            self.duration_s, self.marks, self.phonemes, self.words = duration, marks, [(0.0, duration, "ah")], []

    class FakeEngine:
        name = "fake"

        def __init__(self):
            self.seen = []

        def synthesize(self, text):
            self.seen.append(text)
            return FakeUtterance(4.0, {"m": 3.0})

    engine = FakeEngine()
    s = Scheduler(speech_timer=EngineSpeechTimer(engine))
    (r,) = s.submit(bml('<speech id="s"><text>A &amp; B <sync id="m"/>C</text></speech>'))
    assert engine.seen == ['A &amp; B <mark name="m"/>C']
    t = r.local_times()["s"]
    assert t["end"] == 4.0 and t["m"] == 3.0 and r.activation("s").parameters["timing_source"] == "fake"


@pytest.fixture
def wave_plugin():
    """A third-party plugin adding a namespaced <ex:wave> element."""
    def plan(behaviour, context):
        cycles = float(behaviour.attributes.get("cycles", "2"))
        return BehaviourPlan(TimingModel.from_points({"start": 0.0, "stroke": 0.5, "end": cycles}), "wave",
                             {"cycles": cycles})

    module = types.ModuleType("example_wave_plugin")

    @infuse.hookimpl
    def infuse_bml_behaviours():
        return [BMLBehaviour("wave", plan, "wave a hand", ("{urn:example}wave",), frozenset({"cycles"}))]

    module.infuse_bml_behaviours = infuse_bml_behaviours
    plugins = registry.plugins()
    plugins.register(module)
    yield
    plugins.unregister(module)


def test_third_party_behaviour_plugin(wave_plugin):
    assert "{urn:example}wave" in installed_handlers()
    s = Scheduler()
    (r,) = s.submit(f'<bml xmlns="{NS}" xmlns:ex="urn:example" id="b"><ex:wave id="w" cycles="3" start="1"/>'
                    f'<head id="n" lexeme="NOD" start="w:stroke"/></bml>')
    assert r.activation("w").controller == "wave" and r.activation("w").end == pytest.approx(4.0)
    assert r.activation("n").start == pytest.approx(1.5)
    assert not r.issues


def test_failing_third_party_handler_is_a_warning():
    def broken(behaviour, context):
        raise RuntimeError("boom")
    handlers = dict(installed_handlers())
    from infuse.bml.behaviours import handlers_from
    handlers.update(handlers_from([BMLBehaviour("broken", broken, "", ("head",), priority=5)]))
    s = Scheduler(handlers=handlers)
    (r,) = s.submit(bml('<head id="n"/><gesture id="g" lexeme="BEAT"/>'))
    assert set(r.local_times()) == {"g"}
    assert any("boom" in i.description for i in r.issues)


def test_smartbody_dialect_allows_starting_before_the_block():
    s = Scheduler()
    (r,) = s.submit('<act><bml><gesture lexeme="BEAT" type="YOU" stroke="0" relax="2"/></bml></act>')
    a = r.activations[0]
    assert a.time("stroke") == pytest.approx(0.0) and a.start < 0 and not r.issues


def test_speech_timing_estimate_is_monotonic():
    timer = EstimatedSpeechTimer()
    text = "Hello, world. How are you?"
    timing = timer.time_speech(text, [(str(i), i) for i in range(len(text) + 1)])
    values = [timing.mark_times_s[str(i)] for i in range(len(text) + 1)]
    assert values == sorted(values) and values[-1] <= timing.duration_s
    assert isinstance(timing, SpeechTiming) and 1.0 < timing.duration_s < 3.0


def test_real_tts_engine_marks_drive_the_schedule():
    speech = pytest.importorskip("infuse.speech")
    try:
        engine = speech.tts_engine("espeak")
    except infuse.InfuseError as exc:
        pytest.skip(f"espeak engine not available: {exc}")
    s = Scheduler(speech_timer=engine)  # an engine is wrapped in an EngineSpeechTimer
    (r,) = s.submit(bml('<speech id="s"><text>Nice to <sync id="m"/>meet you.</text></speech>'
                        '<head id="h" lexeme="NOD" stroke="s:m"/>'))
    t = r.local_times()
    assert r.activation("s").parameters["timing_source"] == "espeak" and not r.issues
    assert t["s"]["start"] < t["s"]["m"] < t["s"]["end"] and t["h"]["stroke"] == pytest.approx(t["s"]["m"])
    assert r.activation("s").parameters["tts"]["phonemes"]
