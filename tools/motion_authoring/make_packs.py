"""Author the built-in behaviour packs: locomotion-male, locomotion-female, reaching, gestures and postures.

Run from the repository root: ``python -m tools.motion_authoring.make_packs [pack ...]`` (default: all). It writes each pack's
skeleton, clips (BVH), manifest and README into ``behaviour_libs/<pack>/infuse_pack_<pack>/pack/`` and
builds the pack (``infuse pack build``). The style figures and their sources are in
:data:`STYLES` and repeated in each locomotion pack's README.
"""
from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np

import infuse
from infuse.asset import Asset
from infuse.packs import build_pack, summary
from infuse.packs.manifest import write_manifest

from .body import Body
from .gait import Gait, gait_motion
from .gestures import gesture_clips
from .postures import posture_clips
from .reach import grasp_motion, reach_motion, reach_targets

ROOT = Path(__file__).resolve().parents[2] / "behaviour_libs"
deg = np.radians

#: Per-style gait figures. Sources (see the packs' READMEs):
#: [S] Smith, Lelas & Kerrigan 2002, J Women's Health & Gender-Based Medicine 11(5): pelvic obliquity
#:     range 9.4 deg (women) vs 7.4 deg (men); women less vertical centre-of-mass displacement.
#: [B] Bruening et al. 2015, Gait & Posture 41(2): women greater pelvic obliquity, greater transverse
#:     pelvis and torso rotation, greater arm swing, a steadier torso and head in the frontal plane.
#: [C] Cho, Park & Kwon 2004, Clinical Biomechanics 19(2): women shorter strides, narrower step width,
#:     more pelvic obliquity motion, hips more adducted.
#: [K] Ko et al. 2011, J Biomechanics 44(10): women higher cadence and shorter strides at the same speed.
STYLES = {
    "male": dict(step_width=0.11, pelvis_obliquity=deg(3.7), pelvis_rotation=deg(4.0), trunk_rotation=deg(3.0),
                 trunk_sway=deg(2.5), sway=0.028, bob=0.025, arm_swing=deg(14.0), carrying_angle=deg(11.0),
                 toe_out=deg(7.0), finger_curl=deg(18.0)),
    "female": dict(step_width=0.065, pelvis_obliquity=deg(4.7), pelvis_rotation=deg(6.0), trunk_rotation=deg(4.5),
                   trunk_sway=deg(1.2), sway=0.022, bob=0.021, arm_swing=deg(18.0), carrying_angle=deg(15.0),
                   toe_out=deg(4.0), finger_curl=deg(12.0)),
}
#: (speed m/s, cadence steps/min) per gait: women step faster and shorter at similar speeds [K][C].
SPEEDS = {
    "male": {"walk_slow": (0.9, 92), "walk": (1.4, 110), "walk_fast": (1.85, 124), "jog": (2.5, 156), "run": (3.5, 170),
             "turn": (1.1, 102), "strafe": (0.8, 96)},
    "female": {"walk_slow": (0.85, 98), "walk": (1.32, 117), "walk_fast": (1.75, 131), "jog": (2.3, 164), "run": (3.2, 178),
               "turn": (1.05, 108), "strafe": (0.75, 102)},
}


def running(g: Gait, speed: float, cadence: float, jog: bool) -> Gait:
    return replace(g, speed=speed, cadence=cadence, run=True, duty=0.40 if jog else 0.34, heel_strike=deg(8.0 if jog else 4.0),
                   toe_off=deg(35.0), clearance=0.22 if jog else 0.30, bob=0.035 if jog else 0.04, extra_drop=0.06,
                   elbow=deg(75.0 if jog else 85.0), elbow_swing=deg(10.0), arm_swing=g.arm_swing * (1.5 if jog else 1.9),
                   trunk_lean=deg(5.0 if jog else 8.0), pelvis_tilt=deg(6.0), finger_curl=deg(45.0), head_pitch=deg(-4.0))


def locomotion_clips(style: str) -> dict[str, tuple[Gait, str, list[str]]]:
    """Clip name -> (gait, role, tags) for one style."""
    base = Gait(**STYLES[style])
    s = SPEEDS[style]
    walk = lambda key, **kw: replace(base, speed=s[key][0], cadence=s[key][1], **kw)  # noqa: E731
    turn_rate = deg(50.0)
    return {
        "idle": (replace(base, speed=0.0, cadence=30.0, duty=1.0, heel_strike=0.0, toe_off=0.0, bob=0.002, sway=0.012,
                         step_width=base.step_width + 0.1, pelvis_rotation=deg(1.0), pelvis_obliquity=deg(1.0),
                         trunk_rotation=deg(0.5), trunk_sway=deg(0.5), arm_swing=deg(1.5), extra_drop=0.01), "idle", ["idle"]),
        "walk_slow": (walk("walk_slow", arm_swing=base.arm_swing * 0.7, bob=base.bob * 0.7), "cycle", ["walk", "slow"]),
        "walk": (walk("walk"), "cycle", ["walk"]),
        "walk_fast": (walk("walk_fast", arm_swing=base.arm_swing * 1.3, elbow=deg(25.0), duty=0.58), "cycle", ["walk", "fast"]),
        "jog": (running(base, *s["jog"], jog=True), "cycle", ["jog"]),
        "run": (running(base, *s["run"], jog=False), "cycle", ["run"]),
        "walk_turn_left": (walk("turn", turn_rate=turn_rate), "cycle", ["walk", "turn", "left"]),
        "walk_turn_right": (walk("turn", turn_rate=-turn_rate), "cycle", ["walk", "turn", "right"]),
        "strafe_left": (walk("strafe", direction=deg(90.0), pelvis_rotation=deg(1.5), arm_swing=deg(4.0), heel_strike=deg(5.0),
                             toe_off=deg(20.0), clearance=0.05, step_width=0.16), "cycle", ["strafe", "left"]),
        "strafe_right": (walk("strafe", direction=deg(-90.0), pelvis_rotation=deg(1.5), arm_swing=deg(4.0), heel_strike=deg(5.0),
                              toe_off=deg(20.0), clearance=0.05, step_width=0.16), "cycle", ["strafe", "right"]),
    }


def write_clip(body: Body, motion, path: Path) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    infuse.save(Asset(None, "bvh", body.skeleton, {motion.name: motion}), path)


def pack_folder(name: str) -> Path:
    return ROOT / name / f"infuse_pack_{name.replace('-', '_')}" / "pack"


def make_locomotion(body: Body, style: str) -> Path:
    name = f"locomotion-{style}"
    folder = pack_folder(name)
    entries = []
    for clip, (gait, role, tags) in locomotion_clips(style).items():
        motion, _ = gait_motion(body, gait, clip, cycles=1)
        write_clip(body, motion, folder / "clips" / f"{clip}.bvh")
        entries.append({"name": clip, "file": f"clips/{clip}.bvh", "role": role, "tags": tags, "loop": True})
    write_clip(body, infuse.Motion.rest_pose(body.skeleton, name="rest"), folder / "skeleton.bvh")
    pack = {"name": name, "version": "1.0.0", "kind": "locomotion", "skeleton": "skeleton.bvh", "analysis": "analysis.json",
            "description": f"{style} locomotion: idle, walks, jog, run, turns and strafes (procedural, gait-study figures)"}
    return write_manifest(folder / "manifest.toml", pack, entries)


def make_reaching(body: Body) -> Path:
    folder = pack_folder("reaching")
    stand, _ = gait_motion(body, locomotion_clips("male")["idle"][0], "stand")
    stand = stand.replace(local_rotations=stand.local_rotations[:1], root_translations=stand.root_translations[:1])
    entries = []
    for side, hand in (("l", "left"), ("r", "right")):
        for clip, target in reach_targets(body, side):
            write_clip(body, reach_motion(body, stand, side, target, clip), folder / "clips" / f"{clip}.bvh")
            entries.append({"name": clip, "file": f"clips/{clip}.bvh", "role": "reach", "tags": ["reach"], "loop": False, "hand": hand})
        clip = f"grasp_{hand}"
        write_clip(body, grasp_motion(body, stand, side, clip), folder / "clips" / f"{clip}.bvh")
        entries.append({"name": clip, "file": f"clips/{clip}.bvh", "role": "grasp", "tags": ["grasp"], "loop": False, "hand": hand})
    write_clip(body, infuse.Motion.rest_pose(body.skeleton, name="rest"), folder / "skeleton.bvh")
    pack = {"name": "reaching", "version": "1.0.0", "kind": "reach", "skeleton": "skeleton.bvh", "analysis": "analysis.json",
            "description": "standing reaches over a grid of targets for each hand, and a grasp (procedural)"}
    return write_manifest(folder / "manifest.toml", pack, entries)


def make_gestures(body: Body) -> Path:
    """The gestures pack: each gesture for the hands it is made for, its phases as sync times and the BML
    lexemes it realizes as tags (none on a repeated stroke's variant, which no lexeme names)."""
    folder = pack_folder("gestures")
    stand, _ = gait_motion(body, locomotion_clips("male")["idle"][0], "stand")
    entries = []
    for spec, hand, motion in gesture_clips(body, stand):
        write_clip(body, motion, folder / "clips" / f"{motion.name}.bvh")
        entries.append({"name": motion.name, "file": f"clips/{motion.name}.bvh", "role": "gesture",
                        "tags": [] if "@" in motion.name else [spec.name, *(lexeme.lower() for lexeme in spec.lexemes)],
                        "loop": False,
                        "hand": hand, "sync": {k: round(v, 4) for k, v in motion.sync_points.items()}})
    write_clip(body, infuse.Motion.rest_pose(body.skeleton, name="rest"), folder / "skeleton.bvh")
    pack = {"name": "gestures", "version": "1.0.0", "kind": "gesture", "skeleton": "skeleton.bvh", "analysis": "analysis.json",
            "description": "conversational gestures for each hand and both: beats, offer, reject, shrug, count, wave, "
                           "this big, cycle, contrast, self-point, chin touch, thumbs-up, past, future, here, tiny, "
                           "hand on belly (procedural)"}
    return write_manifest(folder / "manifest.toml", pack, entries)


def make_postures(body: Body) -> Path:
    """The postures pack: each standing or seated posture's looping idle, the BML lexemes it realizes as tags."""
    folder = pack_folder("postures")
    entries = []
    for spec, motion in posture_clips(body):
        write_clip(body, motion, folder / "clips" / f"{motion.name}.bvh")
        entries.append({"name": motion.name, "file": f"clips/{motion.name}.bvh", "role": "posture",
                        "tags": list(dict.fromkeys([spec.name, *(lexeme.lower() for lexeme in spec.lexemes)])), "loop": True})
    write_clip(body, infuse.Motion.rest_pose(body.skeleton, name="rest"), folder / "skeleton.bvh")
    pack = {"name": "postures", "version": "1.0.0", "kind": "posture", "skeleton": "skeleton.bvh", "analysis": "analysis.json",
            "description": "standing and seated postures with their idles: neutral, weight on the left or right leg, arms "
                           "crossed, hands on hips, behind the back or clasped, leaning forward or back; sitting upright, "
                           "hands on the lap, leaning forward with the forearms on the thighs (procedural)"}
    return write_manifest(folder / "manifest.toml", pack, entries)


ALL = ("locomotion-male", "locomotion-female", "reaching", "gestures", "postures")


def main(packs=ALL) -> None:
    body = Body.canonical()
    makers = {"locomotion-male": lambda: make_locomotion(body, "male"), "locomotion-female": lambda: make_locomotion(body, "female"),
              "reaching": lambda: make_reaching(body), "gestures": lambda: make_gestures(body),
              "postures": lambda: make_postures(body)}
    for manifest in (makers[p]() for p in packs):
        print(summary(build_pack(manifest)))


if __name__ == "__main__":
    import sys

    main(tuple(sys.argv[1:]) or ALL)
