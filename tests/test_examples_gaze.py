"""The example replacement of the gaze controller (examples/replacements/example_gaze): installed, BML
``<gaze>`` plays its ``head-gaze`` instead of the built-in gaze, and the head ends up facing the target.

Installing a replacement changes what BML gaze does in the whole environment, so the package is installed
into a temporary folder and the scenes run in child processes with it on their path (and their own
cache and configuration folders).
"""
from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from corpus_data import REPO, corpus_file

EXAMPLE = REPO / "examples" / "replacements" / "example_gaze"
XBOT = "runxaway-models/Xbot.glb"
LAMP = (1.2, 1.9, 1.0)  # to Bob's left, forward and a little above his eyes (he faces +Z)

SCENE = """
import json, sys
import numpy as np
import infuse
from infuse import quaternions as quat
from infuse.scene import Scene

scene = Scene(fps=30, quiet=True, idle=False)
scene.add_character(sys.argv[1], "bob")
scene.add_object("lamp", {lamp})
block = scene.bml("bob", '<bml xmlns="http://www.bml-initiative.org/bml/bml-1.0" id="b1">'
                         '<gazeShift id="g1" target="Lamp" influence="HEAD"/></bml>')
scene.run(2.0)
activity = scene.activities[(block, "g1")]
rig = scene.runtime.rig("bob")
head = rig.joint("skullbase")
rotations, positions = infuse.motion_fk(scene.motion("bob"))
forward = quat.rotate(quat.multiply(rotations[-1, head], rig.aligned[head]), np.array([0.0, 0.0, 1.0]))
toward = np.array({lamp}) - positions[-1, head]
cosine = forward @ toward / np.linalg.norm(toward)
warnings = [e.description for e in scene.feedback.log if e.kind == "warningFeedback"]
print(json.dumps({{"kind": activity.controller.kind, "module": type(activity.controller).__module__,
                  "head_off_target_deg": float(np.degrees(np.arccos(np.clip(cosine, -1.0, 1.0)))),
                  "warnings": warnings}}))
""".format(lamp=LAMP)


@pytest.fixture(scope="module")
def site(tmp_path_factory) -> Path:
    """The example package installed (not editable) into a temporary folder."""
    tmp = tmp_path_factory.mktemp("example-gaze")
    source = tmp / "source"
    shutil.copytree(EXAMPLE, source, ignore=shutil.ignore_patterns("build", "*.egg-info", "__pycache__"))
    proc = subprocess.run([sys.executable, "-m", "pip", "install", "--quiet", "--no-deps", "--no-index",
                           "--no-build-isolation", "--target", str(tmp / "site"), str(source)],
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    return tmp / "site"


def _child(site: Path | None, home: Path, code: str, *args: str, **env_vars: str) -> subprocess.CompletedProcess:
    """Run ``code`` in a child Python with ``site`` on its path and its own cache and configuration."""
    env = dict(os.environ, XDG_CACHE_HOME=str(home / "cache"), INFUSE_CONFIG=str(home / "absent.toml"), **env_vars)
    if "INFUSE_DEFAULT_CONTROLLER_GAZE" not in env_vars:
        env.pop("INFUSE_DEFAULT_CONTROLLER_GAZE", None)
    env.pop("PYTHONPATH", None)
    if site is not None:
        env["PYTHONPATH"] = str(site)
    proc = subprocess.run([sys.executable, "-c", code, *args], capture_output=True, text=True, env=env, timeout=300)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    return proc


def _scene(site: Path | None, home: Path, **env_vars: str) -> dict:
    proc = _child(site, home, SCENE, str(corpus_file(XBOT)), **env_vars)
    return json.loads(proc.stdout.strip().splitlines()[-1])


def test_bml_gaze_plays_the_installed_replacement(site, tmp_path):
    result = _scene(site, tmp_path)
    assert result["kind"] == "head-gaze" and result["module"] == "infuse_example_gaze.controller"
    assert result["head_off_target_deg"] < 2.0  # the head itself faces the lamp (within its limits)
    assert not result["warnings"]


def test_without_it_or_when_chosen_away_the_built_in_gaze_plays(site, tmp_path):
    alone = _scene(None, tmp_path)
    chosen = _scene(site, tmp_path, INFUSE_DEFAULT_CONTROLLER_GAZE="gaze")
    for result in (alone, chosen):
        assert result["kind"] == "gaze" and result["module"].startswith("infuse_gaze")
    assert abs(chosen["head_off_target_deg"] - alone["head_off_target_deg"]) < 1e-9  # the very same frames


def test_infuse_plugins_lists_it_and_what_it_replaces(site, tmp_path):
    out = _child(site, tmp_path, "from infuse.cli import main; raise SystemExit(main(['plugins']))").stdout
    rows = [line.split() for line in out.splitlines()]
    assert ["head-gaze", "controller", "infuse-anim-example-gaze", "0.1.0", "ok"] in rows
    assert "BML behaviours realized by another controller: gaze by head-gaze" in out
    alone = _child(None, tmp_path, "from infuse.cli import main; raise SystemExit(main(['plugins']))").stdout
    assert "realized by another controller" not in alone
