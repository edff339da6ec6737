"""Checks that bad input gets exit code 2 and one line naming the file, in-process and through ``infuse``."""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path

from infuse.cli import main

INFUSE = Path(sys.executable).with_name("infuse")


def _answer_lines(stderr: str) -> list[str]:
    # Warnings about other installed plugins may precede the answer; the answer itself is one line.
    return [ln for ln in stderr.splitlines() if ln.strip() and not ln.startswith("infuse: warning:")]


def assert_info_exits_2(path: Path, capsys) -> str:
    """Run ``infuse info path`` in this process; returns the error line."""
    code = main(["info", str(path)])
    err = capsys.readouterr().err
    lines = _answer_lines(err)
    assert code == 2, err
    assert len(lines) == 1 and str(path) in lines[0] and "Traceback" not in err, err
    return lines[0]


def assert_cli_exits_2(paths: list[Path]) -> None:
    """Run the installed ``infuse info`` on each path (a real process: no traceback may escape)."""
    for path in paths:
        result = subprocess.run([str(INFUSE), "info", str(path)], capture_output=True, text=True, timeout=120)
        lines = _answer_lines(result.stderr)
        assert result.returncode == 2, result.stderr
        assert len(lines) == 1 and str(path) in lines[0] and "Traceback" not in result.stderr, result.stderr
