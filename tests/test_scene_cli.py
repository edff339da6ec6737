"""``infuse run SCENE -o OUTDIR`` on small scenes (TOML and XML): the files it writes, what they hold,
and clear one-line errors with exit codes 2 and 3."""
from __future__ import annotations

import json
import wave

import numpy as np
import pytest
from lxml import etree
from PIL import Image

import infuse
from infuse.cli import main

from corpus_data import corpus_file

BML_NS = "http://www.bml-initiative.org/bml/bml-1.0"


def scene_toml(tmp_path, blocks: str = "", extra: str = "") -> str:
    rpm = corpus_file("talkinghead/avatars/brunette-t.glb")
    utah = corpus_file("smartbody/behaviorsets/MaleLocomotion/skeletons/test_utah.sk")
    text = f'''fps = 25
[[character]]
name = "ann"
file = "{rpm}"
position = [0.0, 0.0, 1.8]
facing = "sam"

[[character]]
name = "sam"
file = "{utah}"
facing = [0.0, 1.8]

[[object]]
name = "ball"
position = [0.3, 0.2, 1.0]
size = 0.2
{extra}
[[block]]
at = 0.2
character = "ann"
bml = \'\'\'<bml xmlns="{BML_NS}" id="hello">
  <speech id="s1"><text>Good <sync id="m"/>morning!</text></speech>
  <gaze id="g1" target="ball" start="s1:m" end="s1:end+0.5"/>
</bml>\'\'\'

[[block]]
at = 0.5
file = "nod.xml"
{blocks}'''
    (tmp_path / "nod.xml").write_text('<act><bml id="nod" characterId="sam"><head id="h" type="NOD" repeats="2"/>'
                                      '<gaze id="g" target="ann" sbm:joint-range="NECK EYES"/></bml></act>')
    path = tmp_path / "scene.toml"
    path.write_text(text)
    return str(path)


def test_run_writes_characters_audio_feedback_and_preview(tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["run", scene_toml(tmp_path), "-o", str(out), "--quiet"]) == 0
    printed = capsys.readouterr().out
    assert "2 characters, 2 blocks" in printed
    assert sorted(p.name for p in out.iterdir()) == ["ann.glb", "ann.wav", "feedback.jsonl", "feedback.xml",
                                                     "preview.png", "sam.glb"]
    ann = infuse.load(out / "ann.glb")
    frames = ann.motions["scene"].num_frames
    assert ann.motions["scene"].fps == 25 and ann.motions["scene"].morph_names
    with wave.open(str(out / "ann.wav")) as f:
        assert abs(f.getnframes() / f.getframerate() - frames / 25) <= 1 / 25
    sam = infuse.load(out / "sam.glb")
    assert sam.motions["scene"].num_frames == frames
    assert np.ptp(sam.motions["scene"].local_rotations, axis=0).max() > 0.05  # sam nods and turns his head
    events = [json.loads(line) for line in (out / "feedback.jsonl").read_text().splitlines()]
    progress = [e for e in events if e["kind"] in ("blockProgress", "syncPointProgress")]
    assert [e["global_time"] for e in progress] == sorted(e["global_time"] for e in progress)
    assert {(e["block"], e["sync"]) for e in events if e["kind"] == "blockProgress"} == {
        ("hello", "start"), ("hello", "end"), ("nod", "start"), ("nod", "end")}
    root = etree.fromstring((out / "feedback.xml").read_bytes())
    assert len(root) == len(events) and etree.QName(root[0]).localname in ("predictionFeedback", "warningFeedback")
    image = Image.open(out / "preview.png")
    assert image.size[0] > 2 * image.size[1]


def test_xml_scene_and_bvh_output(tmp_path):
    rpm = corpus_file("talkinghead/avatars/brunette-t.glb")
    scene = tmp_path / "scene.xml"
    scene.write_text(f'''<scene fps="30" duration="1.5">
  <!-- one character nodding -->
  <character name="ann" file="{rpm}" position="0 0 0" facing="90"/>
  <object name="lamp" position="1 1.8 0.5"/>
  <block at="0.1"><bml xmlns="{BML_NS}" id="b1" characterId="ann"><head id="h" lexeme="NOD"/>
    <gazeShift id="g" target="lamp"/></bml></block>
</scene>''')
    out = tmp_path / "out"
    assert main(["run", str(scene), "-o", str(out), "--format", "bvh", "--preview", "none", "--quiet"]) == 0
    assert sorted(p.name for p in out.iterdir()) == ["ann.bvh", "feedback.jsonl", "feedback.xml"]
    motion = next(iter(infuse.load(out / "ann.bvh").motions.values()))
    assert motion.num_frames == 45


@pytest.mark.parametrize("change,code,words", [
    (("file = \"nod.xml\"", "file = \"missing.xml\""), 2, "block[2].file: file not found"),
    (("size = 0.2", "size = -1"), 2, "object[1].size: must be positive"),
    (("facing = \"sam\"", "facing = \"nobody\""), 2, "character[1]"),
    (("fps = 25", "fps = 25\ncolour = 3"), 2, "colour: unknown key"),
    (("<sync id=\"m\"/>", "<sync id=\"m\">"), 2, "block[1]"),
    (("at = 0.5", "at = 0.5\ncharacter = \"zed\""), 2, "block[2].character: no character 'zed'"),
])
def test_bad_scene_files_exit_with_one_line(tmp_path, capsys, change, code, words):
    path = tmp_path / "scene.toml"
    text = open(scene_toml(tmp_path)).read()
    assert change[0] in text
    path.write_text(text.replace(change[0], change[1], 1))
    out = tmp_path / "out"
    assert main(["run", str(path), "-o", str(out), "--quiet"]) == code
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and words in err[0] and str(path) in err[0]
    assert not out.exists()  # nothing written


def test_a_character_that_is_not_humanoid_exits_3(tmp_path, capsys):
    path = tmp_path / "scene.toml"
    prop = tmp_path / "stick.bvh"
    prop.write_text("HIERARCHY\nROOT a\n{\n OFFSET 0 0 0\n CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n"
                    " JOINT b\n {\n  OFFSET 0 10 0\n  CHANNELS 3 Zrotation Xrotation Yrotation\n  End Site\n  {\n   OFFSET 0 10 0\n  }\n }\n}\n"
                    "MOTION\nFrames: 1\nFrame Time: 0.0333333\n0 0 0 0 0 0 0 0 0\n")
    path.write_text(f'[[character]]\nname = "stick"\nfile = "{prop}"\n')
    assert main(["run", str(path), "-o", str(tmp_path / "out")]) == 3
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "not a humanoid" in err[0]


def test_usage_errors(tmp_path, capsys):
    assert main(["run", str(tmp_path / "none.toml"), "-o", str(tmp_path / "o")]) == 2
    assert "scene file not found" in capsys.readouterr().err
    (tmp_path / "scene.json").write_text("{}")
    assert main(["run", str(tmp_path / "scene.json"), "-o", str(tmp_path / "o")]) == 2
    assert ".toml or .xml" in capsys.readouterr().err


def test_the_demo_scene_and_infuse_run_agree(tmp_path, monkeypatch, capsys):
    """``make demo``'s scene: Bob walks up to Ann, both look at each other, Bob nods, Ann speaks and reaches;
    ``infuse run examples/scenes/demo.toml`` gives the same files."""
    import importlib.util

    from corpus_data import REPO, require_corpus

    require_corpus()
    spec = importlib.util.spec_from_file_location("infuse_demo_scene", REPO / "examples" / "demo.py")
    demo = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(demo)
    monkeypatch.setattr(demo, "OUT", tmp_path / "demo")
    assert demo.scene_demo() == 0
    printed = capsys.readouterr().out
    assert "bob: bob_walk starts" in printed and "ann: ann_talk ends" in printed
    made = tmp_path / "demo" / "scene"
    assert {p.name for p in made.iterdir()} == {"bob.glb", "ann.glb", "ann.wav", "feedback.xml", "feedback.jsonl",
                                                 "preview.png", "scene.gif"}
    assert main(["run", str(REPO / "examples" / "scenes" / "demo.toml"), "-o", str(tmp_path / "run"), "--quiet"]) == 0
    # espeak-ng's timings vary by some milliseconds from one synthesis in a process to the next, so the
    # scene may end a frame or two apart (a file's last frames may hold the last evaluated pose); Bob's
    # walk and nod do not depend on them
    a, b = (infuse.load(folder / "bob.glb").motions["scene"] for folder in (made, tmp_path / "run"))
    common = min(a.num_frames, b.num_frames) - 2
    assert abs(a.num_frames - b.num_frames) <= 2
    assert np.allclose(a.local_rotations[:150], b.local_rotations[:150], atol=1e-6)  # the walk and the nod
    assert np.allclose(a.root_translations[:common], b.root_translations[:common], atol=1e-6)
    bob = infuse.load(made / "bob.glb").motions["scene"]
    hips = infuse.motion_fk(bob)[1][:, 0]
    assert np.linalg.norm(hips[-1, [0, 2]] - (0.0, 0.8)) < 0.15  # Bob walked to his spot
    events = [json.loads(line) for line in (made / "feedback.jsonl").read_text().splitlines()]
    kinds = {e["behaviour"] for e in events if e["kind"] == "syncPointProgress"}
    assert {"walk", "nod", "speech", "reach", "smile", "look_cup"} <= kinds
    assert not [e for e in events if e["kind"] == "warningFeedback" and e["type"] == "CANNOT_CREATE_BEHAVIOR"]
