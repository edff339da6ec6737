"""Committed files speak only of the project: no absolute path of this checkout or of the corpus."""
import subprocess

import pytest

from corpus_data import CORPUS, REPO


def tracked_files():
    try:
        out = subprocess.run(["git", "ls-files", "-z"], cwd=REPO, capture_output=True, check=True).stdout
    except (OSError, subprocess.CalledProcessError):
        pytest.skip("not a git checkout")
    return [REPO / name for name in out.decode().split("\0") if name]


def test_no_machine_paths_in_tracked_files():
    needles = {str(REPO).encode(), str(CORPUS).encode(), str(CORPUS.parent).encode()}
    offenders = []
    for path in tracked_files():
        if not path.is_file():
            continue
        data = path.read_bytes()
        if b"\0" in data[:4096]:
            continue  # binary
        if any(n in data for n in needles):
            offenders.append(str(path.relative_to(REPO)))
    assert not offenders, f"absolute machine paths in: {offenders}"
