"""Malformed input: the checks every reader's tests share, and the helpers that write the cases.

The answer to a malformed file is exit code 2, nothing on stdout, and one line on stderr that starts
with ``infuse: error:`` and names the file; never a traceback. It is checked in this process
(:func:`assert_info_exits_2`) and through the installed ``infuse`` program (:func:`assert_cli_exits_2`).
"""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

import infuse
from infuse.cli import main
from infuse.errors import InputError

from corpus_data import REPO

INFUSE = Path(sys.executable).with_name("infuse")


def answer_lines(stderr: str) -> list[str]:
    """The non-blank stderr lines, less warnings about other installed plugins (a broken one is
    reported, not fatal): what ``infuse`` answered."""
    return [ln for ln in stderr.splitlines() if ln.strip() and not ln.startswith("infuse: warning:")]


def assert_one_error_line(path: Path, code: int, stdout: str, stderr: str) -> str:
    """Exit code 2, no output, one error line naming ``path`` and no traceback; returns the line."""
    lines = answer_lines(stderr)
    assert code == 2, (code, stderr)
    assert len(lines) == 1 and "Traceback" not in stderr and "internal error" not in lines[0], stderr
    assert str(path) in lines[0] and lines[0].startswith("infuse: error:"), stderr
    assert stdout == "", stdout
    return lines[0]


def assert_info_exits_2(path: Path, capsys) -> str:
    """Run ``infuse info path`` in this process; returns the error line."""
    code = main(["info", str(path)])
    out = capsys.readouterr()
    return assert_one_error_line(path, code, out.out, out.err)


def run_info(path: Path, *options: str) -> subprocess.CompletedProcess:
    """The installed ``infuse info [options] path``, as a user runs it (a real process: no
    traceback may escape)."""
    return subprocess.run([str(INFUSE), "info", *options, str(path)], capture_output=True, text=True,
                          cwd=REPO, timeout=120)


def assert_cli_exits_2(paths: list[Path], *options: str) -> None:
    """Run the installed ``infuse info [options]`` on each path."""
    for path in paths:
        run = run_info(path, *options)
        assert_one_error_line(path, run.returncode, run.stdout, run.stderr)


def load_error(path: Path) -> InputError:
    """The :class:`InputError` that loading ``path`` raises; it names the file and a problem."""
    with pytest.raises(InputError) as info:
        infuse.load(path)
    assert info.value.file == str(path) and info.value.problem
    return info.value


def write_case(folder: Path, name: str, content: str | bytes, suffix: str = "") -> Path:
    """``folder/<name><suffix>`` holding ``content``: bytes as they are, text as UTF-8 with its
    line endings kept."""
    path = folder / f"{name}{suffix}"
    if isinstance(content, bytes):
        path.write_bytes(content)
    else:
        path.write_text(content, encoding="utf-8", newline="")
    return path
