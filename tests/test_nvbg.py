"""The ``nonverbal`` BML generator: what each rule adds, where its sync points fall, the listener's
backchannel, the seed, the author's own behaviours, and mistakes in a rules file."""
from __future__ import annotations

import tomllib
from pathlib import Path

import pytest

from infuse.bml import GeneratorContext, Scheduler, parse_bml
from infuse.errors import InputError
from infuse.scene.command import build_scene
from infuse.scene.scenefile import read_scene_file
from infuse_nvbg.generate import generate
from infuse_nvbg.rules import DEFAULT_RULES, load_rules

BML = "http://www.bml-initiative.org/bml/bml-1.0"
CAST = {"ann": "character", "bob": "character", "cup": "object"}


def block(text: str, extra: str = "", flag: str = 'infuse:nonverbal="true"', block_id: str = "b1"):
    return (f'<bml xmlns="{BML}" xmlns:infuse="urn:infuse:bml" id="{block_id}" characterId="ann" {flag}>'
            f'<speech id="s1"><text>{text}</text></speech>{extra}</bml>')


def schedule(text: str, extra: str = "", seed: int = 0, names=CAST, **options):
    scheduler = Scheduler(names=lambda: names, seed=seed, **options)
    return scheduler, scheduler.submit(block(text, extra))


def certain_rules(tmp_path: Path, **changes) -> Path:
    """The built-in rules with every probability 1 (or as ``changes`` say), written to a file."""
    text = DEFAULT_RULES.read_text()
    for key in ("probability", "aversion_probability", "look_back_probability"):
        text = "\n".join(line.split("=")[0] + "= 1.0" if line.strip().startswith(key + " ") else line
                         for line in text.splitlines())
    for old, new in changes.items():
        text = text.replace(old, new)
    path = tmp_path / "rules.toml"
    path.write_text(text)
    return path


def generated(text: str, rules_path: Path, names=CAST, settings=None, extra: str = "", said=()):
    (parsed,) = parse_bml(block(text, extra)).blocks
    context = GeneratorContext("ann", characters=tuple(n for n, k in names.items() if k == "character"),
                               objects=tuple(n for n, k in names.items() if k == "object"), seed=5,
                               settings=settings or {}, said=said)
    return generate(parsed, context, load_rules(rules_path))


def elements(generation) -> list[tuple[str, dict]]:
    speech = next(b for b in generation.block.behaviours if b.element == "speech")
    marks = dict(speech.marks)
    out = []
    for b in generation.block.behaviours:
        if b.id.startswith("nv"):
            where = {s: speech.text[marks[r.sync]:].split()[0].strip(".,?!") if r.sync in marks else r.sync
                     for s, r in b.sync_refs.items()}
            out.append((b.element, {**b.attributes, **where}))
    return out


def test_each_rule_puts_its_behaviour_on_its_word(tmp_path):
    rules = certain_rules(tmp_path)
    g = generated("Hello. Could you pass me that cup? No, because this one here is really important.", rules)
    found = elements(g)
    assert ("gesture", {"lexeme": "WAVE", "mode": found[0][1]["mode"], "stroke": "Hello"}) == found[0]
    assert ("pointing", {"target": "cup", "stroke": "that"}) in found                  # on the demonstrative
    assert ("head", {"lexeme": "SHAKE", "amount": "0.4", "repetition": "2", "stroke": "No"}) in found
    assert ("faceLexeme", {"lexeme": "RAISE_BROWS", "amount": "0.6", "attackPeak": "cup"}) in found  # question's last word
    assert ("faceLexeme", {"lexeme": "RAISE_BROWS", "amount": "0.45", "attackPeak": "really"}) in found
    assert any(e == "gesture" and a["lexeme"] == "BEAT_LARGE" and a["stroke"] == "really" for e, a in found)
    gaze = [(e, a) for e, a in found if e in ("gaze", "gazeShift")]
    assert [e for e, _ in gaze] == ["gaze", "gazeShift"] and gaze[0][1]["start"] == "start"
    assert gaze[0][1]["end"] == gaze[1][1]["start"] and gaze[0][1]["target"] == "bob"


def test_deictics_need_something_to_point_at(tmp_path):
    rules = certain_rules(tmp_path)
    alone = {"ann": "character"}
    found = elements(generated("Could you pass me that cup over there?", rules, names=alone))
    assert not any(e == "pointing" for e, _ in found) and not any(e.startswith("gaze") for e, _ in found)
    found = elements(generated("I have been thinking about it for a long while, and you are right.", rules))
    assert ("gesture", {"lexeme": "SELF", "mode": "RIGHT_HAND", "stroke": "I"}) in found
    assert ("pointing", {"target": "bob", "stroke": "you"}) in found
    assert any(e == "head" and a["lexeme"] == "NOD" and a["stroke"] == "right" for e, a in found)


def test_one_pointing_per_target_and_sentence_and_no_shake_on_a_question_tag(tmp_path):
    rules = certain_rules(tmp_path)
    found = elements(generated("Please switch on that cup over there, next to the window. It is simple, isn't it?", rules))
    assert [a["stroke"] for e, a in found if e == "pointing"] == ["that"]
    assert not any(e == "head" and a["lexeme"] == "SHAKE" for e, a in found)
    found = elements(generated("It is not simple at all, and the window is broken too.", rules))
    assert any(e == "head" and a["lexeme"] == "SHAKE" and a["stroke"] == "not" for e, a in found)


def test_nothing_starts_before_its_block_when_the_speech_is_pinned_to_its_start():
    for start, nods in (("0.2", 0), ("1.5", 1)):
        scheduler = Scheduler(names=lambda: {"ann": "character"})
        (record,) = scheduler.submit(block("Yes.").replace('<speech id="s1">', f'<speech id="s1" start="{start}">'))
        assert sum(a.controller == "head" for a in record.activations) == nods
        assert not [e for e in scheduler.feedback.log if e.kind == "warningFeedback"]


def test_words_the_conversation_said_recently_are_given_not_new(tmp_path):
    rules = certain_rules(tmp_path)
    earlier = ("The old pump pushes the water up to the garden.",)
    text = "Yesterday, the pump broke."

    def beats(said):
        return [a["stroke"] for e, a in elements(generated(text, rules, said=said))
                if e == "gesture" and a["lexeme"] == "BEAT"]
    assert "pump" in beats(()) and "pump" not in beats(earlier)
    remembered = load_rules(rules).remembered_utterances
    assert "pump" in beats(earlier + ("Nothing else.",) * remembered)  # said too long ago: new again


def test_expressiveness_scales_how_much_the_speaker_does():
    text = ("Well, the first thing you have to know is that the machine is old, and the second thing is that "
            "nobody has the manual anymore, so we really must be careful with it.")

    def added(value):
        scheduler = Scheduler(names=lambda: CAST, seed=3)
        flag = f'infuse:nonverbal="true" infuse:expressiveness="{value}"'
        (record, *_) = scheduler.submit(block(text, flag=flag))
        return sum(a.controller in ("gesture", "pointing", "head", "face") for a in record.activations), scheduler
    counts = [added(v)[0] for v in ("0", "0.5", "1", "2")]
    assert counts[0] == 0 and counts[0] < counts[1] < counts[2] <= counts[3], counts
    _, scheduler = added("lots")
    assert any("infuse:expressiveness='lots' is not a number from 0 to 3" in e.description
               for e in scheduler.feedback.log if e.kind == "warningFeedback")


def test_strokes_keep_their_channel_gap_in_estimated_time(tmp_path):
    scheduler, (record, _) = schedule("Bring the red box, the green bag, the old lamp and the new chair to the door, "
                                      "because the big truck leaves early tomorrow morning.", seed=3)
    strokes = sorted(a.time("stroke") for a in record.activations if a.controller in ("gesture", "pointing"))
    gap = load_rules().gap_s["hands"]
    assert len(strokes) >= 3 and min(b - a for a, b in zip(strokes, strokes[1:])) >= gap - 1e-9


def test_every_stroke_is_on_its_words_mark():
    scheduler, records = schedule("So here is the plan: we take the long road north, then we cross the river, "
                                  "and finally we meet the others at the old bridge. Is that clear?", seed=11)
    record = records[0]
    speech = record.activation("s1")
    marks = {m: speech.start + t for m, t in speech.parameters["marks_s"].items()}
    refs = {b.id: b.sync_refs for b in record.block.behaviours}
    checked = 0
    for a in record.activations:
        for sync, ref in refs[a.behaviour].items():
            if ref.behaviour == "s1" and ref.sync in marks:
                assert a.sync_times[sync] == pytest.approx(marks[ref.sync], abs=1e-9)
                checked += 1
    assert checked >= 6


def test_the_listener_nods_on_the_speakers_phrase_ends():
    scheduler, records = schedule("Well, the first thing you have to know is that the machine is old, "
                                  "and the second thing is that nobody has the manual anymore.", seed=2)
    speaker, listener = records
    assert listener.character == "bob" and listener.id == "b1_bob_nv"
    speech = speaker.activation("s1")
    ends = {speech.start + t for m, t in speech.parameters["marks_s"].items() if m.startswith("nve")}
    nods = [a for a in listener.activations if a.controller == "head"]
    assert nods and all(any(abs(a.time("stroke") - t) < 1e-9 for t in ends) for a in nods)


def test_the_added_bml_is_feedback_and_the_seed_repeats_it():
    def feedback(seed):
        scheduler, _ = schedule("Now let me show you the whole thing, step by step, from the very beginning.", seed=seed)
        return next(e.bml for e in scheduler.feedback.log if e.kind == "generatedBml")
    first = feedback(7)
    assert first == feedback(7) and first != feedback(8)
    assert first.startswith("<act>") and 'characterId="bob"' in first and '<sync id="nvw' in first


def test_the_author_keeps_the_channels_it_uses(tmp_path):
    rules = certain_rules(tmp_path)
    found = elements(generated("No, that cup is really important, I am sure.", rules,
                               extra='<gesture id="mine" lexeme="OFFER"/><gaze id="look" target="bob"/>'))
    channels = {e for e, _ in found}
    assert "gesture" not in channels and "pointing" not in channels and "gaze" not in channels
    assert "head" in channels and "faceLexeme" in channels


def test_off_by_default_on_by_flag_scene_key_or_scheduler(tmp_path):
    text = "Yes, absolutely, I agree with every word of that."
    plain = Scheduler(names=lambda: CAST)
    (record,) = plain.submit(block(text, flag=""))
    assert [a.behaviour for a in record.activations] == ["s1"]
    on = Scheduler(names=lambda: CAST, generators=("nonverbal",))
    records = on.submit(block(text, flag=""))
    assert len(records[0].activations) > 1
    off = on.submit(block(text, flag='infuse:nonverbal="false"', block_id="b2"))
    assert [a.behaviour for a in off[0].activations] == ["s1"]
    (tmp_path / "ann.bvh").write_text("")
    scene_file = tmp_path / "scene.toml"
    scene_file.write_text('generators = ["nonverbal"]\n[[character]]\nname = "ann"\nfile = "ann.bvh"\n')
    assert read_scene_file(scene_file).generators == ("nonverbal",)
    xml_file = tmp_path / "scene.xml"
    xml_file.write_text('<scene generators="nonverbal"><character name="ann" file="ann.bvh"/></scene>')
    assert read_scene_file(xml_file).generators == ("nonverbal",)
    scene_file.write_text('generators = ["talkative"]\n[[character]]\nname = "ann"\nfile = "ann.bvh"\n')
    with pytest.raises(InputError, match=r"scene.toml:generators: no BML generator named 'talkative'; installed: .*nonverbal"):
        build_scene(read_scene_file(scene_file))
    scene_file.write_text('generators = [3]\n[[character]]\nname = "ann"\nfile = "ann.bvh"\n')
    with pytest.raises(InputError, match=r"scene.toml:generators: expected a list of names, got \[3\]"):
        read_scene_file(scene_file)


def test_a_smartbody_act_turns_it_on_without_declaring_the_prefix():
    scheduler = Scheduler(names=lambda: CAST)
    records = scheduler.submit('<act><bml characterId="ann" infuse:nonverbal="true"><speech id="s1">'
                               "Yes, I think you are absolutely right about the old machine.</speech></bml></act>")
    assert len(records) == 2 and any(a.behaviour.startswith("nv") for a in records[0].activations)
    assert not [e for e in scheduler.feedback.log if e.kind == "warningFeedback"]


def test_settings_name_the_listener_and_the_seed(tmp_path):
    rules = certain_rules(tmp_path)
    cast = {"ann": "character", "bob": "character", "cid": "character"}
    g = generated("You know, the machine is old and nobody has the manual anymore.", rules, names=cast,
                  settings={"listener": "CID"})
    assert g.blocks[0].character_id == "cid" and ("pointing", {"target": "cid", "stroke": "You"}) in elements(g)
    g = generated("You know, the machine is old.", rules, names=cast, settings={"listener": "dan"})
    assert g.blocks == () and "infuse:listener='dan' names no character" in g.notes[0]
    scheduler = Scheduler(names=lambda: CAST)
    scheduler.submit(block("Fine.", flag='infuse:nonverbal="true" infuse:seed="x"'))
    assert any("infuse:seed='x' is not an integer" in e.description for e in scheduler.feedback.log
               if e.kind == "warningFeedback")


@pytest.mark.parametrize("change, place, problem", [
    ('channel = "hands"', "rule[1].channel", "expected one of hands, head, face"),
    ('on = "greeting"', None, None),
    ("bml = '<gesture lexeme=\"WAVE\" mode=\"{hand}\"/>'", "rule[1].bml", "the element sets its own sync points"),
    ("\nprobability = 1.0", "listener.probability", "expected a number in [0, 1]"),
])
def test_a_mistake_in_the_rules_names_the_file_and_the_key(tmp_path, change, place, problem):
    broken = {'channel = "hands"': 'channel = "feet"',
              'on = "greeting"': 'on = "greetings"',
              "bml = '<gesture lexeme=\"WAVE\" mode=\"{hand}\"/>'": "bml = '<gesture lexeme=\"WAVE\" stroke=\"1\"/>'",
              "\nprobability = 1.0": "\nprobability = 1.5"}[change]
    text = certain_rules(tmp_path).read_text().replace(change, broken, 1)
    assert text != certain_rules(tmp_path).read_text()
    path = tmp_path / "broken.toml"
    path.write_text(text)
    tomllib.loads(text)
    with pytest.raises(InputError) as caught:
        load_rules(path)
    message = str(caught.value)
    assert str(path) in message
    if place is None:
        assert "rule[1].on" in message and "'greetings' is no word class" in message
    else:
        assert place in message and problem in message
