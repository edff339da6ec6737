"""Malformed BVH input: every case is a typed error, exit code 2, one line on stderr naming the file.

A generator derives the broken files from a small valid BVH (and one Bandai file when the corpus
is there): truncation at random points, garbage bytes and tokens, NaN and infinities, wrong
channel counts, unbalanced braces, bad headers, duplicate names, empty files and binary junk.
"""
from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

import infuse

from cli_errors import assert_cli_exits_2, assert_info_exits_2, load_error, write_case
from corpus_data import CORPUS, corpus_available

BANDAI_FILE = "bandai/Bandai-Namco-Research-Motiondataset-1/data/dataset-1_dash_normal_001.bvh"

VALID = """HIERARCHY
ROOT Hips
{
\tOFFSET 0.0 90.0 0.0
\tCHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
\tJOINT Spine
\t{
\t\tOFFSET 0.0 10.0 0.0
\t\tCHANNELS 3 Zrotation Xrotation Yrotation
\t\tJOINT Head
\t\t{
\t\t\tOFFSET 0.0 50.0 0.0
\t\t\tCHANNELS 3 Zrotation Xrotation Yrotation
\t\t\tEnd Site
\t\t\t{
\t\t\t\tOFFSET 0.0 20.0 0.0
\t\t\t}
\t\t}
\t}
\tJOINT LeftUpLeg
\t{
\t\tOFFSET 10.0 0.0 0.0
\t\tCHANNELS 3 Zrotation Xrotation Yrotation
\t\tEnd Site
\t\t{
\t\t\tOFFSET 0.0 -85.0 0.0
\t\t}
\t}
}
MOTION
Frames: 4
Frame Time: 0.0333333
0.0 90.0 0.0 1.5 -2.0 3.0 4.0 5.0 6.0 7.0 8.0 9.0 10.0 11.0 12.0
1.0 91.0 0.5 1.5 -2.0 3.0 4.0 5.0 6.0 7.0 8.0 9.0 10.0 11.0 12.0
2.0 92.0 1.0 1.5 -2.0 3.0 4.0 5.0 6.0 7.0 8.0 9.0 10.0 11.0 12.0
3.0 93.0 1.5 1.5 -2.0 3.0 4.0 5.0 6.0 7.0 8.0 9.0 10.0 11.0 12.0
"""


def _replace_line(text: str, pattern: str, new: str) -> str:
    out, n = re.subn(pattern, new, text, count=1, flags=re.MULTILINE)
    assert n == 1, pattern
    return out


def _replace_value(text: str, frame: int, column: int, new: str) -> str:
    head, data = text.split("Frame Time: 0.0333333\n")
    rows = [r.split() for r in data.splitlines()]
    rows[frame][column] = new
    return head + "Frame Time: 0.0333333\n" + "\n".join(" ".join(r) for r in rows) + "\n"


def _last_token_start(data: bytes) -> int:
    stripped = data.rstrip()
    return max(stripped.rfind(b" "), stripped.rfind(b"\t"), stripped.rfind(b"\n")) + 1


def malformed_cases(seed: int = 2) -> list[tuple[str, bytes]]:
    """(case name, file bytes) pairs; none of them is a valid BVH."""
    rng = np.random.default_rng(seed)
    valid = VALID.encode()
    cases: list[tuple[str, bytes]] = [
        ("empty", b""),
        ("whitespace", b"  \n\t\r\n  \n"),
        ("binary-junk", bytes(rng.integers(0, 256, 512, dtype=np.uint8))),
        ("png-header", b"\x89PNG\r\n\x1a\n" + bytes(rng.integers(0, 256, 64, dtype=np.uint8))),
        ("utf16", VALID.encode("utf-16")),
        ("garbage-text", b"this is not a motion file\n{ }\n"),
        ("no-root", b"HIERARCHY\nMOTION\nFrames: 0\nFrame Time: 0.1\n"),
        ("missing-motion", VALID.split("MOTION")[0].encode()),
        ("missing-frame-time", VALID.replace("Frame Time: 0.0333333\n", "").encode()),
        ("frames-not-a-number", VALID.replace("Frames: 4", "Frames: four").encode()),
        ("frames-negative", VALID.replace("Frames: 4", "Frames: -4").encode()),
        ("frame-time-zero", VALID.replace("Frame Time: 0.0333333", "Frame Time: 0").encode()),
        ("frame-time-negative", VALID.replace("Frame Time: 0.0333333", "Frame Time: -0.03").encode()),
        ("frame-time-nan", VALID.replace("Frame Time: 0.0333333", "Frame Time: nan").encode()),
        ("nan-value", _replace_value(VALID, 2, 7, "nan").encode()),
        ("NaN-value", _replace_value(VALID, 0, 0, "NaN").encode()),
        ("inf-value", _replace_value(VALID, 3, 14, "inf").encode()),
        ("overflow-value", _replace_value(VALID, 1, 4, "1e999").encode()),
        ("garbage-value", _replace_value(VALID, 1, 5, "abc").encode()),
        ("double-dot-value", _replace_value(VALID, 3, 2, "1.2.3").encode()),
        ("garbage-bytes-in-data", _replace_value(VALID, 2, 3, "\xff\xfe").encode("latin-1")),
        ("missing-value", VALID.replace("3.0 93.0 1.5 1.5", "3.0 93.0 1.5").encode()),
        ("extra-value", VALID.replace("1.0 91.0 0.5", "1.0 91.0 0.5 0.5").encode()),
        ("swapped-counts", VALID.replace("1.0 91.0 0.5", "1.0 91.0").replace("2.0 92.0 1.0", "2.0 92.0 1.0 7.0").encode()),
        ("extra-frame", (VALID + VALID.splitlines()[-1] + "\n").encode()),
        ("channels-count-short", VALID.replace("CHANNELS 3 Zrotation Xrotation Yrotation\n\t\tJOINT Head",
                                               "CHANNELS 4 Zrotation Xrotation Yrotation\n\t\tJOINT Head").encode()),
        ("channels-count-long", VALID.replace("CHANNELS 6 Xposition", "CHANNELS 5 Xposition").encode()),
        ("channels-count-word", VALID.replace("CHANNELS 6", "CHANNELS six").encode()),
        ("unknown-channel", VALID.replace("CHANNELS 3 Zrotation Xrotation Yrotation\n\t\tJOINT Head",
                                          "CHANNELS 3 Zrotation Wrotation Yrotation\n\t\tJOINT Head").encode()),
        ("repeated-channel", VALID.replace("CHANNELS 3 Zrotation Xrotation Yrotation\n\t\tJOINT Head",
                                           "CHANNELS 3 Zrotation Zrotation Yrotation\n\t\tJOINT Head").encode()),
        ("offset-short", VALID.replace("OFFSET 0.0 10.0 0.0", "OFFSET 0.0 10.0").encode()),
        ("offset-garbage", VALID.replace("OFFSET 0.0 10.0 0.0", "OFFSET 0.0 ten 0.0").encode()),
        ("offset-nan", VALID.replace("OFFSET 0.0 10.0 0.0", "OFFSET 0.0 nan 0.0").encode()),
        ("missing-close-brace", _replace_line(VALID, r"^\t}\n\tJOINT LeftUpLeg", "\tJOINT LeftUpLeg").encode()),
        ("extra-close-brace", _replace_line(VALID, r"^}\nMOTION", "}\n}\nMOTION").encode()),
        ("missing-open-brace", _replace_line(VALID, r"^\t\{\n\t\tOFFSET 10.0", "\t\tOFFSET 10.0").encode()),
        ("duplicate-name", VALID.replace("JOINT LeftUpLeg", "JOINT Spine").encode()),
        ("joint-outside-root", VALID.replace("HIERARCHY\n", "HIERARCHY\nJOINT Stray\n{\nOFFSET 0 0 0\n}\n").encode()),
        ("end-site-channels", VALID.replace("\t\t\t\tOFFSET 0.0 20.0 0.0\n", "\t\t\t\tOFFSET 0.0 20.0 0.0\n\t\t\t\tCHANNELS 1 Xrotation\n").encode()),
        ("unknown-keyword", VALID.replace("\tJOINT Spine\n", "\tBONE Spine\n").encode()),
        ("joint-without-name", VALID.replace("JOINT Head", "JOINT").encode()),
    ]
    sources = [("synthetic", valid)]
    if corpus_available():
        sources.append(("bandai", (CORPUS / BANDAI_FILE).read_bytes()))
    for label, data in sources:
        stop = _last_token_start(data)  # cutting inside the last number could leave a valid file
        for k, cut in enumerate(sorted(rng.integers(1, stop, 10))):
            cases.append((f"{label}-truncated-{k}@{cut}", data[:cut]))
        motion_at = data.index(b"MOTION")
        for k, cut in enumerate(sorted(rng.integers(motion_at + 30, stop, 4))):
            cases.append((f"{label}-truncated-data-{k}@{cut}", data[:cut]))
        for k in range(6):
            at = int(rng.integers(0, len(data)))
            if k % 2:  # text-like junk: high bytes and punctuation, no NUL
                junk = bytes(rng.integers(128, 256, 4, dtype=np.uint8)) + b"#%$x"
            else:
                junk = bytes(rng.integers(0, 32, 6, dtype=np.uint8)) + b"\x00\x7f"
            cases.append((f"{label}-junk-bytes-{k}@{at}", data[:at] + junk + data[at:]))
    return cases


CASES = malformed_cases()


def _write(tmp_path: Path, name: str, data: bytes) -> Path:
    return write_case(tmp_path, name.replace("@", "_at_"), data, ".bvh")


@pytest.mark.parametrize("name,data", CASES, ids=[c[0] for c in CASES])
def test_malformed_file_is_an_input_error(tmp_path, capsys, name, data):
    path = _write(tmp_path, name, data)
    load_error(path)
    assert_info_exits_2(path, capsys)


# One case of each kind through the installed command, as a user runs it.
CLI_KINDS = {"empty", "binary-junk", "nan-value", "missing-value", "missing-close-brace", "frame-time-zero",
             "duplicate-name", "synthetic-truncated-3", "bandai-truncated-data-1", "bandai-junk-bytes-0",
             "bandai-junk-bytes-1"}
CLI_CASES = [c for c in CASES if c[0].split("@")[0] in CLI_KINDS]


@pytest.mark.parametrize("name,data", CLI_CASES, ids=[c[0] for c in CLI_CASES])
def test_cli_answers_malformed_file_with_exit_2(tmp_path, name, data):
    assert_cli_exits_2([_write(tmp_path, name, data)], "--json")


def test_errors_name_the_place(tmp_path):
    def problem(text: str):
        return load_error(write_case(tmp_path, "case", text, ".bvh"))

    nan = problem(_replace_value(VALID, 2, 7, "nan"))
    assert nan.place == "line 35 (frame 2)" and "Spine" in nan.problem
    assert problem(VALID.replace("3.0 93.0 1.5 1.5", "3.0 93.0 1.5")).place == "line 36 (frame 3)"
    assert problem(VALID.replace("JOINT LeftUpLeg", "JOINT Spine")).place == "line 20"
    assert "never closed" in problem(VALID.split("\t}\n\tJOINT LeftUpLeg")[0]).problem
    assert problem(VALID.replace("Frame Time: 0.0333333", "Frame Time: 0")).place == "line 32"
    assert problem("").problem == "empty file"


def test_the_template_itself_is_valid(tmp_path):
    path = tmp_path / "valid.bvh"
    path.write_text(VALID)
    asset = infuse.load(path)
    assert asset.skeleton.names == ("Hips", "Spine", "Head", "LeftUpLeg")
    assert next(iter(asset.motions.values())).num_frames == 4
    assert len(CLI_CASES) == len(CLI_KINDS) - (0 if corpus_available() else 3)
