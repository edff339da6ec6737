"""The example BML behaviour package (examples/example_bml_behaviour): its <ex:shrug> element is installed,
scheduled against other behaviours, reported when wrong, and realized by the 'shrug' controller."""
from __future__ import annotations

import numpy as np
import pytest

import infuse
from infuse.bml import Scheduler
from infuse.bml.behaviours import installed_handlers
from infuse.cli import main as cli_main
from infuse.kinematics import motion_fk
from infuse.runtime import Runtime

from corpus_data import corpus_file

ELEMENT = "{urn:infuse:example}shrug"
FPS = 30


def _block(body: str) -> str:
    return ('<bml xmlns="http://www.bml-initiative.org/bml/bml-1.0" xmlns:ex="urn:infuse:example" id="b1" '
            f'characterId="bob">{body}</bml>')


def _schedule(body: str):
    scheduler = Scheduler()
    warnings = []
    scheduler.feedback.subscribe(warnings.append, kinds=["warningFeedback"])
    (block,) = scheduler.submit(_block(body), at=0.0)
    return {a.behaviour: a for a in block.activations}, warnings


def test_listed_by_infuse_plugins_and_installed_as_a_handler(capsys):
    assert cli_main(["plugins"]) == 0
    rows = [line.split() for line in capsys.readouterr().out.splitlines()]
    assert ["shrug", "bml-behaviour", "infuse-anim-example-bml", "0.1.0", "ok"] in rows
    assert installed_handlers()[ELEMENT].attributes == {"amount", "duration"}


def test_natural_timing_and_parameters():
    acts, warnings = _schedule('<ex:shrug id="sh1" amount="0.6" duration="2" start="1"/>')
    assert warnings == []
    a = acts["sh1"]
    assert a.controller == "shrug" and a.element == ELEMENT
    assert a.parameters == {"amount": 0.6, "duration_s": 2.0}
    assert a.sync_times == pytest.approx({"start": 1.0, "ready": 1.5, "stroke": 1.9, "relax": 2.3, "end": 3.0})


def test_stroke_aligned_to_a_speech_mark():
    acts, warnings = _schedule('<speech id="s1"><text>I do not <sync id="tm1"/>know.</text></speech>'
                               '<ex:shrug id="sh1" stroke="s1:tm1" end="s1:end+0.5"/>')
    assert warnings == []
    speech, shrug = acts["s1"], acts["sh1"]
    assert shrug.sync_times["stroke"] == pytest.approx(speech.sync_times["tm1"])
    assert shrug.end == pytest.approx(speech.end + 0.5)
    times = list(shrug.sync_times.values())
    assert times == sorted(times)


def test_bad_values_and_unknown_attributes_are_warnings_and_the_block_runs():
    acts, warnings = _schedule('<ex:shrug id="sh1" amount="lots"/><ex:shrug id="sh2" colour="red"/>'
                               '<head id="h1" lexeme="NOD"/>')
    kinds = {w.id: w.type for w in warnings}
    assert "sh1" not in acts and "b1:sh1" in kinds                       # dropped, with the reason
    assert kinds["b1:sh2"] == "CUSTOM_ATTRIBUTE_NOT_SUPPORTED" and "sh2" in acts
    assert "h1" in acts


def test_realized_by_the_shrug_controller():
    acts, _ = _schedule('<ex:shrug id="sh1" amount="1" duration="1.2" start="0.3"/>')
    asset = infuse.load(corpus_file("runxaway-models/Xbot.glb"))
    rt = Runtime(fps=FPS)
    bob = rt.add_character(infuse.Character("bob", asset))
    activity = rt.realize(acts["sh1"], bob)
    assert activity is not None and activity.controller.kind == "shrug"
    rt.run(2.0)
    motion = rt.motion(bob)
    _, positions = motion_fk(motion)
    shoulder = motion.skeleton.names.index("mixamorig:LeftArm")
    rise = positions[:, shoulder, 1] - positions[0, shoulder, 1]
    frames = np.arange(len(rise)) / FPS
    s = acts["sh1"].sync_times
    held = (frames >= s["ready"] + 0.02) & (frames <= s["relax"] - 0.02)
    assert rise[held].min() > 0.01 and np.ptp(rise[held]) < 1e-6         # up and still between ready and relax
    assert np.abs(rise[frames < s["start"]]).max() < 1e-9
    assert np.abs(rise[frames > s["end"] + 0.02]).max() < 1e-9
