"""Malformed .asf and .amc files: the CLI answers exit code 2 with one line naming the file, never a traceback.

Cases are generated (seeded) from the corpus CMU files: truncation at random points, garbage, NaN,
wrong value counts, missing begin/end, unknown bones, hierarchy cycles, empty files.
"""
from __future__ import annotations

import random
from pathlib import Path

import pytest

from cli_errors import assert_cli_exits_2, assert_info_exits_2, write_case
from corpus_data import corpus_file

ASF = "fairmotion/tests/data/11.asf"
AMC = "fairmotion/tests/data/11_01.amc"


def asf_cases(text: str, rng: random.Random) -> dict[str, str | bytes]:
    end = text.rindex("end")  # the hierarchy's closing 'end'
    cases: dict[str, str | bytes] = {f"truncated_{i}": text[: rng.randrange(1, end)] for i in range(8)}
    cases.update({
        "empty": "",
        "comments_only": "# nothing here\n# at all\n",
        "garbage_bytes": bytes(rng.randrange(256) for _ in range(3000)),
        "garbage_text": "this is not a skeleton\n",
        "nan_direction": text.replace("direction 0.34202 -0.939693 0", "direction nan -0.939693 0", 1),
        "short_direction": text.replace("direction 0.34202 -0.939693 0", "direction 0.34202 -0.939693", 1),
        "missing_bone_end": text.replace("    limits (-10.0 170.0)\n  end", "    limits (-10.0 170.0)", 1)
                            .replace("    limits (-10.0 170.0)\r\n  end", "    limits (-10.0 170.0)", 1),
        "missing_bone_begin": text.replace("  begin", "  begun", 3),
        "unknown_bone_in_hierarchy": text.replace("lfemur ltibia", "lfemur lshin", 1),
        "two_parents": text.replace("lfemur ltibia", "lfemur ltibia lfoot", 1),
        "cycle": text.replace("root lhipjoint rhipjoint", "root rhipjoint", 1).replace("lfoot ltoes", "lfoot ltoes\n    ltoes lhipjoint", 1),
        "bad_dof": text.replace("dof rx ry rz", "dof rx rq rz", 1),
        "limits_count": text.replace("dof rx\n", "dof rx rz\n", 1).replace("dof rx\r\n", "dof rx rz\r\n", 1),
        "bad_angle_unit": text.replace("angle deg", "angle grad", 1),
        "bad_axis_order": text.replace("axis 0 0 20  XYZ", "axis 0 0 20  XXY", 1),
        "duplicate_bone": text.replace("name ltibia", "name lfemur", 1),
        "no_hierarchy": text.split(":hierarchy")[0],
        "unknown_section": text.replace(":documentation", ":commentary", 1),
    })
    return cases


def amc_cases(text: str, rng: random.Random) -> dict[str, str | bytes]:
    lines = text.split("\n")
    frame_rows = [i for i, line in enumerate(lines) if line.strip().isdigit()]

    def cut_inside_frame() -> str:
        k = rng.randrange(len(frame_rows) - 1)
        start = len("\n".join(lines[: frame_rows[k] + 1])) + 1
        stop = len("\n".join(lines[: frame_rows[k + 1]])) - 2
        return text[: rng.randrange(start, stop)]

    def replace_line(i: int, new: str) -> str:
        changed = list(lines)
        changed[i] = new
        return "\n".join(changed)

    femur = next(i for i in range(frame_rows[40], frame_rows[41]) if lines[i].startswith("lfemur"))
    cases: dict[str, str | bytes] = {f"truncated_{i}": cut_inside_frame() for i in range(8)}
    cases.update({
        "empty": "",
        "header_only": ":FULLY-SPECIFIED\n:DEGREES\n",
        "garbage_bytes": bytes(rng.randrange(256) for _ in range(4000)),
        "garbage_text": "1\nthis is not a motion\n",
        "nan_value": replace_line(femur, "lfemur nan 0.0 1.0"),
        "not_a_number": replace_line(femur, "lfemur 1.0 2.x 3.0"),
        "value_missing": replace_line(femur, "lfemur 1.0 2.0"),
        "value_extra": replace_line(femur, "lfemur 1.0 2.0 3.0 4.0"),
        "unknown_bone": replace_line(femur, "ltail 1.0 2.0 3.0"),
        "bone_twice": replace_line(femur + 1, lines[femur]),
        "frame_number_jump": replace_line(frame_rows[100], "205"),
        "unknown_header": ":SIDEWAYS\n" + text,
        "bone_before_first_frame": text.replace(":DEGREES", ":DEGREES\nroot 0 0 0 0 0 0", 1),
    })
    return cases


ASF_CASES = [f"truncated_{i}" for i in range(8)] + [
    "empty", "comments_only", "garbage_bytes", "garbage_text", "nan_direction", "short_direction",
    "missing_bone_end", "missing_bone_begin", "unknown_bone_in_hierarchy", "two_parents", "cycle", "bad_dof",
    "limits_count", "bad_angle_unit", "bad_axis_order", "duplicate_bone", "no_hierarchy", "unknown_section"]
AMC_CASES = [f"truncated_{i}" for i in range(8)] + [
    "empty", "header_only", "garbage_bytes", "garbage_text", "nan_value", "not_a_number", "value_missing",
    "value_extra", "unknown_bone", "bone_twice", "frame_number_jump", "unknown_header", "bone_before_first_frame"]


@pytest.fixture(scope="module")
def malformed(tmp_path_factory) -> dict[str, Path]:
    """ASF cases each in their own file; AMC cases beside a link to the real 11.asf."""
    root = tmp_path_factory.mktemp("acclaim_malformed")
    rng = random.Random(8675309)
    asf_text = corpus_file(ASF).read_bytes().decode()
    amc_text = corpus_file(AMC).read_bytes().decode()
    files = {f"asf_{k}": write_case(root, k, v, ".asf") for k, v in asf_cases(asf_text, rng).items()}
    motions = root / "motions"
    motions.mkdir()
    (motions / "11.asf").symlink_to(corpus_file(ASF))
    files.update({f"amc_{k}": write_case(motions, f"11_{k}", v, ".amc") for k, v in amc_cases(amc_text, rng).items()})
    return files


def test_generator_covers_every_listed_case(malformed):
    assert set(malformed) == {f"asf_{c}" for c in ASF_CASES} | {f"amc_{c}" for c in AMC_CASES}


def test_cases_differ_from_the_original(malformed):
    originals = {"asf": corpus_file(ASF).read_bytes(), "amc": corpus_file(AMC).read_bytes()}
    for case, path in malformed.items():
        assert path.read_bytes() != originals[case[:3]], f"{case} did not change the file"


@pytest.mark.parametrize("case", [f"asf_{c}" for c in ASF_CASES] + [f"amc_{c}" for c in AMC_CASES])
def test_cli_rejects_malformed_file(case, malformed, capsys):
    assert_info_exits_2(malformed[case], capsys)


@pytest.mark.parametrize("case", ["asf_cycle", "amc_truncated_5"])
def test_real_cli_process(case, malformed):
    assert_cli_exits_2([malformed[case]], "--json")
