"""A foot let go whose ball has not left the ground yet stays where its ball is held when it is held
again; a foot touched down on its heel before its strike keeps its heading. Bandai dataset-1 feminine on Xbot, a walk to a target 2 m behind: the left foot, held by its
ball where it touched down in the turn on the spot, is let go for a frame as the start begins and held
again by its ball the next; landing, it took the offset of the frame before added to this frame's
animated ball, and moved on with the animation's step, 3 cm in one frame on the ground (the start
skated 2.1 cm). Measured with FK on the output."""
from __future__ import annotations

import math
import tempfile
from pathlib import Path

import pytest

import infuse
from infuse.contacts import foot_contacts
from infuse.metrics import foot_skate
from infuse.packs import build_pack
from infuse.packs.importers import import_bvh_folder
from infuse.packs.infusion import infuse_character
from infuse.packs.walk_test import PARTS, _runtime_walks, walk_parts

from corpus_data import corpus_file, require_corpus

pytest.importorskip("infuse_locomotion")

#: Most foot skate (cm) of the walk's start: 2.1 before (the foot carried on by a frame's step).
MOST_START_SKATE_CM = 1.0
#: Most foot skate (cm) of the walk's stop: 1.1 before (the touched-down foot swivelling on its heel).
MOST_STOP_SKATE_CM = 0.8
SPEED_M_S = 1.3


def _part_skate_cm(dataset: int, style: str, who: str, rig: str, angle_deg: float, seconds: float, part: str,
                   distance_m: float = 2.0) -> float:
    """Foot skate (cm, FK on the output) in ``part`` of a walk to a target ``distance_m`` away ``angle_deg`` off the
    facing, with the Bandai dataset-``dataset`` pack of ``style`` on the character ``rig``."""
    folder = require_corpus() / "bandai" / f"Bandai-Namco-Research-Motiondataset-{dataset}" / "data"
    with tempfile.TemporaryDirectory() as tmp:
        pack = build_pack(import_bvh_folder(folder, Path(tmp) / "pack", name=f"d{dataset}-{style}", pattern=f"dataset-{dataset}_*_{style}_*.bvh"))
        character = infuse.Character(who, infuse.load(corpus_file(rig)))
        space = next(iter(infuse_character(character, [pack]).spaces.values()))
        a = math.radians(angle_deg)
        target = (distance_m * math.sin(a), distance_m * math.cos(a))
        [(motion, (g_rot, g_pos))], _ = _runtime_walks(character, character.mapping, space, [dict(speed=SPEED_M_S, target=target)], seconds)
    base = character.mapping.indices(character.skeleton)["base"]
    parts = walk_parts(g_pos[:, base][:, [0, 2]], SPEED_M_S)[1:]
    steps = parts == PARTS.index(part)
    assert steps.sum() >= 10
    found = foot_contacts(motion, character.mapping, fk=(g_rot, g_pos))
    return 100.0 * foot_skate(g_pos, found, base, steps=steps).travel


def test_a_ball_held_again_before_it_lifts_stays_where_it_is_held():
    skate_cm = _part_skate_cm(1, "feminine", "Xbot", "runxaway-models/Xbot.glb", 180.0, 4.0, "start")
    assert skate_cm <= MOST_START_SKATE_CM, skate_cm


def test_a_foot_touched_down_on_its_heel_keeps_its_heading():
    """Bandai dataset-2 normal on Xbot, 6 m ahead: the stop's last step touches down by its ball, then
    rolls onto its heel before the blend's strike; on its heel the foot swivelled as the blend's swinging
    foot did (its heading held only while the blend's ball was down), sweeping its ball 1.2 cm in a frame."""
    skate_cm = _part_skate_cm(2, "normal", "Xbot", "runxaway-models/Xbot.glb", 0.0, 6.0 / SPEED_M_S + 8.0, "stop", 6.0)
    assert skate_cm <= MOST_STOP_SKATE_CM, skate_cm
