"""Stops, settling and turns on the spot of a pack without an idle or transitions (Bandai dataset-2
"normal" takes, imported as a user would): no foot slides while the walk comes to rest or turns on the
spot. Measured on the output with FK (:func:`infuse.packs.walk_test.trial_pack`, foot skate split by
the walk's parts)."""
from __future__ import annotations

import pytest

import infuse
from infuse.packs.walk_test import trial_pack

from corpus_data import corpus_file, require_corpus

pytest.importorskip("infuse_locomotion")

#: Most foot skate (cm) of any part of a walk to a target but the walk itself.
MOST_CM = 1.5


@pytest.fixture(scope="module")
def pack(tmp_path_factory):
    from infuse.packs import build_pack, import_bvh_folder

    require_corpus()
    source = corpus_file("bandai/Bandai-Namco-Research-Motiondataset-2/data")
    return build_pack(import_bvh_folder(source, tmp_path_factory.mktemp("packs") / "d2-normal", name="d2-normal",
                                        pattern="dataset-2_*_normal_*.bvh"))


@pytest.fixture(scope="module")
def trial(pack):
    xbot = infuse.load(corpus_file("runxaway-models/Xbot.glb"))
    return trial_pack(infuse.Character("x", xbot), pack, distances=(2.0, 4.0), angles=(0.0, 90.0, 180.0))


@pytest.mark.parametrize("part", ["on the spot", "start", "stop", "settle"])
def test_no_foot_slides_coming_to_rest_or_turning_on_the_spot(trial, part):
    # Before swinging feet landed where they touched the ground: settling 6.0 cm (2 m ahead), stopping
    # 6.0 (4 m at 90 degrees), on the spot 3.4 (2 m behind).
    worst = {(t.distance, t.angle_deg): round(t.part_skate_cm[part], 2) for t in trial.targets}
    assert max(worst.values()) <= MOST_CM, worst


def test_the_walks_still_arrive(trial):
    assert all(t.miss_m <= 0.05 and not t.loops for t in trial.targets), [(t.distance, t.angle_deg, t.miss_m) for t in trial.targets]


def test_a_foot_pivoting_on_its_ball_as_a_start_sets_off_keeps_its_heading(pack):
    # Setting off after turning on the spot, the foot held by its ball pitched about an axis taken
    # across the animated foot, not the corrected one (turned by the turn on the spot): its heading
    # swung 20 degrees about the ball and the heel slid 2.1 cm on SmartBody's Brad.
    brad = infuse.load(corpus_file("smartbody/ChrBrad/ChrBrad.sk"))
    behind = trial_pack(infuse.Character("b", brad), pack, distances=(4.0,), angles=(180.0,)).targets[0]
    assert behind.part_skate_cm["start"] <= MOST_CM, behind.part_skate_cm


def test_a_foot_passing_from_heel_to_ball_turning_on_the_spot_keeps_its_heading(tmp_path):
    # Passing from its heel to its ball, a foot took the animation's turn of that frame whole (the
    # turn on the spot's steps turn it): Bandai dataset-1 normal on X Bot, 6 m behind, its heading 6
    # degrees in one frame, the sole under the heel 11.5 mm; on the spot 1.6 cm.
    from infuse.packs import build_pack, import_bvh_folder

    require_corpus()
    source = corpus_file("bandai/Bandai-Namco-Research-Motiondataset-1/data")
    pack = build_pack(import_bvh_folder(source, tmp_path / "d1-normal", name="d1-normal", pattern="dataset-1_*_normal_*.bvh"))
    xbot = infuse.load(corpus_file("runxaway-models/Xbot.glb"))
    behind = trial_pack(infuse.Character("x", xbot), pack, distances=(6.0,), angles=(180.0,)).targets[0]
    assert behind.part_skate_cm["on the spot"] <= 1.0, behind.part_skate_cm


def test_coming_to_rest_is_the_same_in_blocks_of_any_size(pack):
    # Holding the feet down while standing still took the value of the frame before the hold within a
    # block, and the last frame's in a block that began inside the hold: 4.6 cm apart 2 m ahead.
    import numpy as np
    from infuse.runtime import Runtime, controller

    xbot = infuse.load(corpus_file("runxaway-models/Xbot.glb"))
    out = []
    for block in (1, 30):
        rt = Runtime(fps=30, block_frames=block)
        name = rt.add_character(infuse.Character("x", xbot))
        rt.activate(name, controller("locomotion", pack=pack, speed=1.3, target=(0.0, 2.0)), 0.0)
        rt.run(8.0)
        out.append(infuse.motion_fk(rt.motion(name))[1])
    assert np.abs(out[0] - out[1]).max() < 1e-6


@pytest.fixture(scope="module")
def masculinity_on_xbot(tmp_path_factory):
    """(pack, X Bot character, its mapping): the Bandai dataset-1 masculinity takes (no idle) built as a pack."""
    from infuse.mapping import map_skeleton
    from infuse.packs import build_pack, import_bvh_folder

    require_corpus()
    source = corpus_file("bandai/Bandai-Namco-Research-Motiondataset-1/data")
    pack = build_pack(import_bvh_folder(source, tmp_path_factory.mktemp("packs") / "d1-masc", name="d1-masc",
                                        pattern="dataset-1_*_masculinity_*.bvh"))
    xbot = infuse.Character("x", infuse.load(corpus_file("runxaway-models/Xbot.glb")))
    return pack, xbot, map_skeleton(xbot.asset)


def _end_stance(motion, mapping, skeleton):
    """The feet's distance front to back (m, ankles, along the facing from the hips) and the knees'
    bend (degrees, hip-knee-ankle off straight) at a motion's last frame, by FK."""
    import numpy as np

    idx = mapping.indices(skeleton)
    pos = infuse.motion_fk(motion)[1][-1]
    side = (pos[idx["l_hip"]] - pos[idx["r_hip"]]) * np.array([1.0, 0.0, 1.0])
    forward = np.cross(side / np.linalg.norm(side), [0.0, 1.0, 0.0])
    apart = abs(float((pos[idx["l_ankle"]] - pos[idx["r_ankle"]]) @ forward))
    bends = []
    for s in "lr":
        up, down = pos[idx[f"{s}_hip"]] - pos[idx[f"{s}_knee"]], pos[idx[f"{s}_ankle"]] - pos[idx[f"{s}_knee"]]
        bends.append(180.0 - float(np.degrees(np.arccos(up @ down / np.linalg.norm(up) / np.linalg.norm(down)))))
    return apart, max(bends)


def test_a_walk_to_a_target_ends_with_the_feet_side_by_side(masculinity_on_xbot):
    # A pack without an idle stands in its held stance: its blend at the stop's double support with
    # strides of nothing (the feet side by side, 2 cm apart front to back on X Bot). Its last steps
    # landed where they touched, a foot short of its place (its correction to the pelvis still
    # fading) or stepping while the pelvis still came over the point it stops at: Bandai dataset-1
    # masculinity on X Bot ended with the feet 20 cm apart 2 m ahead, 13 cm 4 m at 90 degrees; with
    # each foot stepping once at the end, 9 cm 2 m at 135 degrees (a foot out of reach stood there).
    import math

    from infuse.runtime import Runtime, controller

    pack, xbot, mapping = masculinity_on_xbot
    targets = [(2.0, 0.0), (4.0, 90.0), (4.0, 180.0), (6.0, 45.0), (2.0, 135.0)]
    rt = Runtime(fps=30)
    names = {}
    for d, a in targets:
        for pinned in (True, False):
            name = rt.add_character(xbot, name=f"w{d:g}-{a:g}-{pinned}", mapping=mapping)
            rt.activate(name, controller("locomotion", pack=pack, speed=1.3, pin_feet=pinned,
                                         target=(d * math.sin(math.radians(a)), d * math.cos(math.radians(a)))), 0.0)
            names[d, a, pinned] = name
    rt.run(10.0)
    ends = {key: _end_stance(rt.motion(name), mapping, xbot.skeleton) for key, name in names.items()}
    for d, a in targets:
        apart, bend = ends[d, a, True]
        stance, stance_bend = ends[d, a, False]  # the pack's stance, the feet where its blend puts them
        assert apart <= stance + 0.03, ((d, a), round(apart, 3), round(stance, 3))
        assert bend <= stance_bend + 5.0, ((d, a), round(bend, 1), round(stance_bend, 1))


def test_a_walk_to_a_target_comes_to_rest_standing_up(masculinity_on_xbot):
    # Without an idle a walk stands in its slowest walk's double support with strides of nothing: the
    # feet side by side under a pelvis as low as between two strides apart, the knees bent 40-45
    # degrees on X Bot (Bandai dataset-1 masculinity, the takes' stance legs 10-13), the pelvis 3-5 cm
    # below the takes' straightest stance.
    import math

    import numpy as np

    from infuse.packs import space_on
    from infuse.runtime import Runtime, controller

    pack, xbot, mapping = masculinity_on_xbot
    idx = mapping.indices(xbot.skeleton)
    legs = [[idx[f"{s}_{j}"] for j in ("hip", "knee", "ankle")] for s in "lr"]
    targets = [(2.0, 0.0), (4.0, 90.0), (4.0, 180.0), (2.0, 135.0)]
    rt = Runtime(fps=30)
    names = {}
    for d, a in targets:
        names[d, a] = rt.add_character(xbot, name=f"w{d:g}-{a:g}", mapping=mapping)
        rt.activate(names[d, a], controller("locomotion", pack=pack, speed=1.3,
                                            target=(d * math.sin(math.radians(a)), d * math.cos(math.radians(a)))), 0.0)
    rt.run(10.0)

    def bends(pos):  # (F, 2) each knee's bend (degrees off straight) in positions (F, J, 3)
        out = []
        for hip, knee, ankle in legs:
            up, down = pos[:, hip] - pos[:, knee], pos[:, ankle] - pos[:, knee]
            cos = (up * down).sum(-1) / np.linalg.norm(up, axis=-1) / np.linalg.norm(down, axis=-1)
            out.append(180.0 - np.degrees(np.arccos(np.clip(cos, -1.0, 1.0))))
        return np.stack(out, axis=-1)

    # The takes' straightest stance on X Bot: the slowest straight walk's frames with a foot planted,
    # each leg at its hip farthest from its ankle, and the pelvis's height there.
    walks = [c for c in space_on(rt.rig(names[targets[0]]), pack).group("locomotion")
             if c.parameters["forward_speed"] > 0.0 and abs(c.parameters["lateral_speed"]) + abs(c.parameters["turn_rate"]) < 1e-3]
    slowest = min(walks, key=lambda c: c.parameters["forward_speed"])
    pos = infuse.motion_fk(slowest.motion)[1]
    planted = np.asarray(slowest.contacts, dtype=bool)
    reach = np.where(planted, np.stack([np.linalg.norm(pos[:, h] - pos[:, a], axis=-1) for h, _, a in legs], axis=-1), -1.0)
    frames = reach.argmax(axis=0)
    stance_bends = bends(pos)[frames, [0, 1]]
    stance_height = float(pos[frames, idx["base"], 1].mean())
    # Each ball's height planted in that walk (median of its planted frames): the feet stand flat on
    # the ground as they lie in it. Laid as they lie in the walk back (the slowest clip stepping, its
    # feet landing by the toes), the left ball stood at 1.5 cm and the right at 6.1 (the takes' 4.5, 4.1).
    balls = [idx[f"{s}_forefoot"] for s in "lr"]
    planted_balls = np.array([np.median(pos[planted[:, k], balls[k], 1]) for k in range(2)])
    for key, name in names.items():
        end = infuse.motion_fk(rt.motion(name))[1][-1:]
        bend, height = bends(end)[0], float(end[0, idx["base"], 1])
        assert (bend <= stance_bends + 10.0).all(), (key, bend.round(1), stance_bends.round(1))
        assert abs(height - stance_height) <= 0.02, (key, round(height, 3), round(stance_height, 3))
        assert (np.abs(end[0, balls, 1] - planted_balls) <= 0.015).all(), (key, end[0, balls, 1].round(3), planted_balls.round(3))
