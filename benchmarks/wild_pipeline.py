"""The whole pipeline on rigs of families the project was not developed on (``INFUSE_WILD``).

For every humanoid rig of the wild folder:

1. **Retargeting.** Three corpus clips (a Bandai BVH walk, a SmartBody walk, CMU 131_01 "start walk
   stop") are put onto the rig as ``infuse retarget`` does (both skeletons mapped by the default
   mapper, one :class:`~infuse_retarget.RetargetPlan`, contact-pinned feet, the clip stood on the
   ground) and written to a ``.glb``; the written file is read back and measured with FK:

   - foot skate, cm per metre walked (:func:`infuse.metrics.foot_skate` over the source's contacts),
     source and output, and its target, source x 1.1 + 0.5;
   - bone-direction error, degrees: the limbs and the hip and shoulder lines, output against source;
   - penetration of each foot below the level it rests at while planted, cm (mean and deepest; the
     source's deepest beside it: a mocap floor is not always level), and the float of a planted
     foot, cm;
   - popping: the joint whose largest turn between two frames comes closest to (or goes furthest
     past) 1.5 x the source's + 10 degrees, and its margin (negative: past the bound);
   - the share of foot goals out of reach, the largest miss of a reachable one (mm);
   - on the written file: every value finite, and the lowest foot point (soles included) over the
     clip, cm (0: it stands on y = 0 as written);
   - on a rig whose feet end at the ankle and carry a mesh, the deepest the heel or tip the mesh
     gives them (:attr:`~infuse_retarget.RetargetPlan.sole_points`, carried by the ankle) goes below
     the level its foot is planted at, cm (one sole depth per rig, as above, cannot see a foot
     pitching its tip into the ground).

2. **Behaviour packs.** The rig is infused with ``locomotion-male``, ``gestures`` and ``postures`` in
   a scene (a pack the rig cannot play, :class:`~infuse.MissingJointsError`, is counted with its
   reason and the others go on); it walks to a point 4 m away at 90 degrees to its left, then plays a
   beat gesture and an arms-crossed posture. Measured on the scene's output with FK: the pelvis's
   miss of the target (m, its ground point over the last half second of the walk) and when it came
   within 10 cm for good (s), foot skate over the walk (cm per metre), how far the beat moved the
   right wrist and the posture the wrists (relative to the chest, % of the arm's length), every
   value finite, the deepest a foot goes below the level it stood at in the first frame (cm, soles
   included), the joint (fingers aside) that turns most in one frame (degrees), and on a rig whose
   feet hang outside their legs (from the root, in rigs built for IK) how far a foot joint gets from
   its shin's end (mm, :func:`infuse.runtime.limb_ik.carried_offset`).

The worst cases of each table are named at the end. Run: ``python benchmarks/wild_pipeline.py``
(``--quick``: 6 rigs and the Bandai walk only; ``--rigs TEXT``: rigs whose path contains TEXT;
``--markdown``: a summary, one row per rig, as in ``docs/wild.md``).
"""
from __future__ import annotations

import argparse
import dataclasses
import json
import os
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

import infuse
from infuse import metrics
from infuse import quaternions as quat
from infuse.contacts import feet, foot_contacts, lowest_points
from infuse.errors import MissingJointsError
from infuse.grounding import foot_height, grounded, sole_depth
from infuse.kinematics import motion_fk
from infuse.mapping import map_skeleton
from infuse.packs import infuse_character
from infuse.runtime.limb_ik import carried_offset
from infuse.scene import Scene
from infuse_retarget import RetargetPlan, retarget_clip
from infuse_retarget.command import source_mapping
from infuse_retarget.quality import evaluate

REPO = Path(__file__).resolve().parents[1]
WILD = Path(os.environ.get("INFUSE_WILD", REPO.parent / "shared" / "wild")).resolve()
CORPUS = Path(os.environ.get("INFUSE_CORPUS", REPO.parent / "shared" / "corpus")).resolve()
SOURCES = {
    "bandai walk": "bandai/Bandai-Namco-Research-Motiondataset-1/data/dataset-1_walk_normal_001.bvh",
    "smartbody walk": "smartbody/behaviorsets/MaleLocomotion/motions/ChrUtah_Walk001.skm",
    "cmu walk": "bvh11/resources/131_01.bvh",
}
PACKS = ("locomotion-male", "gestures", "postures")
QUICK = ("mocapbank", "BrainStem", "Motive", "mannequiny", "Casual", "CandyRockStar")
FPS = 30.0
#: The walk's target: 4 m away at 90 degrees to the left of a character facing +Z (x, z), metres.
TARGET = (4.0, 0.0)
WALK_AT_S, WALK_S = 0.2, 8.0
BML = '<bml xmlns="http://www.bml-initiative.org/bml/bml-1.0" id="{id}" characterId="bob">{body}</bml>'
BEAT = '<gesture id="g1" lexeme="BEAT" mode="RIGHT_HAND"/>'
POSTURE = '<posture id="p1" start="0"><stance type="STANDING"/><pose part="ARMS" lexeme="ARMS_CROSSED"/></posture>'


def humanoid_rigs(contains: str | None = None) -> list[str]:
    """Paths (relative to the wild root) of the humanoid rigs its labels list, sorted."""
    docs = [json.loads(p.read_text()) for p in sorted((WILD / "labels").glob("*.json"))]
    return [d["file"] for d in docs if d["humanoid"] and (contains is None or contains in d["file"])]


def short(rel: str) -> str:
    """A rig's file name and the folder holding it (two rigs of one source share a file name)."""
    return "/".join(Path(rel).parts[-2:])


@dataclass
class RetargetRow:
    """Figures of one clip on one rig (see the module docstring); lengths cm, angles degrees;
    ``pop_frame`` the frame of the written clip where ``pop_joint`` turns most."""

    rig: str
    source: str
    scale: float
    skate_source: float
    skate: float
    skate_limit: float
    bones: float
    penetration: float
    max_penetration: float
    source_max_penetration: float
    float_cm: float
    pop_joint: str
    pop_margin: float
    pop_frame: int
    unreachable: float
    residual_mm: float
    finite: bool
    written_lowest_cm: float
    sole_cm: float = float("nan")

    @property
    def ok(self) -> bool:
        """Within the retargeting targets: finite, skate <= its limit, bones <= 5 degrees, no joint
        past the popping bound, reachable goals met within 1 mm, standing on y = 0 as written."""
        return (self.finite and self.skate <= self.skate_limit and self.bones <= 5.0 and self.pop_margin >= 0.0
                and self.residual_mm <= 1.0 and abs(self.written_lowest_cm) < 0.1)


class Sources:
    """The source clips, each with its asset and mapping (as ``infuse retarget`` maps a motion file), loaded once."""

    def __init__(self, names=tuple(SOURCES)):
        self.clips = {}
        for name in names:
            asset = infuse.load(CORPUS / SOURCES[name])
            self.clips[name] = (next(iter(asset.motions.values())), source_mapping(asset, None, None))


def _ground_depth(asset: infuse.Asset, mapping, motion) -> tuple[np.ndarray, float]:
    """(F, 2) lowest point of each foot over ``motion``'s frames, soles included, and the sole depth (m)."""
    pair = feet(asset.skeleton, mapping)
    g, p = motion_fk(motion)
    depth = sole_depth(asset, pair)
    return lowest_points(asset.skeleton, pair, g, p) - depth, depth


def _above_planted(lowest: np.ndarray, planted: np.ndarray) -> np.ndarray:
    """(F, 2) each foot's lowest point over the level it is planted at (its median while planted, else
    its lowest): a rig's legs may differ in length (an OpenNI capture's by 7 cm)."""
    levels = [np.median(lowest[planted[:, k], k]) if planted[:, k].any() else lowest[:, k].min() for k in (0, 1)]
    return lowest - np.array(levels)


def _sole_below_planted(plan: RetargetPlan, motion, planted: np.ndarray) -> float:
    """cm: the deepest the mesh heel or tip of a foot (``plan.sole_points``, (2, 3) in its ankle's
    frame) goes below the level the foot is planted at (the median over ``planted`` (F, 2) of the
    lowest of its ankle, heel and tip); NaN for a rig whose feet have none."""
    if any(points is None for points in plan.sole_points):
        return float("nan")
    g, p = motion_fk(motion)
    ankles = [f.ankle for f in plan.target.feet]
    sites = p[:, ankles, None] + quat.rotate(g[:, ankles, None], np.stack(plan.sole_points)[None])  # (F, 2, 2, 3)
    low = np.minimum(sites[..., 1].min(axis=2), p[:, ankles, 1])
    levels = [np.median(low[planted[:, k], k]) if planted[:, k].any() else low[:, k].min() for k in (0, 1)]
    return 100.0 * float(max(0.0, -(sites[..., 1] - np.array(levels)[None, :, None]).min()))


def retarget_row(character: infuse.Asset, rel: str, source: str, sources: Sources, out_dir: Path) -> RetargetRow:
    """Retarget ``source`` onto ``character`` as ``infuse retarget`` does, write it, read it back, measure."""
    clip, src_map = sources.clips[source]
    tgt_map = map_skeleton(character)
    plan = RetargetPlan(clip.skeleton, src_map, character.skeleton, tgt_map, source_motion=clip,
                        target_motion=next(iter(character.motions.values()), None), target_meshes=character.meshes)
    q = evaluate(plan, clip)
    result = retarget_clip(plan, clip)
    motion = result.motion.replace(name="retargeted")
    motion = grounded(motion, foot_height(character, tgt_map, motion))
    out = out_dir / f"{short(rel).replace('/', '_')}.{source.replace(' ', '_')}.glb"
    infuse.save(dataclasses.replace(character, motions={"retargeted": motion}), out)
    back = infuse.load(out)
    written = next(iter(back.motions.values()))
    back_map = map_skeleton(back)
    g, p = motion_fk(written)
    lowest, _ = _ground_depth(back, back_map, written)
    planted = result.contacts.foot_flags()
    ground = metrics.ground_contact(_above_planted(lowest, planted), planted, 0.0)
    source_ground = metrics.ground_contact(_above_planted(result.contacts.lowest, planted), planted, 0.0)
    pop = q.popping_final
    j = back_map.indices(back.skeleton).get(pop.worst)
    frame = 0
    if j is not None and len(g) > 1:
        frame = int(np.argmax(quat.angle_between(g[:-1, j], g[1:, j]))) + 1
    return RetargetRow(short(rel), source, q.scale, q.skate_source, q.skate_final, q.skate_limit(), q.bones_final,
                       ground.penetration, ground.max_penetration, source_ground.max_penetration, ground.float, pop.worst, -pop.excess, frame,
                       100.0 * q.unreachable, q.residual_mm, bool(np.isfinite(g).all() and np.isfinite(p).all()),
                       100.0 * float(lowest.min()), _sole_below_planted(plan, written, planted))


@dataclass
class PackRow:
    """What the packs do on one rig (see the module docstring): ``refused`` pack -> reason; the walk's
    ``miss_m``, ``arrival_s`` and ``skate`` (cm/m), NaN without locomotion; ``beat_arm`` /
    ``posture_arm`` how far the wrists moved, % of the arm's length, NaN when not played;
    ``depth_cm`` the deepest a foot went below the level it started at; ``pop_joint`` / ``pop_deg`` /
    ``pop_frame`` the joint turning most in one frame; ``carried_mm`` the farthest a foot hanging outside
    its leg got from its shin's end (NaN where the feet hang from the shins); ``motion`` the scene's
    output, ``mapping`` the rig's."""

    rig: str
    packs: tuple[str, ...]
    refused: dict[str, str] = field(default_factory=dict)
    miss_m: float = float("nan")
    arrival_s: float = float("nan")
    skate: float = float("nan")
    beat_arm: float = float("nan")
    posture_arm: float = float("nan")
    finite: bool = True
    depth_cm: float = float("nan")
    pop_joint: str = ""
    pop_deg: float = float("nan")
    pop_frame: int = 0
    carried_mm: float = float("nan")
    seconds: float = 0.0
    motion: object = None
    mapping: object = None


def _chest_wrists(rig, g: np.ndarray, p: np.ndarray, sides: str) -> np.ndarray:
    """(F, S, 3) the wrists of ``sides`` in the frame of the joint the arm hangs from."""
    out = []
    for s in sides:
        top = rig.joint(f"{s}_acromioclavicular") or rig.joint(f"{s}_shoulder")
        chest = rig.skeleton.parents[top]
        w = rig.joint(f"{s}_wrist")
        out.append(quat.rotate(quat.conjugate(g[:, chest]), p[:, w] - p[:, chest]))
    return np.stack(out, axis=1)


def _arm_length(rig, p: np.ndarray) -> float:
    """The right arm's length (m): shoulder to elbow to wrist in the first frame of (F, J, 3) ``p``."""
    a, b, c = (p[0, rig.joint(f"r_{n}")] for n in ("shoulder", "elbow", "wrist"))
    return float(np.linalg.norm(b - a) + np.linalg.norm(c - b))


def _moved(wrists: np.ndarray, start: int, stop: int, arm: float) -> float:
    """How far (F, S, 3) wrists get from where they were at ``start``, before ``stop``, in % of ``arm``."""
    span = wrists[start:stop]
    return 100.0 * float(np.linalg.norm(span - span[:1], axis=-1).max()) / arm if len(span) else float("nan")


def pack_row(rel: str, cache: Path) -> PackRow:
    """Infuse the built-in packs onto one wild rig, walk, gesture and pose it in a scene, measure the output."""
    start = time.perf_counter()
    asset = infuse.load(WILD / rel)
    mapping = map_skeleton(asset)
    row = PackRow(short(rel), ())
    for pack in PACKS:
        try:
            infuse_character(infuse.Character("bob", asset, mapping), [pack], mapping=mapping, cache=cache)
        except MissingJointsError as exc:
            row.refused[pack] = exc.problem
    row.packs = tuple(p for p in PACKS if p not in row.refused)
    if not row.packs:
        return row
    scene = Scene(fps=FPS, tts=None, quiet=True, idle=False, pack_cache=cache)
    scene.add_character(infuse.Character("bob", asset, mapping), "bob", facing=0.0, packs=row.packs)
    walking = "locomotion-male" in row.packs
    if walking:
        scene.walk_to("bob", TARGET, at=WALK_AT_S)
    scene.run(WALK_S)
    beat_at, posture_at = WALK_S + 0.2, WALK_S + 2.0
    if "gestures" in row.packs:
        scene.bml("bob", BML.format(id="beat", body=BEAT), at=beat_at)
    if "postures" in row.packs:
        scene.bml("bob", BML.format(id="pose", body=POSTURE), at=posture_at)
    scene.run(scene.end_time + 0.5)
    motion = scene.motion("bob")
    rig = scene.runtime.rig("bob")
    g, p = motion_fk(motion)
    row.finite = bool(np.isfinite(g).all() and np.isfinite(p).all())
    walk_end = int(WALK_S * FPS)
    if walking:
        ground = p[:, rig.joint("base")][:, [0, 2]]
        row.miss_m = float(np.linalg.norm(ground[walk_end - int(FPS / 2):walk_end].mean(axis=0) - TARGET))
        away = np.nonzero(np.linalg.norm(ground[:walk_end] - TARGET, axis=-1) > 0.1)[0]
        row.arrival_s = (away[-1] + 1) / FPS if away.size and away[-1] + 1 < walk_end else float("nan")
        walk = motion.replace(local_rotations=motion.local_rotations[:walk_end],
                              root_translations=motion.root_translations[:walk_end],
                              joint_translations=None if motion.joint_translations is None
                              else motion.joint_translations[:walk_end])
        found = foot_contacts(walk, mapping, fk=(g[:walk_end], p[:walk_end]))
        row.skate = metrics.foot_skate(p[:walk_end], found, rig.joint("base")).per_metre
    if "gestures" in row.packs:
        a = int(beat_at * FPS)
        row.beat_arm = _moved(_chest_wrists(rig, g, p, "r"), a, a + int(1.5 * FPS), _arm_length(rig, p))
    if "postures" in row.packs:
        a = int(posture_at * FPS)
        row.posture_arm = _moved(_chest_wrists(rig, g, p, "lr"), a, a + int(3.0 * FPS), _arm_length(rig, p))
    lowest, _ = _ground_depth(asset, mapping, motion)
    row.depth_cm = 100.0 * float(max(lowest[0].min() - lowest.min(), 0.0))
    index = mapping.indices(asset.skeleton)
    names = [n for n in index if not n.startswith(("l_thumb", "l_index", "l_middle", "l_ring", "l_pinky",
                                                     "r_thumb", "r_index", "r_middle", "r_ring", "r_pinky"))]
    turns = np.degrees(quat.angle_between(g[:-1][:, [index[n] for n in names]], g[1:][:, [index[n] for n in names]]))
    f, k = np.unravel_index(int(np.argmax(turns)), turns.shape)
    row.pop_joint, row.pop_deg, row.pop_frame = names[k], float(turns[f, k]), int(f) + 1
    row.carried_mm = _off_shins(rig, g, p)
    row.seconds = time.perf_counter() - start
    row.motion, row.mapping = motion, mapping
    return row


def _off_shins(rig, g: np.ndarray, p: np.ndarray) -> float:
    """mm: the farthest any limb end hanging outside its limb (``rig.carried_limbs``) gets from the end of
    its middle joint's bone over global rotations (F, J, 4) and positions (F, J, 3); NaN without one."""
    limbs = rig.carried_limbs
    if not len(limbs):
        return float("nan")
    offsets = np.stack([carried_offset(rig.skeleton, limb) for limb in limbs])
    ends = p[:, limbs[:, 1]] + quat.rotate(g[:, limbs[:, 1]], offsets)
    return 1000.0 * float(np.linalg.norm(p[:, limbs[:, 2]] - ends, axis=-1).max())


def _fmt(x: float, width: int = 6, digits: int = 2) -> str:
    return f"{x:{width}.{digits}f}" if np.isfinite(x) else f"{'-':>{width}}"


def print_retargeting(rows: list[RetargetRow]) -> None:
    head = (f"{'rig':<42} {'source':<14} {'scale':>5} | {'skate src/out':>13} {'limit':>5} | {'bones':>5} | "
            f"{'pen mean/max (src)':>19} {'float':>5} | {'popping joint':<16} {'margin':>6} {'frame':>5} | "
            f"{'out%':>4} {'IK mm':>5} | {'lowest':>6} {'sole':>5}")
    print(head)
    print("-" * len(head))
    for r in rows:
        print(f"{r.rig[-42:]:<42} {r.source:<14} {r.scale:5.2f} | {r.skate_source:6.2f} {r.skate:6.2f} {r.skate_limit:5.2f} | "
              f"{r.bones:5.2f} | {r.penetration:5.2f} {r.max_penetration:6.2f} {r.source_max_penetration:6.2f} {r.float_cm:5.2f} | {r.pop_joint:<16} "
              f"{r.pop_margin:6.1f} {r.pop_frame:5d} | {r.unreachable:4.0f} {r.residual_mm:5.2f} | {r.written_lowest_cm:6.2f} {_fmt(r.sole_cm, 5)}"
              + ("" if r.finite else "  NON-FINITE") + ("" if r.ok else "  <- misses a target"))


def print_packs(rows: list[PackRow]) -> None:
    head = (f"{'rig':<42} {'packs':<5} | {'miss m':>6} {'arrive':>6} {'skate':>6} | {'beat':>5} {'post':>5} | "
            f"{'depth':>5} | {'largest turn':<16} {'deg':>5} {'frame':>5} | {'shin mm':>7} | {'s':>4}")
    print(head)
    print("-" * len(head))
    for r in rows:
        played = "".join(p[0].upper() if p in r.packs else "." for p in PACKS)
        print(f"{r.rig[-42:]:<42} {played:<5} | {_fmt(r.miss_m, 6, 3)} {_fmt(r.arrival_s, 6, 1)} {_fmt(r.skate)} | "
              f"{_fmt(r.beat_arm, 5, 0)} {_fmt(r.posture_arm, 5, 0)} | {_fmt(r.depth_cm, 5, 1)} | {r.pop_joint:<16} "
              f"{_fmt(r.pop_deg, 5, 1)} {r.pop_frame:5d} | {_fmt(r.carried_mm, 7, 3)} | {r.seconds:4.1f}"
              + ("" if r.finite else "  NON-FINITE"))
    for r in rows:
        for pack, reason in r.refused.items():
            print(f"  {r.rig} refuses {pack}: {reason}")


def print_worst(retargeted: list[RetargetRow], packs: list[PackRow], n: int = 5) -> None:
    def names(rows, key, fmt):
        ranked = sorted((r for r in rows if np.isfinite(key(r))), key=key, reverse=True)[:n]
        return ", ".join(fmt(r) for r in ranked)

    print("\nworst cases")
    print("  retargeting, skate over its limit (cm/m): "
          + names(retargeted, lambda r: r.skate - r.skate_limit, lambda r: f"{r.rig} {r.source} {r.skate - r.skate_limit:+.2f}"))
    print("  retargeting, bone directions (deg): "
          + names(retargeted, lambda r: r.bones, lambda r: f"{r.rig} {r.source} {r.bones:.2f}"))
    print("  retargeting, popping margin (deg): "
          + names(retargeted, lambda r: -r.pop_margin, lambda r: f"{r.rig} {r.source} {r.pop_joint} {r.pop_margin:+.1f} at {r.pop_frame}"))
    print("  retargeting, deepest foot below its planted level (cm): "
          + names(retargeted, lambda r: r.max_penetration, lambda r: f"{r.rig} {r.source} {r.max_penetration:.2f}"))
    print("  retargeting, mesh heel or tip below its planted level (cm): "
          + names(retargeted, lambda r: r.sole_cm, lambda r: f"{r.rig} {r.source} {r.sole_cm:.2f} (source {r.source_max_penetration:.2f})"))
    print("  packs, walk miss (m): " + names(packs, lambda r: r.miss_m, lambda r: f"{r.rig} {r.miss_m:.3f}"))
    print("  packs, walk skate (cm/m): " + names(packs, lambda r: r.skate, lambda r: f"{r.rig} {r.skate:.2f}"))
    print("  packs, foot below its start level (cm): " + names(packs, lambda r: r.depth_cm, lambda r: f"{r.rig} {r.depth_cm:.1f}"))
    print("  packs, foot hanging outside its leg off its shin's end (mm): "
          + names(packs, lambda r: r.carried_mm, lambda r: f"{r.rig} {r.carried_mm:.3f}"))
    failed = [r for r in retargeted if not r.ok]
    refused = sum(len(r.refused) for r in packs)
    print(f"\n{len(retargeted)} retargeted pairs, {len(failed)} miss a target; {len(packs)} rigs infused, "
          f"{refused} pack refusal(s); non-finite: {sum(not r.finite for r in retargeted + packs)}")


def print_summary(retargeted: list[RetargetRow], packs: list[PackRow]) -> None:
    """One Markdown row per rig: the worst figure of its retargeted clips and what the packs did."""
    print("| rig | skate cm/m (limit) | bones deg | popping margin deg | deepest foot cm (source) | packs | "
          "miss m | skate cm/m | beat / posture % arm | depth cm |")
    print("|---|---:|---:|---:|---:|---|---:|---:|---:|---:|")
    for p in packs:
        rows = [r for r in retargeted if r.rig == p.rig]
        over = max(rows, key=lambda r: r.skate / r.skate_limit)
        deep = max(rows, key=lambda r: r.max_penetration)
        played = "".join(k[0].upper() if k in p.packs else "." for k in PACKS)
        print(f"| {p.rig} | {over.skate:.2f} ({over.skate_limit:.2f}) | {max(r.bones for r in rows):.2f} | "
              f"{min(r.pop_margin for r in rows):+.1f} | {deep.max_penetration:.1f} ({deep.source_max_penetration:.1f}) | "
              f"{played} | {_fmt(p.miss_m, 0, 3)} | {_fmt(p.skate, 0, 2)} | {_fmt(p.beat_arm, 0, 0)} / "
              f"{_fmt(p.posture_arm, 0, 0)} | {_fmt(p.depth_cm, 0, 1)} |")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true", help="6 rigs and the Bandai walk only")
    parser.add_argument("--rigs", metavar="TEXT", help="only rigs whose path contains TEXT")
    parser.add_argument("--markdown", action="store_true", help="also a Markdown table, one row per rig")
    args = parser.parse_args(argv)
    for root, what in ((WILD, "INFUSE_WILD"), (CORPUS, "INFUSE_CORPUS")):
        if not (root / "labels").is_dir():
            print(f"{root} not found (set {what})", file=sys.stderr)
            return 2
    rigs = humanoid_rigs(args.rigs)
    if args.quick:
        rigs = [r for r in rigs if any(k in r for k in QUICK)]
    started = time.perf_counter()
    sources = Sources(("bandai walk",) if args.quick else tuple(SOURCES))
    retargeted, infused = [], []
    with tempfile.TemporaryDirectory() as tmp:
        for rel in rigs:
            character = infuse.load(WILD / rel)
            retargeted += [retarget_row(character, rel, s, sources, Path(tmp)) for s in sources.clips]
            infused.append(pack_row(rel, Path(tmp) / "infusions"))
    print(f"retargeting onto {len(rigs)} wild rigs (cm, degrees; lowest: cm, as written)\n")
    print_retargeting(retargeted)
    print(f"\nbehaviour packs (L locomotion-male, G gestures, P postures played): walk to {TARGET} m, a beat, "
          "a posture; miss m, arrival s, skate cm/m, wrist travel % of the arm, depth cm, feet hanging outside "
          "their legs: farthest from their shins' ends, mm\n")
    print_packs(infused)
    print_worst(retargeted, infused)
    if args.markdown:
        print()
        print_summary(retargeted, infused)
    print(f"\n{time.perf_counter() - started:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
