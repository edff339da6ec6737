"""Issue-level check across every reader: each labelled corpus file loads and ``infuse info --json``
reports joint names containing every joint its label maps, plus parents, frames, fps, units, up axis."""
import json
import subprocess
import sys

import pytest

import infuse
from corpus_data import CORPUS, labels, require_corpus
from infuse.cli.builtin import asset_summary

LABELS = labels()
REQUIRED_KEYS = {"joints", "parents", "frames", "fps", "units", "up_axis", "morph_targets"}


@pytest.mark.parametrize("label", LABELS, ids=[d["file"] for d in LABELS])
def test_labelled_file_reports_every_mapped_joint(label):
    require_corpus()
    summary = asset_summary(infuse.load(CORPUS / label["file"]))
    assert REQUIRED_KEYS <= set(summary)
    joints = set(summary["joints"])
    expected = {name for name in label["mapping"].values() if name}
    assert expected <= joints, f"missing: {sorted(expected - joints)}"
    parents = summary["parents"]
    assert len(parents) == len(summary["joints"])
    assert all(-1 <= p < i for i, p in enumerate(parents))
    if label["meta"].get("frames"):
        assert summary["frames"] >= 1 and summary["fps"] > 0


def test_every_labelled_file_is_covered():
    require_corpus()
    assert len(LABELS) >= 222
    assert sum(1 for d in LABELS if d["meta"].get("plain_python")) >= 219


@pytest.mark.parametrize("relative", [
    "runxaway-models/Xbot.glb",
    "smartbody/behaviorsets/MaleLocomotion/motions/ChrUtah_Walk001.skm",
    "ue4-mannequin/SK_Mannequin.FBX",
    "smartbody/mesh/utah/Utah.dae",
])
def test_info_json_through_the_installed_command(relative):
    require_corpus()
    exe = [sys.executable, "-c", "from infuse.cli import run; run()"]
    done = subprocess.run(exe + ["info", "--json", str(CORPUS / relative)], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    doc = json.loads(done.stdout)
    assert REQUIRED_KEYS <= set(doc) and len(doc["joints"]) == len(doc["parents"]) > 10
