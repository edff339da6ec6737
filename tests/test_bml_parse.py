"""BML parsing: dialects, names, speech marks, constraints, sync references, and refusing unsafe XML."""
from __future__ import annotations

import pytest

from infuse.bml import SyncRefError, parse_bml, parse_sync_ref
from infuse.bml.model import DIALECT_BML1, DIALECT_DRAFT, DIALECT_SMARTBODY
from infuse.errors import InputError

BML = 'xmlns="http://www.bml-initiative.org/bml/bml-1.0"'


def test_bml1_block_behaviours_and_constraints():
    doc = parse_bml(f"""<bml {BML} id="b1" characterId="Alice" composition="append">
      <speech id="s1"><text>Hello <sync id="tm1"/>world.</text></speech>
      <head id="h1" lexeme="NOD" start="s1:tm1+0.5" stroke_end="2"/>
      <required><gesture id="g1" lexeme="BEAT" stroke="s1:tm1"/></required>
      <constraint id="c1">
        <synchronize><sync ref="h1:stroke"/><sync ref="g1:stroke-0.25"/></synchronize>
        <before ref="s1:end"><sync ref="g1:end"/></before>
      </constraint>
    </bml>""", file="inline.xml")
    (block,) = doc.blocks
    assert (block.id, block.character_id, block.composition, block.dialect) == ("b1", "Alice", "APPEND", DIALECT_BML1)
    speech, head, gesture = block.behaviours
    assert speech.text == "Hello world." and speech.marks == (("tm1", 6),)
    assert head.sync_refs["start"].behaviour == "s1" and head.sync_refs["start"].offset == 0.5
    assert head.sync_refs["strokeEnd"].time == 2.0  # SmartBody spelling normalized
    assert head.attributes == {"lexeme": "NOD"} and not head.required and gesture.required
    sync, before = block.constraints
    assert sync.kind == "synchronize" and [r.text for r in sync.syncs] == ["h1:stroke", "g1:stroke-0.25"]
    assert sync.syncs[1].offset == -0.25 and sync.id == "c1"
    assert before.kind == "before" and before.ref.sync == "end" and before.syncs[0].behaviour == "g1"


def test_smartbody_act_envelope_with_undeclared_sbm_prefix():
    doc = parse_bml("""<?xml version="1.0" encoding="UTF-8"?>
<!-- a SmartBody script line -->
<act>
  <bml>
    <sbm:reach sbm:action="touch" target="pawn3"/> + <speech type="text/plain">Hi there</speech>
  </bml>
</act>""")
    (block,) = doc.blocks
    assert block.dialect == DIALECT_SMARTBODY and block.id == "bml1"
    reach, speech = block.behaviours
    assert reach.element == "sbm:reach" and reach.attributes == {"sbm:action": "touch", "target": "pawn3"}
    assert reach.id and not reach.id_given
    assert speech.text == "Hi there"
    assert doc.comments == (" a SmartBody script line ",)
    assert not block.issues  # sbm: is the dialect, not a problem


def test_other_undeclared_prefix_is_reported_and_its_attribute_kept_apart():
    doc = parse_bml(f'<bml {BML} id="b"><head id="n" lexeme="NOD" odd:thing="1"/></bml>')
    (block,) = doc.blocks
    assert block.behaviours[0].attributes == {"lexeme": "NOD", "odd:thing": "1"}
    assert any("odd" in i.description for i in block.issues)


def test_draft_namespace_speech_with_tm_markers_and_prosody_children():
    doc = parse_bml("""<bml xmlns="http://www.mindmakers.org/projects/BML" character="Greta" composition="replace" id="x">
      <speech xmlns="" id="s1" start="0.0"><description type="gretabml"><reference>f.pho</reference></description>
        <tm id="tm1"/> Hello, <tm id="tm2"/> my name is Camille. <tm id="tm3"/>
        <boundary id="b1" start="s1:tm3" end="s1:tm3+0.5" type="LL"/>
      </speech>
      <face id="f" start="-0.6" end="1.5"><lexeme lexeme="joy"/></face>
    </bml>""")
    (block,) = doc.blocks
    assert block.dialect == DIALECT_DRAFT and block.composition == "REPLACE" and block.character_id == "Greta"
    speech, face = block.behaviours
    assert speech.text == "Hello, my name is Camille."
    assert speech.marks == (("tm1", 0), ("tm2", 7), ("tm3", 26))
    assert face.sync_refs["start"].time == -0.6
    assert face.children[0].name == "lexeme" and face.children[0].attributes == {"lexeme": "joy"}


def test_duplicate_and_missing_ids_are_named_and_reported():
    doc = parse_bml(f'<bml {BML} id="b"><head id="h"/><head id="h"/><gesture lexeme="BEAT"/></bml>')
    ids = [b.id for b in doc.blocks[0].behaviours]
    assert ids[0] == "h" and ids[1] == "h#2" and ids[2] == "gesture_1"
    assert any("used twice" in i.description for i in doc.blocks[0].issues)


def test_block_extension_attributes():
    doc = parse_bml(f'<bml {BML} xmlns:bmla="http://www.asap-project.org/bmla" id="b5" '
                    f'bmla:appendAfter="b1, b2" bmla:interrupt="b3" mood="x"/>')
    (block,) = doc.blocks
    assert block.append_after == ("b1", "b2") and block.interrupts == ("b3",)
    assert [i.type for i in block.issues] == ["CUSTOM_ATTRIBUTE_NOT_SUPPORTED"]


@pytest.mark.parametrize("text, expected", [
    ("2.5", dict(time=2.5)),
    ("-0.56", dict(time=-0.56)),
    ("b1:end+0.5", dict(behaviour="b1", sync="end", offset=0.5)),
    ("h1:start - 1", dict(behaviour="h1", sync="start", offset=-1.0)),
    ("bml2:b1:stroke", dict(block="bml2", behaviour="b1", sync="stroke")),
    ("g1:stroke:2", dict(behaviour="g1", sync="stroke", iteration=2)),
    ("g1:stroke_start", dict(behaviour="g1", sync="strokeStart")),
    ("s1:tm1", dict(behaviour="s1", sync="tm1")),
    ("joint 1:end", dict(behaviour="joint 1", sync="end")),
])
def test_sync_reference_grammar(text, expected):
    ref = parse_sync_ref(text)
    for key, value in expected.items():
        assert getattr(ref, key) == value, key


@pytest.mark.parametrize("text", ["nod1:relax:2", "a:b:c:d", ":end", "nod1", "g1:stroke:0", "b1:st\nart"])
def test_invalid_sync_references(text):
    with pytest.raises(SyncRefError):
        parse_sync_ref(text)


def test_malformed_xml_names_file_and_line():
    with pytest.raises(InputError) as info:
        parse_bml(f'<bml {BML} id="b">\n<speech id="s"><text>x</text></speech>\n</speech>\n</bml>', file="bad.bml")
    assert info.value.file == "bad.bml" and info.value.place == "line 3" and "malformed XML" in info.value.problem


@pytest.mark.parametrize("root", ["<notbml/>", "<act><other/></act>"])
def test_wrong_root(root):
    with pytest.raises(InputError, match="line 1"):
        parse_bml(root)


BILLION_LAUGHS = """<?xml version="1.0"?>
<!DOCTYPE lolz [<!ENTITY lol "lol"><!ENTITY lol2 "&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;">
<!ENTITY lol3 "&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;">
<!ENTITY lol4 "&lol3;&lol3;&lol3;&lol3;&lol3;&lol3;&lol3;&lol3;&lol3;&lol3;">]>
<bml xmlns="http://www.bml-initiative.org/bml/bml-1.0" id="b"><speech id="s"><text>&lol4;</text></speech></bml>"""


def test_billion_laughs_is_refused():
    with pytest.raises(InputError, match="DOCTYPE"):
        parse_bml(BILLION_LAUGHS)


def test_external_entity_file_read_is_refused(tmp_path):
    secret = tmp_path / "secret.txt"
    secret.write_text("TOP-SECRET-CONTENT")
    xxe = (f'<?xml version="1.0"?><!DOCTYPE b [<!ENTITY x SYSTEM "file://{secret}">]>'
           f'<bml {BML} id="b"><speech id="s"><text>&x;</text></speech></bml>')
    with pytest.raises(InputError) as info:
        parse_bml(xxe)
    assert "TOP-SECRET" not in str(info.value)


def test_external_dtd_is_not_fetched(tmp_path):
    dtd = tmp_path / "evil.dtd"
    dtd.write_text('<!ENTITY x "INJECTED">')
    with pytest.raises(InputError, match="DOCTYPE"):
        parse_bml(f'<?xml version="1.0"?><!DOCTYPE bml SYSTEM "file://{dtd}"><bml {BML} id="b"/>')


def test_size_limit(tmp_path):
    big = f'<bml {BML} id="b"><speech id="s"><text>{"a" * 5000}</text></speech></bml>'
    with pytest.raises(InputError, match="larger than 1000 bytes"):
        parse_bml(big, max_bytes=1000)
    path = tmp_path / "big.xml"
    path.write_text(big)
    from infuse.bml import parse_bml_file
    with pytest.raises(InputError, match="big.xml"):
        parse_bml_file(path, max_bytes=1000)


def test_string_with_encoding_declaration_parses():
    doc = parse_bml(f'<?xml version="1.0" encoding="ISO-8859-1"?><bml {BML} id="b"><speech id="s"><text>Caf\u00e9</text></speech></bml>')
    assert doc.blocks[0].behaviours[0].text == "Caf\u00e9"
