"""When a walk's feet are down: contact flags of a cycle made one loop, strikes where the heel reaches
the ground and toe offs where the ball leaves it, and every stepping cycle of the imported packs
giving its feet's events. Measured on the clips as infused onto Xbot."""
from __future__ import annotations

import numpy as np
import pytest

import infuse

from corpus_data import corpus_file, require_corpus

phase_keys = pytest.importorskip("infuse_locomotion.phase_keys")


def flags(text: str) -> np.ndarray:
    return np.array([c == "1" for c in text])


def test_a_contact_on_the_seam_and_a_broken_contact_are_one_loop():
    # The last frame repeats the first: a contact found only on the last frame starts on the seam.
    assert "".join("1" if f else "0" for f in phase_keys.looped(flags("0111100000001"), 0)) == "1111100000001"
    # A contact broken for two frames is one contact; a swing of six frames stays a swing.
    assert "".join("1" if f else "0" for f in phase_keys.looped(flags("1110011000000001"), 3)) == "1111111000000001"
    # Going round the seam: the break is at the cycle's end.
    assert "".join("1" if f else "0" for f in phase_keys.looped(flags("1100000011111000"), 3)) == "1100000011111111"
    assert not phase_keys.looped(flags("0000"), 3).any() and phase_keys.looped(flags("1111"), 3).all()


def test_a_heel_reaches_the_ground_before_its_detected_strike():
    # A heel coming down (mm), on the ground from frame 9, its contact detected from frame 12 (it slowed
    # down there), lifting again after frame 18; frame 24 repeats frame 0.
    heights = np.array([120, 150, 160, 150, 120, 90, 60, 30, 12, 2.0, 0.5, 0.2, 0.0, 0, 0, 0, 0, 0, 0, 9, 20, 40, 70, 100, 120]) / 1000.0
    swinging = (np.arange(25) < 12) | (np.arange(25) > 18)
    # Within 2.7 mm of its height at the strike from frame 9: three frames before the strike.
    assert phase_keys.grounded_frames(heights, swinging, 12, 0.0027, -1) == 3
    # At most a quarter of the swing (17 frames): 4 frames.
    assert phase_keys.grounded_frames(heights, swinging, 12, 1.0, -1) == 4
    # A ball leaving the ground after frame 18, its last frame down: 9 mm up one frame later.
    assert phase_keys.grounded_frames(heights, swinging, 18, 0.0085, 1) == 0
    assert phase_keys.grounded_frames(heights, swinging, 18, 0.0095, 1) == 1


@pytest.fixture(scope="module")
def xbot():
    require_corpus()
    return infuse.load(corpus_file("runxaway-models/Xbot.glb"))


@pytest.mark.parametrize("style", ["masculinity", "normal"])
def test_every_stepping_cycle_of_an_imported_pack_has_its_feet_events(xbot, style, tmp_path):
    """Every walking cycle of a Bandai dataset-1 style (recorded takes, cut at a left strike) gives each
    foot's strike, foot flat, heel off and toe off in order, the strike within three frames before the
    one its contact flags show."""
    from infuse.packs import build_pack, import_bvh_folder, infuse_character

    source = corpus_file("bandai/Bandai-Namco-Research-Motiondataset-1/data")
    pack = build_pack(import_bvh_folder(source, tmp_path / style, pattern=f"dataset-1_walk*_{style}_*.bvh")).manifest.path.parent
    space = next(iter(infuse_character(infuse.Character("x", xbot), [pack]).spaces.values()))
    walks = [c for c in space.group("locomotion") if c.role != "idle"]
    assert len(walks) >= 4
    for clip in walks:
        events = phase_keys.foot_events(clip)
        assert events is not None, clip.name
        spans = np.diff(events, axis=1)
        assert (spans >= 0.0).all() and (events[:, 3] - events[:, 0] < 1.0).all(), (clip.name, events)


def test_a_foot_whose_contact_was_not_found_steps_half_a_cycle_after_the_other():
    """A running cycle (31 frames at 30 fps, left strike at 0 and 1 s) whose right foot was never found
    down: its events are the left foot's half a cycle later; with neither foot found, none."""
    from types import SimpleNamespace

    left = np.zeros(31, dtype=bool)
    left[:9] = True
    left[30] = True
    contacts = np.stack((left, np.zeros(31, dtype=bool)), axis=1)
    clip = SimpleNamespace(contacts=contacts, phases=np.stack((contacts, contacts), axis=-1), keys=np.array([0.0, 0.5, 1.0]),
                           motion=SimpleNamespace(fps=30.0))
    events = phase_keys.foot_events(clip)
    assert events is not None
    # The left foot lands at its key (a flag holds its frame's half-frame either side) and leaves after 9 frames.
    assert events[0] == pytest.approx([1.0 - 0.5 / 30.0, 1.0 - 0.5 / 30.0, 1.0 + 8.5 / 30.0, 1.0 + 8.5 / 30.0])
    assert events[1] == pytest.approx(events[0] - 0.5)
    clip.contacts = np.zeros_like(contacts)
    clip.phases = np.zeros_like(clip.phases)
    assert phase_keys.foot_events(clip) is None


def rooted_away(asset, offset) -> infuse.Asset:
    """``asset`` with a joint ``Root`` added above its joint 0 at the origin, the old joint 0 placed
    ``offset`` (3,) metres from it as its child (as an OptiTrack Motive export has its hips 0.85 m
    from its root); no motions."""
    import dataclasses

    from infuse.skeleton import Skeleton

    sk = asset.skeleton
    translations = np.concatenate(([[0.0, 0.0, 0.0]], sk.rest_translations))
    translations[1] += offset
    skeleton = Skeleton(("Root",) + sk.names, np.concatenate(([-1], np.where(sk.parents < 0, 0, sk.parents + 1))),
                        translations, np.concatenate(([[0.0, 0.0, 0.0, 1.0]], sk.rest_rotations)),
                        sk.end_site_parents + 1, sk.end_site_offsets)
    return dataclasses.replace(asset, skeleton=skeleton, motions={}, path=None)


def test_a_walk_reaches_its_target_on_a_rig_whose_root_sits_away_from_the_hips(xbot, tmp_path):
    """X Bot with a root joint 0.85 m beside its hips (Motive's offset) walks to a point 4 m away at 90
    degrees to its left as X Bot does: the clips are turned and placed about the pelvis, not joint 0
    (turned about joint 0, the hips swung by the offset turned with the walk: a 0.85 m miss)."""
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
    from benchmarks.wild_pipeline import pack_row

    variant = tmp_path / "xbot_rooted_away.bvh"  # a BVH keeps a joint no mesh is bound to
    infuse.save(rooted_away(xbot, np.array([-0.45, -0.1, -0.72])), variant)
    row = pack_row(str(variant), tmp_path / "infusions")
    assert row.finite and "locomotion-male" in row.packs, row.refused
    assert row.miss_m < 0.1, row.miss_m


FEET = ("l_ankle", "r_ankle", "l_forefoot", "r_forefoot", "l_toe", "r_toe")
LEGS = ("l_hip", "r_hip", "l_knee", "r_knee") + FEET


def played_source_turns(row, asset, cache) -> np.ndarray:
    """(K,) the largest turn in one frame (degrees) of each leg joint of ``row`` (its mapped ones of
    :data:`LEGS`) in the pack cycles its walk can blend: those no faster than the first cycle at least
    as fast as the walk went (its pelvis's ground speed, averaged over each second)."""
    from infuse import metrics
    from infuse.packs import infuse_character

    index = row.mapping.indices(row.motion.skeleton)
    joints = [index[n] for n in LEGS if n in index]
    infusion = infuse_character(infuse.Character("bob", asset, row.mapping), ["locomotion-male"], mapping=row.mapping, cache=cache)
    cycles = [c for c in next(iter(infusion.spaces.values())).group("locomotion") if c.role != "idle"]
    _, p = infuse.motion_fk(row.motion)
    fps = row.motion.fps
    ground = p[:, index["base"], [0, 2]]
    second = int(round(fps))
    walked = float((np.linalg.norm(ground[second:] - ground[:-second], axis=-1)).max())  # metres in one second
    speeds = np.array([np.hypot(c.parameters["forward_speed"], c.parameters["lateral_speed"]) for c in cycles])
    top = speeds[speeds >= walked].min(initial=speeds.max())
    return np.max([metrics.largest_turns(infuse.motion_fk(c.motion)[0][:, joints])
                   for c, v in zip(cycles, speeds) if v <= top + 1e-9], axis=0)


@pytest.mark.parametrize("rig", ["xbot", "mannequiny.glb", "dab.bvh", "jesse_dance.bvh", "Hand_expression.fbx",
                                 "Witch.glb", "MotiveSkeleton.fbx", "player.glb"])
def test_legs_do_not_pop_in_a_walk(xbot, rig, tmp_path):
    """A walk to a point 4 m away at 90 degrees to the left, on X Bot and on wild rigs: no leg joint
    turns more in one frame than the pack cycles the walk blends turn theirs, plus 10 degrees. (The
    stop's quicker last steps let a foot laid flat take the animation's toe off within a frame: 39
    degrees on X Bot's left ball at arrival; on Rokoko's dance rig, whose toes point straight down at
    toe off, toes bent up the smaller way round flipped by 170 degrees. On Unity-chan the heel's rise
    about a pinned ball jumped from 23 to 41 degrees as the hip passed the closest its arc comes:
    a 28 degree ankle turn. Starting the turn, the blend went from the slowest walk to the turning
    walk in one frame, turning joint 0 by 20 degrees: the legs of Quaternius' Witch hang from it,
    30.5 degrees at the knee; OptiTrack Motive's knees 23 degrees, now under 18. GDQuest's player.glb,
    whose feet have no ball, held its ankle pinned 7% beyond the leg's reach after toe off, the knee
    locked straight: it bent from 0 to 47 degrees in one frame as the goal came back, the hip turning
    35.2 degrees.)"""
    import sys
    from pathlib import Path

    from infuse import metrics

    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
    from benchmarks.wild_pipeline import humanoid_rigs, pack_row

    if rig == "xbot":
        path, asset = str(corpus_file("runxaway-models/Xbot.glb")), xbot
    else:
        from wild_data import require_wild, wild_file

        require_wild()
        (rel,) = humanoid_rigs(rig)
        path, asset = str(wild_file(rel)), infuse.load(wild_file(rel))
    row = pack_row(path, tmp_path / "infusions")
    assert row.finite and row.miss_m < 0.1, row
    index = row.mapping.indices(row.motion.skeleton)
    joints = [index[n] for n in LEGS if n in index]
    turns = metrics.largest_turns(infuse.motion_fk(row.motion)[0][:, joints])
    source = played_source_turns(row, asset, tmp_path / "infusions")
    assert (turns <= source + metrics.POP_MARGIN_DEG).all(), (turns, source)


@pytest.mark.parametrize("rig", ["xbot", "test_mocapbank.bvh", "freya_edit.bvh"])
def test_toes_stay_above_the_level_the_feet_stand_at_in_a_walk(xbot, rig, tmp_path):
    """The built-in walk's toe off pitches the foot over its ball without bending the toes: on X Bot
    the toes' tip went 7 cm below the level the feet stood at, and a foot without a ball joint
    (MocapBank, Perception Neuron BVH: one rigid bone to the tip, longer than the pack's) dug its tip
    in by 5.6 and 5.9 cm. The lowest foot point over the whole scene (toe ends included) stays within
    1 cm of the first frame's."""
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
    from benchmarks.wild_pipeline import humanoid_rigs, pack_row

    if rig == "xbot":
        path = str(corpus_file("runxaway-models/Xbot.glb"))
    else:
        from wild_data import require_wild, wild_file

        require_wild()
        (rel,) = humanoid_rigs(rig)
        path = str(wild_file(rel))
    row = pack_row(path, tmp_path / "infusions")
    assert row.finite and row.miss_m < 0.1, row
    assert row.depth_cm < 1.0, row.depth_cm
