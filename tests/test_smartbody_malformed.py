"""Malformed .sk and .skm files: the CLI answers exit code 2 with one line naming the file, never a traceback.

Cases are generated (seeded) from real corpus files: truncation at random points, garbage, NaN,
wrong channel counts, missing braces, unknown joints and channel types, empty files.
"""
from __future__ import annotations

import random
from pathlib import Path

import pytest

from cli_errors import assert_cli_exits_2, assert_info_exits_2, write_case
from corpus_data import corpus_file

SK = "smartbody/ChrBrad/ChrBrad.sk"
SKM_SKELETON = "smartbody/behaviorsets/MaleLocomotion/skeletons/test_utah.sk"
SKM = "smartbody/behaviorsets/MaleLocomotion/motions/ChrUtah_Walk001.skm"


def _nth_replace(text: str, old: str, new: str, n: int) -> str:
    start = -1
    for _ in range(n + 1):
        start = text.index(old, start + 1)
    return text[:start] + new + text[start + len(old):]


def sk_cases(text: str, rng: random.Random) -> dict[str, str | bytes]:
    last_brace = text.rindex("}")
    cases: dict[str, str | bytes] = {f"truncated_{i}": text[: rng.randrange(1, last_brace)] for i in range(8)}
    cases.update({
        "empty": "",
        "blank": "  \n\n  \n",
        "garbage_bytes": bytes(rng.randrange(256) for _ in range(3000)),
        "garbage_text": "hello world, this is not a skeleton\n",
        "garbage_in_joint": _nth_replace(text, "prerot", "%%garbage%% prerot", 5),
        "nan_offset": _nth_replace(text, "offset 0.000000", "offset nan", 0),
        "inf_prerot_angle": _nth_replace(text, "ang 121.434761", "ang inf", 0),
        "missing_close_brace": _nth_replace(text, "}", "", rng.randrange(text.count("}"))),
        "missing_open_brace": _nth_replace(text, "{", "", rng.randrange(1, text.count("{"))),
        "unknown_channel_type": _nth_replace(text, "channel Quat", "channel Quaternion", 3),
        "channel_without_limits": _nth_replace(text, "channel XPos 0 free", "channel XPos 0", 0),
        "axis_without_angle": _nth_replace(text, " ang 121.434761", "", 0),
        "duplicate_joint": _nth_replace(text, "joint JtKneeLf", "joint JtHipLf", 0),
        "no_skeleton_keyword": text.replace("skeleton\n", "skelet0n\n", 1),
    })
    return cases


def skm_cases(text: str, rng: random.Random) -> dict[str, str | bytes]:
    frame_lines = [i for i, line in enumerate(text.split("\n")) if line.startswith("kt ")]
    block_end = text.index("\n", text.index(text.split("\n")[frame_lines[-1]]))
    lines = text.split("\n")

    def with_line(k: int, new: str) -> str:
        changed = list(lines)
        changed[frame_lines[k]] = new
        return "\n".join(changed)

    frame = lines[frame_lines[10]].split()
    cases: dict[str, str | bytes] = {f"truncated_{i}": text[: rng.randrange(1, block_end - 2)] for i in range(8)}
    cases.update({
        "empty": "",
        "garbage_bytes": bytes(rng.randrange(256) for _ in range(5000)),
        "garbage_text": "SkMotion? no.\n",
        "garbage_line_in_frames": with_line(20, "this line is not a frame"),
        "garbage_value": with_line(12, " ".join(frame[:40] + ["1.2.3"] + frame[41:])),
        "nan_value": with_line(30, " ".join(frame[:50] + ["nan"] + frame[51:])),
        "inf_key_time": with_line(5, " ".join(["kt", "inf"] + frame[2:])),
        "key_times_decrease": with_line(8, " ".join(["kt", "0.01"] + frame[2:])),
        "channel_count_high": text.replace("channels 280", "channels 281", 1),
        "channel_count_low": text.replace("channels 280", "channels 279", 1),
        "frame_value_missing": with_line(3, " ".join(frame[:-1])),
        "frame_value_extra": with_line(3, " ".join(frame + ["0.5"])),
        "frames_count_high": text.replace("frames 65", "frames 70", 1),
        "frames_count_low": text.replace("frames 65", "frames 60", 1),
        "frames_count_garbage": text.replace("frames 65", "frames sixty", 1),
        "unknown_joint": text.replace("\nl_knee Quat\n", "\nl_kneecap Quat\n", 1),
        "unknown_channel_type": text.replace("\nbase XPos\n", "\nbase WPos\n", 1),
        "duplicate_channel": text.replace("\nl_knee Quat\n", "\nl_hip Quat\n", 1),
        "no_signature": text.replace("SkMotion", "Motion", 1),
        "bad_timing": text.replace("ready time: 0.3", "ready time: soon", 1),
    })
    return cases


@pytest.fixture(scope="module")
def malformed(tmp_path_factory) -> dict[str, Path]:
    """Malformed files in a scratch folder laid out like a SmartBody behaviour set."""
    root = tmp_path_factory.mktemp("smartbody_malformed")
    (root / "skeletons").mkdir()
    (root / "motions").mkdir()
    (root / "skeletons" / "utah.sk").symlink_to(corpus_file(SKM_SKELETON))
    rng = random.Random(20240611)
    files = {f"sk_{k}": write_case(root, k, v, ".sk") for k, v in sk_cases(corpus_file(SK).read_text(), rng).items()}
    files.update({f"skm_{k}": write_case(root / "motions", k, v, ".skm")
                  for k, v in skm_cases(corpus_file(SKM).read_text(), rng).items()})
    return files


SK_CASES = ["truncated_%d" % i for i in range(8)] + [
    "empty", "blank", "garbage_bytes", "garbage_text", "garbage_in_joint", "nan_offset", "inf_prerot_angle",
    "missing_close_brace", "missing_open_brace", "unknown_channel_type", "channel_without_limits",
    "axis_without_angle", "duplicate_joint", "no_skeleton_keyword"]
SKM_CASES = ["truncated_%d" % i for i in range(8)] + [
    "empty", "garbage_bytes", "garbage_text", "garbage_line_in_frames", "garbage_value", "nan_value",
    "inf_key_time", "key_times_decrease", "channel_count_high", "channel_count_low", "frame_value_missing",
    "frame_value_extra", "frames_count_high", "frames_count_low", "frames_count_garbage", "unknown_joint",
    "unknown_channel_type", "duplicate_channel", "no_signature", "bad_timing"]


@pytest.mark.parametrize("case", [f"sk_{c}" for c in SK_CASES] + [f"skm_{c}" for c in SKM_CASES])
def test_cli_rejects_malformed_file(case, malformed, capsys):
    assert_info_exits_2(malformed[case], capsys)


def test_generator_covers_every_listed_case(malformed):
    assert set(malformed) == {f"sk_{c}" for c in SK_CASES} | {f"skm_{c}" for c in SKM_CASES}


@pytest.mark.parametrize("case", ["sk_truncated_3", "skm_unknown_joint"])
def test_real_cli_process(case, malformed):
    assert_cli_exits_2([malformed[case]], "--json")
