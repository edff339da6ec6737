"""What users see frame by frame in walks: pops, flipped feet, curled toes, joints under the floor.

Each locomotion pack (SmartBody's MaleLocomotion and FemaleLocomotion sets and the six Bandai styles,
imported as :mod:`benchmarks.locomotion_packs` does, and the built-in packs) walks on Xbot, Brad and
rigs of other families from the wild folder (``INFUSE_WILD``): straight at its slowest, walking and
fastest forward speeds (:data:`STRAIGHT_S` seconds each, from standing), and to points
:data:`TARGET_M` m away at :data:`ANGLES` degrees off the facing. Measured with FK on the output at
30 fps, against the pack's own takes (on the pack's skeleton, each take's frames 1/30 s apart):

- **pop**: each joint's largest turn of its global orientation in one frame (degrees), over the
  largest the takes show for the same canonical joint at that speed (the takes no faster than the
  slowest example at or above the asked speed, with the standing and transition takes), at least
  :data:`POP_FLOOR_DEG`: a ratio above :data:`POP_RATIO` is a pop; fingers aside;
- **roll**: how far a foot turns about its length from its flat pose (the frame of the walk or take
  where ankle and ball are lowest together): its turn less its turn about the vertical, about the
  horizontal from the ankle toward the ball (turned as the foot yawed), degrees; past 90 it is upside
  down;
- **toe bend**: the ball joint's turn relative to the ankle about the axis across the foot, up
  positive, against the flat pose (degrees), and how far it goes beyond the range of the takes;
- **lowest**: the lowest joint of the legs and feet (hips down) over the walk, cm above the ground
  (y = 0, where the runtime stands characters).

Run: ``python benchmarks/locomotion_pops.py [--only PACK] [--on CHARACTER] [--quick]`` (needs the
corpus; ``--quick``: Xbot and Brad only).
"""
from __future__ import annotations

import argparse
import math
import os
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

import infuse
from infuse import quaternions as quat
from infuse.contacts import feet
from infuse.errors import MissingJointsError
from infuse.kinematics import forward_kinematics, motion_fk
from infuse.packs import build_pack, infuse_character, load_pack
from infuse.packs.importers import import_bvh_folder, import_smartbody
from infuse.packs.walk_test import forward_speeds

REPO = Path(__file__).resolve().parents[1]
CORPUS = Path(os.environ.get("INFUSE_CORPUS", REPO.parent / "shared" / "corpus")).resolve()
WILD = Path(os.environ.get("INFUSE_WILD", REPO.parent / "shared" / "wild")).resolve()
CHARACTERS = {"Xbot": CORPUS / "runxaway-models/Xbot.glb", "Brad": CORPUS / "smartbody/ChrBrad/ChrBrad.sk",
              "animation.bvh": WILD / "numediart-ofxMotionMachine/mmExampleData/animation.bvh",
              "Med_General": WILD / "sketchpunklabs-kaykit_char/res/anim/Med_General.glb",
              "Casual": WILD / "trebeljahr-quaternius-showcase/public/glb/modular_men/Casual.glb",
              "mannequiny": WILD / "godotengine-godot-demo-projects/3d/ragdoll_physics/characters/mannequiny.glb"}
SMARTBODY = {"sb-male": "MaleLocomotion", "sb-female": "FemaleLocomotion"}
BANDAI = {f"d{n}-{style}": (f"Bandai-Namco-Research-Motiondataset-{n}", f"dataset-{n}_*_{style}_*.bvh")
          for n, styles in ((1, ("feminine", "masculinity", "normal")), (2, ("feminine", "masculine", "normal")))
          for style in styles}
BUILT_IN = ("locomotion-male", "locomotion-female")

FPS = 30.0
STRAIGHT_S = 6.0
TARGET_M = 4.0
ANGLES = (0.0, 45.0, 90.0, 135.0, 180.0, -90.0)
WALK_SPEED = 1.3
#: A joint the takes turn less than this (degrees a frame at 30 fps) is compared with this.
POP_FLOOR_DEG = 3.0
#: A frame whose turn is more than this many times the takes' is a pop.
POP_RATIO = 3.0
FINGERS = ("thumb", "index", "middle", "ring", "pinky")


def turns_per_frame(g_rot: np.ndarray, fps: float) -> np.ndarray:
    """(F', J) turn of each joint's global orientation (degrees) over 1/:data:`FPS` s, from (F, J, 4)
    global rotations at ``fps``: between frames ``round(fps / FPS)`` apart, scaled to 1/FPS s."""
    step = max(int(round(fps / FPS)), 1)
    if len(g_rot) <= step:
        return np.zeros((0, g_rot.shape[1]))
    return np.degrees(quat.angle_between(g_rot[:-step], g_rot[step:])) * (fps / FPS / step)


def _tip(sk, joint: int) -> np.ndarray | None:
    """(3,) offset of ``joint``'s farthest child joint or end site in its frame, or None."""
    offsets = [sk.rest_translations[c] for c in np.flatnonzero(sk.parents == joint)]
    offsets += [o for j, o in zip(sk.end_site_parents, sk.end_site_offsets) if j == joint]
    far = max(offsets, key=lambda o: float(np.linalg.norm(o)), default=None)
    return None if far is None or np.linalg.norm(far) < 1e-6 else np.asarray(far, dtype=np.float64)


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.maximum(np.linalg.norm(v, axis=-1, keepdims=True), 1e-12)


@dataclass
class FootMeasures:
    """Per-frame foot figures, degrees: ``roll`` (F, 2) about the foot's length; ``toe_bend`` (F, 2) the
    toes' turn up about the axis across the foot against its flat pose (NaN for a foot without a ball
    joint)."""

    roll: np.ndarray
    toe_bend: np.ndarray


def foot_measures(sk, mapping, g_rot: np.ndarray, g_pos: np.ndarray) -> FootMeasures:
    """Roll and toe bend of both feet (see :class:`FootMeasures`) from (F, J, 4) global rotations and
    (F, J, 3) positions (metres) of ``sk`` mapped by ``mapping``, each foot against its flat pose in the
    same motion: the frame where its ankle and ball (or tip) are lowest together (rest poses are not
    always standing ones)."""
    pair = feet(sk, mapping)
    up = np.array([0.0, 1.0, 0.0])
    roll = np.zeros((len(g_rot), 2))
    bend = np.full((len(g_rot), 2), np.nan)
    for k, foot in enumerate(pair):
        tip = _tip(sk, foot.ankle) if foot.ball is None else None
        if foot.ball is not None:
            front = g_pos[:, foot.ball]
        elif tip is not None:
            front = g_pos[:, foot.ankle] + quat.rotate(g_rot[:, foot.ankle], tip)
        else:
            continue
        ankle_rot = g_rot[:, foot.ankle]
        flat = int(np.argmin(g_pos[:, foot.ankle, 1] + front[:, 1]))
        ahead = front[flat] - g_pos[flat, foot.ankle]
        to_local = quat.conjugate(ankle_rot[flat])
        ahead = quat.rotate(to_local, _unit(ahead - up * ahead[1]))
        # The foot's turn from its flat pose (world frame) less its turn about the vertical: a turn about a
        # horizontal axis, whose part about the foot's ahead (the flat pose's, turned as the foot yawed)
        # is the roll (past 90 degrees, upside down) and the rest the pitch.
        turn = quat.multiply(ankle_rot, quat.conjugate(ankle_rot[flat]))
        heading = np.zeros_like(turn)
        heading[:, 1], heading[:, 3] = turn[:, 1], turn[:, 3]
        heading = quat.normalize(np.where(np.abs(heading).sum(axis=-1, keepdims=True) > 1e-12, heading, quat.identity()))
        tilt = quat.to_rotvec(quat.multiply(turn, quat.conjugate(heading)))
        along = quat.rotate(heading, quat.rotate(ankle_rot[flat], ahead))
        roll[:, k] = np.degrees(np.abs(np.sum(tilt * along, axis=-1)))
        if foot.ball is None:
            continue
        # The toes' turn against the foot since the flat pose (in the ankle's frame), about the axis across
        # the foot there: up (the toes' front toward the foot's up) positive.
        relative = quat.multiply(quat.conjugate(ankle_rot), g_rot[:, foot.ball])
        since = quat.to_rotvec(quat.multiply(relative, quat.conjugate(relative[flat])))
        bend[:, k] = np.degrees(since @ _unit(np.cross(ahead, quat.rotate(to_local, up))))
    return FootMeasures(roll, bend)


def leg_joints(sk, mapping) -> list[int]:
    """Every joint of both legs: the hips and everything below them."""
    pair = feet(sk, mapping)
    inside = np.zeros(sk.num_joints, dtype=bool)
    inside[[pair[0].hip, pair[1].hip]] = True
    for j in range(sk.num_joints):
        p = sk.parents[j]
        inside[j] |= p >= 0 and inside[p]
    return [int(j) for j in np.flatnonzero(inside)]


@dataclass
class Take:
    """One take of a pack, measured on the pack's skeleton: its speed (m/s), each canonical joint's
    largest turn in 1/30 s (degrees), its toe bend range (degrees, both feet) and largest roll."""

    name: str
    speed: float
    turns: dict[str, float]
    toe_range: tuple[float, float]
    roll: float


def takes(pack) -> list[Take]:
    """Every locomotion take of ``pack`` (a :class:`~infuse.packs.Pack`), measured (see :class:`Take`)."""
    sk, mapping = pack.skeleton, pack.mapping
    index = mapping.indices(sk)
    names = [n for n in index if not any(f in n for f in FINGERS)]
    out = []
    for name, motion in pack.motions.items():
        info = pack.clip_info(name)
        g_rot, g_pos = forward_kinematics(sk, motion.local_rotations, motion.root_translations, motion.joint_translations)
        turns = turns_per_frame(g_rot[:, [index[n] for n in names]], motion.fps)
        fm = foot_measures(sk, mapping, g_rot, g_pos)
        bend = fm.toe_bend[np.isfinite(fm.toe_bend)]
        speed = float(info.get("parameters", {}).get("speed", 0.0))
        out.append(Take(name, speed, dict(zip(names, turns.max(axis=0) if len(turns) else np.zeros(len(names)))),
                        (float(bend.min()), float(bend.max())) if bend.size else (0.0, 0.0),
                        float(np.abs(fm.roll).max())))
    return out


def takes_at(all_takes: list[Take], speed: float) -> list[Take]:
    """The takes no faster than the slowest take at or above ``speed`` (m/s; every take when none is)."""
    above = [t.speed for t in all_takes if t.speed >= 0.95 * speed]
    limit = min(above) if above else max(t.speed for t in all_takes)
    return [t for t in all_takes if t.speed <= limit + 1e-9]


@dataclass
class Walk:
    """One walk's figures: the worst pop (joint, degrees in one frame, the takes' largest, ratio,
    frame), the largest roll and toe bend (degrees) and beyond the takes' range, the lowest leg joint."""

    label: str
    pop_joint: str = ""
    pop_deg: float = 0.0
    pop_ref_deg: float = 0.0
    pop_ratio: float = 0.0
    pop_frame: int = 0
    roll_deg: float = 0.0
    roll_ref_deg: float = 0.0
    toe_up_deg: float = 0.0
    toe_down_deg: float = 0.0
    toe_beyond_deg: float = 0.0
    toe_beyond_frames: int = 0
    lowest_cm: float = 0.0
    lowest_joint: str = ""
    lowest_frame: int = 0


def measure_walk(label: str, motion, mapping, reference: list[Take], fk=None) -> Walk:
    """The figures of one output ``motion`` (30 fps) against the pack's ``reference`` takes."""
    sk = motion.skeleton
    g_rot, g_pos = motion_fk(motion) if fk is None else fk
    index = mapping.indices(sk)
    names = [n for n in index if not any(f in n for f in FINGERS) and n in reference[0].turns]
    w = Walk(label)
    if len(g_rot) > 1 and names:
        turns = turns_per_frame(g_rot[:, [index[n] for n in names]], motion.fps)
        ref = np.array([max(t.turns[n] for t in reference) for n in names])
        ratio = turns / np.maximum(ref, POP_FLOOR_DEG)
        f, j = np.unravel_index(int(np.argmax(ratio)), ratio.shape)
        w.pop_joint, w.pop_deg, w.pop_ref_deg, w.pop_ratio, w.pop_frame = names[j], float(turns[f, j]), float(ref[j]), float(ratio[f, j]), int(f) + 1
    fm = foot_measures(sk, mapping, g_rot, g_pos)
    w.roll_deg, w.roll_ref_deg = float(np.abs(fm.roll).max()), max(t.roll for t in reference)
    if np.isfinite(fm.toe_bend).any():
        lo, hi = min(t.toe_range[0] for t in reference), max(t.toe_range[1] for t in reference)
        b = np.where(np.isfinite(fm.toe_bend), fm.toe_bend, 0.0)
        w.toe_up_deg, w.toe_down_deg = float(b.max()), float(b.min())
        beyond = np.maximum(b - hi, lo - b)
        w.toe_beyond_deg = float(max(beyond.max(), 0.0))
        w.toe_beyond_frames = int((beyond > 5.0).any(axis=1).sum())
    legs = leg_joints(sk, mapping)
    heights = g_pos[:, legs, 1]
    f, j = np.unravel_index(int(np.argmin(heights)), heights.shape)
    w.lowest_cm, w.lowest_joint, w.lowest_frame = 100.0 * float(heights[f, j]), sk.names[legs[j]], int(f)
    return w


def walk_pack(character, pack, space, mapping, reference: list[Take]) -> list[Walk]:
    """Walk ``space`` (the pack infused on ``character``) straight at three speeds and to targets, and
    measure each walk (:func:`measure_walk`)."""
    from infuse.runtime import Runtime, controller

    speeds = forward_speeds(space)
    speeds = speeds[[0, len(speeds) // 2, -1]] if speeds.size else np.zeros(0)
    walk = float(np.clip(WALK_SPEED, speeds.min(), speeds.max())) if speeds.size else WALK_SPEED
    settings = [(f"straight {v:.2f} m/s", dict(speed=float(v))) for v in speeds]
    settings += [(f"to {TARGET_M:g} m at {a:g} deg", dict(speed=walk, target=(TARGET_M * math.sin(math.radians(a)), TARGET_M * math.cos(math.radians(a)))))
                 for a in ANGLES]
    rt = Runtime(fps=FPS, report=lambda who, message: None)
    names = []
    for k, (_, s) in enumerate(settings):
        names.append(rt.add_character(character, name=f"walk{k}", mapping=mapping))
        rt.activate(names[-1], controller("locomotion", pack=space, **s), 0.0)
    rt.run(max(STRAIGHT_S, TARGET_M / walk + 7.0))
    out = []
    for (label, s), name in zip(settings, names):
        m = rt.motion(name)
        if label.startswith("straight"):
            m = m.replace(local_rotations=m.local_rotations[:int(STRAIGHT_S * FPS)],
                          root_translations=m.root_translations[:int(STRAIGHT_S * FPS)],
                          joint_translations=None if m.joint_translations is None else m.joint_translations[:int(STRAIGHT_S * FPS)])
        out.append(measure_walk(label, m, mapping, takes_at(reference, float(s["speed"]))))
    return out


def packs(folder: Path, only: str | None) -> dict[str, object]:
    """Pack name -> a loaded :class:`~infuse.packs.Pack` (imported and built in ``folder``, or built in)."""
    out: dict[str, object] = {}
    for name, source in SMARTBODY.items():
        if not only or only in name:
            out[name] = load_pack(build_pack(import_smartbody(CORPUS / "smartbody" / "behaviorsets" / source, folder / name, name=name)).manifest.path)
    for name, (source, pattern) in BANDAI.items():
        if not only or only in name:
            out[name] = load_pack(build_pack(import_bvh_folder(CORPUS / "bandai" / source / "data", folder / name, name=name, pattern=pattern)).manifest.path)
    for name in BUILT_IN:
        if not only or only in name:
            out[name] = load_pack(name)
    return out


@dataclass
class Row:
    pack: str
    character: str
    walks: list[Walk] = field(default_factory=list)
    refused: str = ""

    def worst(self, key: str, lowest: bool = False) -> Walk:
        return (min if lowest else max)(self.walks, key=lambda w: getattr(w, key))


def trial(pack, who: str, asset) -> Row:
    """Walk ``pack`` on ``asset`` and measure (:func:`walk_pack`)."""
    row = Row(pack.name, who)
    character = infuse.Character(who, asset)
    try:
        infusion = infuse_character(character, [pack])
    except MissingJointsError as exc:
        row.refused = exc.problem
        return row
    space = next(iter(infusion.spaces.values()))
    row.walks = walk_pack(character, pack, space, infusion.mapping, takes(pack))
    return row


def line(row: Row) -> str:
    if row.refused:
        return f"{row.pack:<18} {row.character:<14} refused: {row.refused}"
    p, r, t, lo = row.worst("pop_ratio"), row.worst("roll_deg"), row.worst("toe_beyond_deg"), row.worst("lowest_cm", lowest=True)
    return (f"{row.pack:<18} {row.character:<14} {p.pop_deg:6.1f} {p.pop_ref_deg:5.1f} {p.pop_ratio:5.1f} "
            f"{p.pop_joint + '@' + str(p.pop_frame) + ' ' + p.label:<38} {r.roll_deg:4.0f}/{r.roll_ref_deg:<3.0f} {t.toe_up_deg:6.1f} {t.toe_beyond_deg:6.1f} "
            f"{t.toe_beyond_frames:4d} {lo.lowest_cm:6.1f} {lo.lowest_joint + '@' + str(lo.lowest_frame) + ' ' + lo.label}")


HEADER = (f"{'pack':<18} {'character':<14} {'pop':>6} {'takes':>5} {'ratio':>5} {'where':<38} {'roll/takes':>8} {'toe up':>6} "
          f"{'beyond':>6} {'fr':>4} {'lowest':>6} where\n"
          f"{'':<18} {'':<14} {'deg':>6} {'deg':>5} {'':>5} {'':<38} {'deg':>8} {'deg':>6} {'deg':>6} {'':>4} {'cm':>6}")


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--only", help="packs whose name holds this")
    p.add_argument("--on", help="characters whose name holds this")
    p.add_argument("--quick", action="store_true", help="Xbot and Brad only")
    p.add_argument("--full", action="store_true", help="print every walk")
    args = p.parse_args()
    if not (CORPUS / "bandai").is_dir():
        print(f"corpus not found at {CORPUS} (set INFUSE_CORPUS)", file=sys.stderr)
        return 2
    chosen = {n: f for n, f in CHARACTERS.items() if (not args.on or args.on in n) and (not args.quick or n in ("Xbot", "Brad"))}
    missing = [str(f) for f in chosen.values() if not f.exists()]
    if missing:
        print(f"not found: {', '.join(missing)} (set INFUSE_WILD)", file=sys.stderr)
        return 2
    assets = {n: infuse.load(f) for n, f in chosen.items()}
    print(HEADER)
    with tempfile.TemporaryDirectory() as tmp:
        for pack in packs(Path(tmp), args.only).values():
            for who, asset in assets.items():
                start = time.perf_counter()
                row = trial(pack, who, asset)
                print(line(row) + f"  ({time.perf_counter() - start:.0f} s)", flush=True)
                if args.full:
                    for w in row.walks:
                        print(f"    {w}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
