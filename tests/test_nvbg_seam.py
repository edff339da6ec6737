"""The BML generator seam: a block's ``infuse:NAME`` attribute or the scheduler's ``generators`` run a
generator before scheduling; what it adds is scheduled and reported as ``generatedBml`` feedback."""
from __future__ import annotations

import sys
import types
from dataclasses import replace

import pytest

import infuse
from infuse import registry
from infuse.bml import Generation, GenerationError, Scheduler, parse_bml
from infuse.errors import UsageError
from infuse.plugin_types import BMLGenerator

BML = "http://www.bml-initiative.org/bml/bml-1.0"


def _add_nod(block, context):
    """Adds a nod on the first speech's end, and a listener block for every other character."""
    if context.settings.get("fail") == "yes":
        raise GenerationError("asked to fail")
    speech = next(b for b in block.behaviours if b.element == "speech")
    amount = context.settings.get("amount", "0.5")
    added = f'<bml xmlns="{BML}" id="{block.id}"><head id="gen_nod" lexeme="NOD" amount="{amount}" stroke="{speech.id}:end"/></bml>'
    (extra,) = parse_bml(added).blocks
    listeners = tuple(
        parse_bml(f'<bml xmlns="{BML}" id="{block.id}_{name}" characterId="{name}">'
                  f'<head id="back" lexeme="NOD" stroke="{block.id}:{speech.id}:end"/></bml>').blocks[0]
        for name in context.characters if name != context.character)
    return Generation(replace(block, behaviours=block.behaviours + extra.behaviours), listeners, added,
                      notes=(f"seed {context.seed}, said before: {' / '.join(context.said) or 'nothing'}",))


@pytest.fixture
def generator():
    module = types.ModuleType("seam_generator")

    @infuse.hookimpl
    def infuse_bml_generators():
        return [BMLGenerator("nodder", _add_nod, "a nod at the end of speech", frozenset({"amount", "fail"}))]

    module.infuse_bml_generators = infuse_bml_generators
    sys.modules[module.__name__] = module
    registry.plugins().register(module)
    yield module
    registry.plugins().unregister(module)
    del sys.modules[module.__name__]


SPEECH = (f'<bml xmlns="{BML}" xmlns:infuse="urn:infuse:bml" id="b1" characterId="ann" {{flag}}>'
          '<speech id="s1"><text>Hello there.</text></speech></bml>')


def test_a_block_turns_a_generator_on_and_its_bml_is_feedback(generator):
    scheduler = Scheduler(names=lambda: {"ann": "character", "bob": "character", "cup": "object"})
    records = scheduler.submit(SPEECH.format(flag='infuse:nodder="true" infuse:amount="0.8"'))
    assert [r.id for r in records] == ["b1", "b1_bob"]
    nod = records[0].activation("gen_nod")
    speech = records[0].activation("s1")
    assert nod.parameters["amount"] == pytest.approx(0.8)
    assert nod.time("stroke") == pytest.approx(speech.end)
    assert records[1].character == "bob" and records[1].activation("back").time("stroke") == pytest.approx(speech.end)
    (generated,) = [e for e in scheduler.feedback.log if e.kind == "generatedBml"]
    assert generated.generator == "nodder" and generated.block == "b1" and 'id="gen_nod"' in generated.bml
    assert "<infuse:generatedBml" in generated.to_xml() and "gen_nod" in generated.to_xml()
    warnings = [e.description for e in scheduler.feedback.log if e.kind == "warningFeedback"]
    assert len(warnings) == 1 and warnings[0].startswith("seed ")


def test_the_seed_depends_on_the_scheduler_seed_and_the_block(generator):
    def seed_of(seed):
        scheduler = Scheduler(generators=("nodder",), seed=seed)
        scheduler.submit(SPEECH.format(flag=""))
        return next(e.description for e in scheduler.feedback.log if e.kind == "warningFeedback")
    assert seed_of(3) == seed_of(3) != seed_of(4)


def test_a_generator_knows_what_was_said_before(generator):
    scheduler = Scheduler(generators=("nodder",))
    scheduler.submit(SPEECH.format(flag=""))
    scheduler.submit(SPEECH.format(flag="").replace('"b1"', '"b2"').replace("Hello there.", "Hi again."))
    notes = [e.description for e in scheduler.feedback.log if e.kind == "warningFeedback"]
    assert notes[0].endswith("said before: nothing") and notes[1].endswith("said before: Hello there.")


def test_off_unknown_and_failing_generators_warn_and_the_block_still_plays(generator):
    scheduler = Scheduler(generators=("nodder",))
    (record,) = scheduler.submit(SPEECH.format(flag='infuse:nodder="false"'))
    assert [a.behaviour for a in record.activations] == ["s1"]
    (record,) = scheduler.submit(SPEECH.format(flag='infuse:nodder="maybe" infuse:colour="red"').replace('"b1"', '"b2"'))
    warnings = [e.description for e in scheduler.feedback.log if e.kind == "warningFeedback"]
    assert any("infuse:nodder='maybe' is neither true nor false" in w for w in warnings)
    assert any("'infuse:colour' names no installed BML generator (infuse:nodder" in w for w in warnings)
    assert record.activation("gen_nod") is not None  # still on: the scheduler's default
    (record,) = scheduler.submit(SPEECH.format(flag='infuse:fail="yes"').replace('"b1"', '"b3"'))
    assert [a.behaviour for a in record.activations] == ["s1"]
    assert any("generator 'nodder' added nothing: asked to fail" in e.description for e in scheduler.feedback.log
               if e.kind == "warningFeedback")


def test_an_unknown_default_generator_is_a_usage_error(generator):
    with pytest.raises(UsageError, match="no BML generator named 'talker'; installed: .*nodder"):
        Scheduler(generators=("talker",))
