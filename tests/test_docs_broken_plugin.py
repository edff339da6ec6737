"""What the plugin guide says about broken plugins: a plugin that fails to import or whose hook raises is
reported once and skipped, the rest keeps working; a descriptor function that crashes is a bug (exit 1).

The broken distribution is made in a temporary folder (a ``.dist-info`` with entry points beside its
modules) and put on ``PYTHONPATH`` of a child ``infuse`` process, so the shared environment is untouched.
"""
from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from corpus_data import corpus_file

DIST = "infuse-broken-example"


@pytest.fixture(scope="module")
def broken_site(tmp_path_factory) -> Path:
    site = tmp_path_factory.mktemp("site")
    info = site / "infuse_broken_example-0.1.0.dist-info"
    info.mkdir()
    (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {DIST}\nVersion: 0.1.0\n")
    (info / "entry_points.txt").write_text(textwrap.dedent("""\
        [infuse.mappers]
        broken = infuse_broken_example

        [infuse.controllers]
        raising = infuse_raising_example

        [infuse.readers]
        crashing = infuse_crashing_reader
        """))
    (site / "infuse_broken_example.py").write_text('raise RuntimeError("broken on purpose at import")\n')
    (site / "infuse_raising_example.py").write_text(textwrap.dedent("""\
        import infuse

        @infuse.hookimpl
        def infuse_controllers():
            raise ValueError("broken on purpose in the hook")
        """))
    (site / "infuse_crashing_reader.py").write_text(textwrap.dedent("""\
        import infuse
        from infuse.plugin_types import Reader

        def read(path, **options):
            raise RuntimeError("broken on purpose while reading")

        @infuse.hookimpl
        def infuse_readers():
            return [Reader("crashing", (".crash",), read)]
        """))
    return site


def _infuse(site: Path, *args: str) -> subprocess.CompletedProcess:
    env = dict(os.environ, PYTHONPATH=str(site))
    env.pop("INFUSE_DEBUG", None)
    return subprocess.run([sys.executable, "-c", "from infuse.cli import run; run()", *args],
                          capture_output=True, text=True, env=env, timeout=120)


def test_import_failure_is_reported_once_and_listed_as_broken(broken_site):
    proc = _infuse(broken_site, "plugins")
    assert proc.returncode == 0, proc.stderr
    warning = (f"infuse: warning: plugin 'broken' ({DIST}, group infuse.mappers) failed to load and is skipped: "
               "RuntimeError: broken on purpose at import")
    assert proc.stderr.count(warning) == 1, proc.stderr
    rows = [line.split(None, 4) for line in proc.stdout.splitlines()]
    assert ["broken", "mapper", DIST, "0.1.0", "BROKEN: RuntimeError: broken on purpose at import"] in rows
    assert any(r[:2] == ["heuristic", "mapper"] and r[4] == "ok" for r in rows)  # the others still load


def test_a_raising_hook_is_skipped_and_the_rest_works(broken_site):
    path = corpus_file("runxaway-models/Xbot.glb")
    proc = _infuse(broken_site, "map", str(path))
    assert proc.returncode == 0, proc.stderr
    assert "canonical joints mapped by heuristic" in proc.stdout
    assert "failed to load and is skipped" in proc.stderr
    code = "from infuse.runtime import controller_components; print(sorted(controller_components()))"
    env = dict(os.environ, PYTHONPATH=str(broken_site))
    listed = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, timeout=120)
    assert listed.returncode == 0, listed.stderr
    assert "gaze" in listed.stdout and "shrug" in listed.stdout
    assert (f"plugin '{DIST}:infuse_raising_example' failed in infuse_controllers and is skipped: "
            "ValueError: broken on purpose in the hook") in listed.stderr


def test_a_crashing_reader_is_a_bug_with_one_line_and_exit_code_1(broken_site, tmp_path):
    target = tmp_path / "thing.crash"
    target.write_text("anything")
    proc = _infuse(broken_site, "info", str(target))
    assert proc.returncode == 1
    last = proc.stderr.strip().splitlines()[-1]
    assert last.startswith("infuse: internal error (a bug; set INFUSE_DEBUG=1 for details): RuntimeError")
    assert "Traceback" not in proc.stderr
