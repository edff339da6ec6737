"""Every command of the usage blocks in README.md and docs/quickstart.md runs as written.

The commands run in a folder holding the files they name, linked to corpus files: ``character.glb``
and ``Xbot.glb`` (Mixamo's X Bot), ``walk.bvh`` (a Bandai walk), ``avatar.glb`` (a Ready Player Me
avatar), ``cast/`` and ``mocap/`` (one of each), ``meeting.toml`` / ``scene.toml``, the
quickstart's scene file, and ``my-pack``, the built-in female locomotion pack's folder. Each block runs in order (later commands read what earlier ones wrote).
A command that serves until stopped (``infuse view`` without ``--html`` or ``--screenshot``,
``infuse serve``) is run until it prints its address: the test fetches the page there, then stops
it as Ctrl-C would. The ``make`` lines set up the checkout this test runs in, so they are left out.
"""
from __future__ import annotations

import os
import re
import shlex
import signal
import subprocess
import sys
import urllib.request
from pathlib import Path

import pytest

from corpus_data import REPO, corpus_file, require_corpus

INFUSE = Path(sys.executable).with_name("infuse")
DOCUMENTS = ("README.md", "docs/quickstart.md")
FILES = {
    "character.glb": "runxaway-models/Xbot.glb",
    "Xbot.glb": "runxaway-models/Xbot.glb",
    "walk.bvh": "bandai/Bandai-Namco-Research-Motiondataset-1/data/dataset-1_walk_normal_001.bvh",
    "avatar.glb": "talkinghead/avatars/brunette-t.glb",
    "cast/Xbot.glb": "runxaway-models/Xbot.glb",
    "mocap/walk.bvh": "bandai/Bandai-Namco-Research-Motiondataset-1/data/dataset-1_walk_normal_001.bvh",
}
#: Folders of this repository the commands name.
PACKS = {"my-pack": "behaviour_libs/locomotion-female/infuse_pack_locomotion_female/pack"}
TIMEOUT_S = 900


def fenced(text: str, language: str) -> list[str]:
    """The bodies of the ```language blocks of a Markdown text."""
    return re.findall(rf"^```{language}\n(.*?)^```", text, flags=re.M | re.S)


def commands(document: str) -> list[list[str]]:
    """The ``infuse`` command lines (argv) of a document's ``sh`` blocks, comments dropped."""
    lines = [ln for block in fenced((REPO / document).read_text(encoding="utf-8"), "sh") for ln in block.splitlines()]
    argvs = [shlex.split(ln, comments=True) for ln in lines]
    return [argv for argv in argvs if argv and argv[0] != "make"]


def test_the_documents_have_commands():
    for document in DOCUMENTS:
        argvs = commands(document)
        assert argvs and all(argv[0] == "infuse" for argv in argvs), document


@pytest.fixture(scope="module")
def workspace(tmp_path_factory) -> Path:
    require_corpus()
    folder = tmp_path_factory.mktemp("docs-commands")
    for name, rel in FILES.items():
        (folder / name).parent.mkdir(exist_ok=True)
        (folder / name).symlink_to(corpus_file(rel))
    for name, rel in PACKS.items():
        (folder / name).symlink_to(REPO / rel, target_is_directory=True)
    scene = fenced((REPO / "docs/quickstart.md").read_text(encoding="utf-8"), "toml")
    assert len(scene) == 1
    for name in ("meeting.toml", "scene.toml"):
        (folder / name).write_text(scene[0], encoding="utf-8")
    return folder


def _environment(folder: Path) -> dict:
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    env["HOME"] = str(folder)  # caches (infused packs) stay in the test's folder
    return env


def serves(argv: list[str]) -> bool:
    """Whether the command serves until stopped."""
    return argv[1] == "serve" or (argv[1] == "view" and not {"--html", "--screenshot"} & set(argv))


def _serve(argv: list[str], folder: Path) -> None:
    """Run a command that serves a page until stopped: fetch the page, then stop it as Ctrl-C does."""
    proc = subprocess.Popen(argv, cwd=folder, env=_environment(folder), stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    try:
        line = proc.stdout.readline()
        found = re.search(r"(http://\S+)", line)
        assert found, f"{shlex.join(argv)}: {line!r} {proc.stderr.read() if proc.poll() is not None else ''}"
        with urllib.request.urlopen(found.group(1), timeout=60) as page:
            assert page.status == 200 and page.read(4096)
        proc.send_signal(signal.SIGINT)
        assert proc.wait(timeout=60) == 0, proc.stderr.read()
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()


@pytest.mark.parametrize("document", DOCUMENTS)
def test_every_command_runs_as_written(workspace, document):
    for argv in commands(document):
        run = [str(INFUSE), *argv[1:]]
        if serves(argv):
            _serve(run, workspace)
            continue
        proc = subprocess.run(run, cwd=workspace, env=_environment(workspace), capture_output=True, text=True,
                              timeout=TIMEOUT_S)
        assert proc.returncode == 0, f"{shlex.join(argv)} exited {proc.returncode}: {proc.stderr[-2000:]}"
