"""Infusion refuses, with the joints named and exit 3, a pack whose IK limbs a character lacks or does not
hold (feet hanging outside their legs: ``test_free_feet.py``)."""
from __future__ import annotations

import subprocess

import pytest

from infuse.errors import MissingJointsError
from infuse.packs import infuse_character

from cli_errors import INFUSE
from corpus_data import corpus_file

ROBOT = "adibkn1-robot/RobotExpressive.glb"   # palm bones start at the wrist


def test_a_pack_driving_unmapped_joints_is_refused_naming_them():
    with pytest.raises(MissingJointsError) as err:
        infuse_character(corpus_file(ROBOT), ["reaching"])
    assert "l_wrist" in str(err.value) and "r_wrist" in str(err.value) and "RobotExpressive.glb" in str(err.value)


def test_the_cli_answers_exit_3_in_one_line():
    run = subprocess.run([str(INFUSE), "infuse", str(corpus_file(ROBOT)), "--packs", "reaching"],
                         capture_output=True, text=True, timeout=120)
    assert run.returncode == 3
    assert run.stderr.strip().count("\n") == 0 and "pack 'reaching' drives l_wrist" in run.stderr


def test_characters_with_whole_limbs_infuse():
    infusion = infuse_character(corpus_file("runxaway-models/Xbot.glb"), ["reaching", "locomotion-male"])
    assert set(infusion.spaces) == {"reaching", "locomotion-male"}
