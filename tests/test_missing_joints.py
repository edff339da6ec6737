"""Controllers asked to move joints a character lacks raise MissingJointsError naming the character and
what is missing (exit code 3), never a TypeError from a wrongly built error."""
from __future__ import annotations

import pytest

from infuse.errors import MissingJointsError
from infuse.runtime import Runtime, controller

from runtime_characters import synthetic_character

HEAD = ("spine5", "skullbase", "eyeball_left", "eyeball_right", "upper_eyelid_left", "lower_eyelid_left",
        "upper_eyelid_right", "lower_eyelid_right")
SPINE = ("spine1", "spine2", "spine3", "spine4", "spine5")


@pytest.mark.parametrize("kind, settings, drop, problem", [
    ("gaze", {"target": (0.0, 1.6, 2.0)}, SPINE + HEAD, "cannot gaze"),
    ("head", {"lexeme": "NOD"}, SPINE + HEAD, "no neck or head joint"),
    ("breathing", {}, SPINE + HEAD, "no spine joint"),
])
def test_a_controller_without_its_joints_raises_missing_joints(kind, settings, drop, problem):
    rt = Runtime(fps=30)
    rt.add_character(synthetic_character("headless", drop=drop), name="headless")
    with pytest.raises(MissingJointsError, match=problem) as info:
        rt.activate("headless", controller(kind, **settings), 0.0)
        rt.run(0.5)
    assert info.value.exit_code == 3 and info.value.file == "headless"
