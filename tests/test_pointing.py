"""Pointing through BML in a scene, measured by forward kinematics on the written motion: the ray from the
shoulder joint through the index fingertip passes within 5 cm of the target at the stroke, the stroke
(the arm's furthest reach) lands on its sync time, the index is straight and the other fingers curled,
the body turns toward a target behind with the feet kept where they were; on X Bot, the Ready Player Me
avatar and the SmartBody utah skeleton."""
from __future__ import annotations

import numpy as np
import pytest

import infuse
from infuse.bml.model import NO_SUCH_TARGET
from infuse.scene import Scene
from infuse_manipulation.pointing import PointingState

from corpus_data import require_corpus
from runtime_characters import corpus_character, synthetic_character

pytest.importorskip("infuse_manipulation")

FPS = 30.0
OBJECTS = {"lamp": (1.6, 2.0, 2.2), "box": (-1.4, 0.4, -2.4), "shelf": (2.5, 1.2, 0.6)}
#: (behaviour id, element, the target's name or point, stroke time in seconds).
BML = """<bml xmlns="http://www.bml-initiative.org/bml/bml-1.0" xmlns:sbm="http://ict.usc.edu" id="b1">
  <pointing id="p1" target="lamp" stroke="1.2"/>
  <pointing id="p2" target="ann:skullbase" mode="LEFT_HAND" stroke="4.0"/>
  <pointing id="p3" target="ann" mode="RIGHT_HAND" stroke="6.8"/>
  <sbm:reach id="p4" sbm:action="point-at" sbm:target-pos="-1.5 1.0 1.5" stroke="9.6"/>
  <pointing id="p5" target="box" stroke="12.4"/>
  <pointing id="p6" target="shelf" mode="BOTH_HANDS" stroke="15.2"/>
</bml>"""
POINTINGS = ("p1", "p2", "p3", "p4", "p5", "p6")


def _scene(key: str):
    require_corpus()
    scene = Scene(fps=FPS, idle=False, quiet=True)
    warnings = []
    scene.on("warningFeedback", warnings.append)
    scene.add_character(corpus_character(key), name="bob", position=(0.3, 0.0, -0.2), facing=20.0)
    scene.add_character(corpus_character("rpm"), name="ann", position=(-0.4, 0.0, 2.6), facing="bob")
    for name, where in OBJECTS.items():
        scene.add_object(name, where)
    scene.bml("bob", BML, at=0.0)
    scene.run(17.0)
    return scene, warnings


@pytest.fixture(scope="module", params=["xbot", "rpm", "utah"])
def pointed(request):
    scene, warnings = _scene(request.param)
    motion = scene.motion("bob")
    g_rot, g_pos = infuse.motion_fk(motion)
    ann_pos = infuse.motion_fk(scene.motion("ann"))[1]
    rig, ann = scene.runtime.rig("bob"), scene.runtime.rig("ann")
    return {"key": request.param, "scene": scene, "warnings": warnings, "g_pos": g_pos, "g_rot": g_rot,
            "ix": rig.mapping.indices(motion.skeleton), "ann_pos": ann_pos,
            "ann_ix": ann.mapping.indices(ann.skeleton)}


def _activity(scene, behaviour):
    return scene.activities[("b1", behaviour)]


def _target(p, behaviour, frame) -> np.ndarray:
    if behaviour == "p2":
        return p["ann_pos"][frame, p["ann_ix"]["skullbase"]]
    if behaviour == "p3":
        return p["ann_pos"][frame, [p["ann_ix"]["eyeball_left"], p["ann_ix"]["eyeball_right"]]].mean(axis=0)
    if behaviour == "p4":
        return np.array([-1.5, 1.0, 1.5])
    return np.array(OBJECTS[{"p1": "lamp", "p5": "box", "p6": "shelf"}[behaviour]])


def _ray_distance(shoulder, tip, target) -> float:
    """Distance (metres) of ``target`` from the ray from ``shoulder`` through ``tip`` (inf behind it)."""
    u = (tip - shoulder) / np.linalg.norm(tip - shoulder)
    d = target - shoulder
    along = float(d @ u)
    return float(np.linalg.norm(d - along * u)) if along > 0 else np.inf


def test_the_ray_passes_within_5_cm_of_the_target_at_the_stroke(pointed):
    p = pointed
    distances = {}
    for behaviour in POINTINGS:
        activity = _activity(p["scene"], behaviour)
        frame = int(round(activity.source.time("stroke") * FPS))
        for side in activity.state_of(PointingState).hands:
            s = side[0]
            shoulder, tip = p["g_pos"][frame, p["ix"][f"{s}_shoulder"]], p["g_pos"][frame, p["ix"][f"{s}_index4"]]
            distances[f"{behaviour} {side}"] = _ray_distance(shoulder, tip, _target(p, behaviour, frame))
    print(p["key"], "ray-to-target distances at the stroke (cm):", {k: round(v * 100, 3) for k, v in distances.items()})
    assert max(distances.values()) < 0.05
    assert _activity(p["scene"], "p2").state_of(PointingState).hands == ("left",)
    assert _activity(p["scene"], "p3").state_of(PointingState).hands == ("right",)
    assert _activity(p["scene"], "p6").state_of(PointingState).hands == ("left", "right")


def test_the_stroke_lands_on_its_sync_time(pointed):
    """The arm reaches furthest (fingertip from shoulder) at the frame of the stroke's scheduled time."""
    p = pointed
    for behaviour, wanted in (("p1", 1.2), ("p2", 4.0), ("p3", 6.8), ("p4", 9.6)):
        activity = _activity(p["scene"], behaviour)
        assert activity.source.time("stroke") == pytest.approx(wanted, abs=1e-6)
        s = activity.state_of(PointingState).hands[0][0]
        first, last = (int(round(activity.source.time(k) * FPS)) for k in ("ready", "relax"))
        reach = np.linalg.norm(p["g_pos"][first:last + 1, p["ix"][f"{s}_index4"]]
                               - p["g_pos"][first:last + 1, p["ix"][f"{s}_shoulder"]], axis=1)
        assert abs(first + int(np.argmax(reach)) - wanted * FPS) <= 1.0, behaviour


def test_index_straight_other_fingers_curled(pointed):
    p = pointed
    g = p["g_pos"]
    ix = p["ix"]
    frame = int(round(1.2 * FPS))
    s = _activity(p["scene"], "p1").state_of(PointingState).hands[0][0]
    rest = 0  # the first frame: before any pointing
    index = [g[frame, ix[f"{s}_index{k}"]] for k in (1, 2, 3, 4)]
    first, last = index[1] - index[0], index[3] - index[2]
    bend = np.degrees(np.arccos(first @ last / np.linalg.norm(first) / np.linalg.norm(last)))
    assert bend < 20.0
    for finger in ("middle", "ring", "pinky"):
        reach = np.linalg.norm(g[:, ix[f"{s}_{finger}4"]] - g[:, ix[f"{s}_{finger}1"]], axis=1)
        assert reach[frame] < 0.6 * reach[rest], finger  # curled toward the palm


def test_the_body_turns_toward_a_target_behind_and_the_feet_stay(pointed):
    p = pointed
    g, ix = p["g_pos"], p["ix"]
    activity = _activity(p["scene"], "p5")
    before = int(round(activity.start_s * FPS)) - 1
    frame = int(round(activity.source.time("stroke") * FPS))

    def off_box_deg(f):
        """Angle about +Y between the shoulders' forward and the direction of the box from the chest."""
        left = g[f, ix["l_shoulder"]] - g[f, ix["r_shoulder"]]
        forward = np.array([-left[2], left[0]])
        box = np.array(OBJECTS["box"])[[0, 2]] - 0.5 * (g[f, ix["l_shoulder"]] + g[f, ix["r_shoulder"]])[[0, 2]]
        return np.degrees(np.arccos(forward @ box / np.linalg.norm(forward) / np.linalg.norm(box)))

    print(p["key"], f"shoulders {off_box_deg(before):.0f} deg off the box before, {off_box_deg(frame):.0f} at the stroke")
    assert off_box_deg(frame) < off_box_deg(before) - 30.0
    for ankle in ("l_ankle", "r_ankle"):
        assert np.linalg.norm(g[frame, ix[ankle]] - g[before, ix[ankle]]) < 0.005, ankle


def test_no_warning_but_the_real_reasons(pointed):
    messages = [w.description for w in pointed["warnings"]]
    assert not any("reaching pack" in m for m in messages), messages
    assert not messages, messages


def test_unknown_target_warns_with_its_name():
    require_corpus()
    scene = Scene(fps=FPS, idle=False, quiet=True)
    warnings = []
    scene.on("warningFeedback", warnings.append)
    scene.add_character(corpus_character("xbot"), name="bob")
    scene.bml("bob", '<bml xmlns="http://www.bml-initiative.org/bml/bml-1.0" id="b1">'
                     '<pointing id="p1" target="nowhere"/><pointing id="p2" target="bob:no_such_joint"/></bml>', at=0.0)
    scene.run(1.0)
    kinds = {w.id: (w.type, w.description) for w in warnings}
    assert kinds["b1:p1"][0] == NO_SUCH_TARGET and "'nowhere'" in kinds["b1:p1"][1]
    assert "no_such_joint" in kinds["b1:p2"][1]
    assert ("b1", "p1") not in scene.activities and ("b1", "p2") not in scene.activities


def test_a_rig_without_fingers_points_its_wrist():
    """The canonical skeleton without fingers: said so once, and the shoulder-wrist ray meets the target."""
    fingers = tuple(f"{s}_{f}{k}" for s in "lr" for f in ("thumb", "index", "middle", "ring", "pinky") for k in (1, 2, 3, 4))
    scene = Scene(fps=FPS, idle=False, quiet=True)
    warnings = []
    scene.on("warningFeedback", warnings.append)
    scene.add_character(synthetic_character("plain", drop=fingers), name="plain")
    scene.add_object("lamp", (1.0, 2.0, 2.0))
    scene.bml("plain", '<bml xmlns="http://www.bml-initiative.org/bml/bml-1.0" id="b1">'
                       '<pointing id="p1" target="lamp" stroke="1.0"/></bml>', at=0.0)
    scene.run(3.0)
    assert any("no fingers are mapped on the left hand: the wrist points" in w.description for w in warnings)
    g = infuse.motion_fk(scene.motion("plain"))[1]
    ix = scene.runtime.rig("plain").mapping.indices(scene.runtime.rig("plain").skeleton)
    assert _ray_distance(g[30, ix["l_shoulder"]], g[30, ix["l_wrist"]], np.array([1.0, 2.0, 2.0])) < 0.05


def test_smartbody_point_at_document():
    """SmartBody's ReachDemo ``sbm:reach sbm:action="point-at"``: a pointing, its ray through the pawn."""
    from corpus_data import corpus_file

    require_corpus()
    pawn = np.array([-1.5, 1.5, 2.0])
    scene = Scene(fps=FPS, idle=False, quiet=True)
    warnings = []
    scene.on("warningFeedback", warnings.append)
    scene.add_character(corpus_character("utah"), name="ChrBrad1")
    scene.add_object("pointPawn", pawn)
    scene.bml("ChrBrad1", corpus_file("bml/smartbody/sb35_reach_point_at.xml"), at=0.0)
    scene.run(3.0)
    assert not warnings, [w.description for w in warnings]
    (activity,) = scene.activities.values()
    assert activity.controller.kind == "pointing"
    frame = int(round(activity.source.time("stroke") * FPS))
    g = infuse.motion_fk(scene.motion("ChrBrad1"))[1]
    ix = scene.runtime.rig("ChrBrad1").mapping.indices(scene.runtime.rig("ChrBrad1").skeleton)
    s = activity.state_of(PointingState).hands[0][0]
    assert _ray_distance(g[frame, ix[f"{s}_shoulder"]], g[frame, ix[f"{s}_index4"]], pawn) < 0.05


def test_a_bare_runtime_realizes_pointing_from_bml():
    """Without a scene: the scheduler's activation through the controller's ``from_bml``."""
    from infuse.bml import Scheduler
    from infuse.runtime import Runtime

    require_corpus()
    (block,) = Scheduler().submit('<bml xmlns="http://www.bml-initiative.org/bml/bml-1.0" id="b1" characterId="bob">'
                                  '<pointing id="p1" target="bob:l_ankle" mode="RIGHT_HAND" stroke="1.5"/></bml>', at=0.0)
    (activation,) = block.activations
    rt = Runtime(fps=FPS)
    bob = rt.add_character(corpus_character("xbot"), "bob")
    activity = rt.realize(activation, bob)
    rt.run(3.0)
    g = infuse.motion_fk(rt.motion(bob))[1]
    ix = rt.rig(bob).mapping.indices(rt.rig(bob).skeleton)
    frame = int(round(1.5 * FPS))
    assert activity.state_of(PointingState).hands == ("right",)
    assert _ray_distance(g[frame, ix["r_shoulder"]], g[frame, ix["r_index4"]], g[frame, ix["l_ankle"]]) < 0.05


def test_builder_point():
    """``scene.point`` writes a <pointing> block: a point target, the hand as asked."""
    require_corpus()
    scene = Scene(fps=FPS, idle=False, quiet=True)
    scene.add_character(corpus_character("rpm"), name="ann")
    block = scene.point("ann", (1.0, 1.0, 2.0), at=0.2, hand="left")
    scene.run(3.0)
    (activity,) = [a for (b, _), a in scene.activities.items() if b == block]
    assert activity.state_of(PointingState).hands == ("left",)
    frame = int(round(activity.source.time("stroke") * FPS))
    g = infuse.motion_fk(scene.motion("ann"))[1]
    ix = scene.runtime.rig("ann").mapping.indices(scene.runtime.rig("ann").skeleton)
    assert _ray_distance(g[frame, ix["l_shoulder"]], g[frame, ix["l_index4"]], np.array([1.0, 1.0, 2.0])) < 0.05


#: Targets around a character at the origin facing +Z (metres): name -> point. "near" is within reach.
AROUND = {"high": (0.8, 2.6, 1.5), "high-side": (1.5, 2.3, 0.8), "low": (0.4, 0.1, 1.8), "side": (-2.5, 1.4, 0.2),
          "front": (-0.2, 1.3, 3.0), "behind": (-0.8, 1.2, -2.5), "near": (0.3, 1.25, 0.35)}


@pytest.fixture(scope="module", params=["xbot", "rpm", "utah"])
def around(request):
    require_corpus()
    scene = Scene(fps=FPS, idle=True, quiet=True)
    scene.add_character(corpus_character(request.param), name="bob")
    pointings = "".join(f'<pointing id="{name.replace("-", "_")}" target="{name}" stroke="{1.2 + 2.8 * k:.1f}"/>'
                        for k, name in enumerate(AROUND))
    for name, where in AROUND.items():
        scene.add_object(name, where)
    scene.bml("bob", f'<bml xmlns="http://www.bml-initiative.org/bml/bml-1.0" id="b1">{pointings}</bml>', at=0.0)
    scene.run(2.8 * len(AROUND) + 0.5)
    motion = scene.motion("bob")
    return request.param, scene, infuse.motion_fk(motion)[1], scene.runtime.rig("bob").mapping.indices(motion.skeleton)


def test_a_far_target_is_pointed_at_with_the_arm_nearly_straight(around):
    """At the stroke, FK on the written motion: the elbow opens to 150° or more for a target farther than
    1.5 arm lengths (shoulder to index fingertip) from the shoulder, the elbow hangs below the
    shoulder-wrist line, the ray passes within 5 cm; a target within reach keeps the fingertip short of it."""
    key, scene, g, ix = around
    found = {}
    for name, where in AROUND.items():
        activity = scene.activities[("b1", name.replace("-", "_"))]
        frame = int(round(activity.source.time("stroke") * FPS))
        (side,) = activity.state_of(PointingState).hands
        shoulder, elbow, wrist, tip = (g[frame, ix[f"{side[0]}_{j}"]] for j in ("shoulder", "elbow", "wrist", "index4"))
        length = sum(np.linalg.norm(b - a) for a, b in ((shoulder, elbow), (elbow, wrist), (wrist, tip)))
        upper, fore = shoulder - elbow, wrist - elbow
        angle = np.degrees(np.arccos(upper @ fore / np.linalg.norm(upper) / np.linalg.norm(fore)))
        line = (wrist - shoulder) / np.linalg.norm(wrist - shoulder)
        off_line = (elbow - shoulder) - ((elbow - shoulder) @ line) * line  # the elbow off the shoulder-wrist line
        target = np.array(where)
        found[name] = (np.linalg.norm(target - shoulder) / length, angle, off_line[1], _ray_distance(shoulder, tip, target),
                       np.linalg.norm(target - shoulder) - np.linalg.norm(tip - shoulder))
    print(key, "name: (target distance / arm length, elbow deg, elbow height off the line m, ray cm, tip short of target m)",
          {k: tuple(round(float(x), 3) for x in v) for k, v in found.items()})
    for name, (distance, angle, elbow_up, ray, short) in found.items():
        assert ray < 0.05, name
        assert elbow_up < 0.005, name
        if distance > 1.5:
            assert angle >= 150.0, name
    distance, angle, _, _, short = found["near"]
    assert distance < 1.0 and short > 0.05 and angle < 150.0
