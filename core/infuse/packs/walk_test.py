"""Testing a locomotion pack on a character: what the walks it drives realize, measured on the output.

Every figure comes from forward kinematics of the runtime's output motion (never from the controller's
internals). Walks run side by side as characters of one runtime at 30 fps:

- **speed**: a straight walk asked for each of :data:`SPEEDS` speeds spanning the pack's forward range
  (its slowest to its fastest straight forward example), reached at once; realized speed = the
  pelvis's net horizontal travel from :data:`SETTLE_S` on over the time it took. Foot skate on the same
  walk: :func:`infuse.metrics.foot_skate` (default contact detector), cm per metre walked.
- **drift**: a straight walk of :data:`DRIFT_S` seconds at the pack's walking speed; heading drift =
  change of the facing (from the hips, averaged over :data:`WINDOW_S` windows, which hold whole gait
  cycles) from the first window after :data:`SETTLE_S` to the last, degrees.
- **targets**: walks to points :data:`DISTANCES` metres away at :data:`ANGLES` degrees off the facing
  (+ left); miss = distance of the pelvis (its ground point, averaged over the last half second)
  from the target; path ratio = length of the pelvis's ground path (smoothed over one second, which
  takes out the sway of the gait) over the straight line; turned = how far round that path's
  direction of travel goes, degrees (the range of the unwrapped direction, so a slow walk's sway,
  which one second leaves in the path where a stride takes longer, does not add up; a turn on the
  spot is not on the path); a loop turns more than :data:`LOOP_DEG`; arrival = first time the pelvis stays within 5 cm; foot skate over the
  whole walk (its start, turn on the spot and stop), cm in all, and split over its parts
  (:func:`walk_parts`, walking at 90% of the speed asked or more: on the spot, start, walk, stop,
  settle; each frame-to-frame step counted in the part of the frame it ends at, contacts and planted
  heights those of the whole walk, so the parts add up to the whole).

Angles are degrees in every table (turn rates degrees per second); distances metres, speeds m/s.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from ..contacts import foot_contacts
from ..kinematics import motion_fk
from ..metrics import foot_skate
from .analysis import headings

FPS = 30.0
SPEEDS = 5
SETTLE_S = 1.5
DRIFT_S = 8.0
WINDOW_S = 2.0
DISTANCES = (2.0, 4.0, 6.0)
ANGLES = (0.0, 45.0, 90.0, 135.0, 180.0, -90.0)
#: Walking speed asked of target walks and the drift walk (m/s), within the pack's forward range.
WALK_SPEED = 1.3
#: Within this many metres of its target a walk has arrived.
ARRIVED_M = 0.05
#: A path whose direction of travel goes round more than this (degrees, the range of its unwrapped
#: direction where it moves faster than :data:`MOVING_M_S`) makes a loop.
LOOP_DEG = 270.0
MOVING_M_S = 0.2
#: The parts of a walk to a target whose foot skate is measured apart (:func:`walk_parts`).
PARTS = ("on the spot", "start", "walk", "stop", "settle")
#: Below this pelvis speed (m/s, over :data:`PART_WINDOW_S`) a walk stands or turns on the spot; from
#: :data:`CRUISE` of its top speed on it walks.
STILL_M_S = 0.15
CRUISE = 0.9
PART_WINDOW_S = 0.3


@dataclass
class SpeedTrial:
    asked: float
    realized: float
    skate_cm_m: float

    @property
    def error(self) -> float:
        """Relative error of the realized speed (realized / asked - 1)."""
        return self.realized / self.asked - 1.0


@dataclass
class TargetTrial:
    distance: float
    angle_deg: float
    miss_m: float
    path_ratio: float
    turned_deg: float
    arrival_s: float | None
    skate_cm: float = float("nan")
    #: Foot skate (cm) of each of :data:`PARTS`.
    part_skate_cm: dict = field(default_factory=dict)

    @property
    def loops(self) -> bool:
        return self.turned_deg > LOOP_DEG


@dataclass
class PackTrial:
    """What a pack realizes on a character: speed trials, heading drift (degrees over :data:`DRIFT_S`),
    target trials, the ground paths (x, z) of the target walks for drawing, and output motions to show
    (``"straight"``: the drift walk; ``"target"``: the walk to the farthest target straight behind, or
    the last target) with the character's mapping."""

    pack: str
    character: str
    speeds: list[SpeedTrial] = field(default_factory=list)
    drift_deg: float = float("nan")
    drift_speed: float = float("nan")
    targets: list[TargetTrial] = field(default_factory=list)
    paths: list[np.ndarray] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    motions: dict = field(default_factory=dict)
    mapping: object = None

    def worst(self) -> dict:
        """The worst figure of each measure (speed error as a share, degrees, metres, ratio, cm/m; cm on
        a walk to a target)."""
        return {"speed_error": max((abs(s.error) for s in self.speeds), default=float("nan")),
                "drift_deg": abs(self.drift_deg),
                "miss_m": max((t.miss_m for t in self.targets), default=float("nan")),
                "path_ratio": max((t.path_ratio for t in self.targets), default=float("nan")),
                "loops": sum(t.loops for t in self.targets),
                "skate_cm_m": max((s.skate_cm_m for s in self.speeds), default=float("nan")),
                "target_skate_cm": max((t.skate_cm for t in self.targets), default=float("nan")),
                "part_skate_cm": {part: max((t.part_skate_cm.get(part, 0.0) for t in self.targets), default=float("nan"))
                                  for part in PARTS}}


def forward_speeds(space) -> np.ndarray:
    """(:data:`SPEEDS`,) speeds spanning the forward range of a locomotion blend space: from its slowest
    to its fastest straight forward example (travel within 30 degrees of the facing, turning less than
    30 degrees per second), at least 0.3 m/s (or the fastest, if slower)."""
    t = space.tessellations["locomotion"]
    pts = t.points
    vf, vl, w = pts[:, 0], pts[:, 1], pts[:, 2]
    ahead = (vf > 0.05) & (np.abs(vl) < 0.58 * vf) & (np.abs(w) < math.radians(30.0))
    if not ahead.any():
        return np.zeros(0)
    hi = float(vf[ahead].max())
    lo = min(max(float(vf[ahead].min()), 0.3), hi)  # a character with short legs may walk slower than 0.3 m/s
    return np.linspace(lo, hi, SPEEDS)


def _runtime_walks(character, mapping, space, settings: list[dict], seconds: float):
    """Run one walk per entry of ``settings`` (Locomotion keyword arguments), side by side; returns for
    each its output motion and FK (global rotations, positions), and the runtime's notes."""
    from ..runtime import Runtime, controller

    notes = []
    rt = Runtime(fps=FPS, report=lambda who, message: notes.append(message))
    names = []
    for k, s in enumerate(settings):
        name = rt.add_character(character, name=f"walk{k}", mapping=mapping)
        rt.activate(name, controller("locomotion", pack=space, **s), 0.0)
        names.append(name)
    rt.run(seconds)
    out = []
    for name in names:
        m = rt.motion(name)
        out.append((m, motion_fk(m)))
    return out, notes


def _window_mean(x: np.ndarray, frames: int) -> np.ndarray:
    """Means of (F, ...) ``x`` over a centred sliding window of ``frames``, the ends held (F, ...)."""
    half = frames // 2
    padded = np.concatenate((np.repeat(x[:1], half, axis=0), x, np.repeat(x[-1:], frames - 1 - half, axis=0)))
    c = np.cumsum(np.concatenate((np.zeros((1,) + x.shape[1:]), padded)), axis=0)
    return (c[frames:] - c[:-frames]) / frames


def path_turn_deg(path: np.ndarray) -> float:
    """How far round (degrees) the direction of travel of a ground path (F, 2) metres, sampled at
    :data:`FPS`, goes where it moves faster than :data:`MOVING_M_S`: the range of its unwrapped direction
    (swings to and fro count once, a circle 360 degrees)."""
    step = np.diff(path, axis=0)
    moving = np.linalg.norm(step, axis=-1) > MOVING_M_S / FPS
    tangent = np.unwrap(np.arctan2(step[moving, 0], step[moving, 1])) if moving.any() else np.zeros(1)
    return float(np.degrees(np.ptp(tangent)))


def walk_parts(ground: np.ndarray, cruise: float | None = None) -> np.ndarray:
    """(F,) index into :data:`PARTS` of each frame of a walk to a target, from its pelvis ground path
    (F, 2) metres: before it first moves at :data:`CRUISE` of its top speed, on the spot (slower than
    :data:`STILL_M_S`: standing, or turning on the spot) or starting; after it last does, stopping or
    settling (still again); walking between. Speeds over :data:`PART_WINDOW_S` windows. ``cruise``: the
    walking speed asked (m/s), the top speed where the walk reaches it (a start or stop clip may go
    faster than the walk between them: its steps at the walking speed are walking)."""
    v = np.linalg.norm(np.gradient(_window_mean(ground, max(int(PART_WINDOW_S * FPS), 1)), axis=0), axis=-1) * FPS
    out = np.full(len(v), PARTS.index("walk"))
    if len(v) < 2 or v.max() <= STILL_M_S:
        out[:] = PARTS.index("on the spot")
        return out
    top = v.max() if cruise is None else min(float(v.max()), float(cruise))
    fast = np.nonzero(v >= CRUISE * top)[0]
    still = v < STILL_M_S
    first, last = int(fast[0]), int(fast[-1]) + 1
    out[:first] = np.where(still[:first], PARTS.index("on the spot"), PARTS.index("start"))
    out[last:] = np.where(still[last:], PARTS.index("settle"), PARTS.index("stop"))
    return out


def trial_pack(character, pack, mapping=None, speeds=None, distances=DISTANCES, angles=ANGLES) -> PackTrial:
    """Measure ``pack`` (a name, folder, manifest or :class:`~infuse.packs.BlendSpace`) on ``character``
    (a :class:`~infuse.Character`, asset or file): see the module doc."""
    from .infusion import BlendSpace, as_character, infuse_character

    character = as_character(character)
    if isinstance(pack, BlendSpace):
        space, mapping = pack, mapping or character.mapping
    else:
        infusion = infuse_character(character, [pack], mapping=mapping)
        space, mapping = next(iter(infusion.spaces.values())), infusion.mapping
    if mapping is None:
        from ..mapping import map_skeleton

        mapping = map_skeleton(character.asset)
    character.mapping = mapping
    index = mapping.indices(character.skeleton)
    base = index["base"]
    trial = PackTrial(space.pack, character.name)
    asked = forward_speeds(space) if speeds is None else np.asarray(speeds, dtype=np.float64)
    settle = int(SETTLE_S * FPS)
    if asked.size:
        walks, notes = _runtime_walks(character, mapping, space, [dict(speed=float(v), max_accel=50.0) for v in asked], 5.0)
        trial.notes += notes
        for v, (m, (g_rot, g_pos)) in zip(asked, walks):
            p = g_pos[settle:, base]
            realized = float(np.hypot(*(p[-1] - p[0])[[0, 2]]) / ((len(p) - 1) / FPS))
            found = foot_contacts(m, mapping, fk=(g_rot, g_pos))
            found = replace(found, flags=found.flags[settle:], lowest=found.lowest[settle:])
            skate = foot_skate(g_pos[settle:], found, base).per_metre
            trial.speeds.append(SpeedTrial(float(v), realized, float(skate)))
    walk_speed = float(np.clip(WALK_SPEED, asked.min(), asked.max())) if asked.size else WALK_SPEED
    trial.drift_speed = walk_speed
    window = int(WINDOW_S * FPS)
    targets = [(d, a) for d in distances for a in angles]
    settings: list[dict[str, object]] = [dict(speed=walk_speed, max_accel=50.0)]
    settings += [dict(speed=walk_speed, target=(d * math.sin(math.radians(a)), d * math.cos(math.radians(a))))
                 for d, a in targets]
    longest = max([DRIFT_S + SETTLE_S] + [d / walk_speed + 8.0 for d in distances])
    walks, notes = _runtime_walks(character, mapping, space, settings, longest)
    trial.notes += [n for n in notes if n not in trial.notes]
    trial.mapping = mapping
    trial.motions["straight"] = walks[0][0]
    behind = [k for k, (d, a) in enumerate(targets) if abs(a) == 180.0]
    trial.motions["target"] = walks[1 + (behind[-1] if behind else len(targets) - 1)][0] if targets else None
    _, (_, g_pos) = walks[0]
    facing = _window_mean(np.unwrap(headings(g_pos[:int((DRIFT_S + SETTLE_S) * FPS)], index)), window)
    trial.drift_deg = float(np.degrees(facing[-1 - window // 2] - facing[settle + window // 2]))
    for (d, a), (m, (g_rot, g_pos)) in zip(targets, walks[1:]):
        ground = g_pos[:, base][:, [0, 2]]
        goal = np.array([d * math.sin(math.radians(a)), d * math.cos(math.radians(a))])
        end = ground[-int(FPS / 2):].mean(axis=0)
        smooth = _window_mean(ground, int(FPS))
        path = float(np.linalg.norm(np.diff(smooth, axis=0), axis=-1).sum())
        gap = np.linalg.norm(ground - goal, axis=-1)
        away = np.nonzero(gap > ARRIVED_M)[0]
        arrival = None if gap[-1] > ARRIVED_M else float((away[-1] + 1) / FPS if away.size else 0.0)
        turned = path_turn_deg(smooth)
        found = foot_contacts(m, mapping, fk=(g_rot, g_pos))
        skate = foot_skate(g_pos, found, base).travel
        parts = walk_parts(ground, walk_speed)[1:]  # each step's, by the frame it ends at
        by_part = {part: 100.0 * foot_skate(g_pos, found, base, steps=parts == k).travel for k, part in enumerate(PARTS)}
        trial.targets.append(TargetTrial(d, a, float(np.linalg.norm(end - goal)), path / d, turned, arrival, 100.0 * skate, by_part))
        trial.paths.append(smooth)
    return trial


def report(trial: PackTrial) -> str:
    """A printable report of a :class:`PackTrial`."""
    lines = [f"{trial.pack} on {trial.character}"]
    lines.append("  speed asked -> realized (m/s), error, foot skate (cm/m):")
    for s in trial.speeds:
        lines.append(f"    {s.asked:5.2f} -> {s.realized:5.2f}  {100 * s.error:+6.1f}%  skate {s.skate_cm_m:5.2f}")
    lines.append(f"  heading drift over {DRIFT_S:g} s straight at {trial.drift_speed:.2f} m/s: {trial.drift_deg:+.1f} deg")
    lines.append("  walk to a target: distance (m), angle (deg) -> miss (m), path / straight line, turned (deg), arrival (s), "
                 "foot skate (cm):")
    for t in trial.targets:
        arrival = f"{t.arrival_s:5.1f}" if t.arrival_s is not None else "never"
        flag = "  LOOP" if t.loops else ""
        lines.append(f"    {t.distance:3.0f} {t.angle_deg:+5.0f} -> {t.miss_m:6.3f}  {t.path_ratio:5.2f}  {t.turned_deg:6.0f}  {arrival}  "
                     f"{t.skate_cm:5.1f}{flag}")
    if trial.targets:
        worst = trial.worst()["part_skate_cm"]
        lines.append("  foot skate of the walks to a target by part, worst walk (cm): "
                     + ", ".join(f"{part} {cm:.1f}" for part, cm in worst.items()))
    for note in trial.notes:
        lines.append(f"  note: {note}")
    return "\n".join(lines)


def draw_paths(trial: PackTrial, path, size: int = 640) -> None:
    """A top view (PNG at ``path``) of the target walks: each pelvis ground path (smoothed as measured)
    from the start (the circle, facing up the image, +Z) to its target (a cross; red when missed by
    more than :data:`ARRIVED_M`), a 1 m grid, +X (the character's left) to the left."""
    from PIL import Image, ImageDraw

    goals = [(t.distance * math.sin(math.radians(t.angle_deg)), t.distance * math.cos(math.radians(t.angle_deg)))
             for t in trial.targets]
    pts = np.concatenate([np.zeros((1, 2)), np.array(goals).reshape(-1, 2)] + [p for p in trial.paths])
    lo, hi = pts.min(axis=0) - 0.5, pts.max(axis=0) + 0.5
    scale = (size - 20) / float(max(hi - lo))
    centre = 0.5 * (lo + hi)

    def px(x, z):  # +X (left of the character) drawn to the left, +Z up
        return (size / 2 - (x - centre[0]) * scale, size / 2 - (z - centre[1]) * scale)

    image = Image.new("RGB", (size, size), "white")
    draw = ImageDraw.Draw(image)
    for v in range(int(np.floor(lo.min())), int(np.ceil(hi.max())) + 1):
        draw.line([px(v, lo[1]), px(v, hi[1])], fill=(232, 232, 232))
        draw.line([px(lo[0], v), px(hi[0], v)], fill=(232, 232, 232))
    for t, (gx, gz), p in zip(trial.targets, goals, trial.paths):
        draw.line([px(x, z) for x, z in p], fill=(40, 90, 200) if not t.loops else (200, 120, 0), width=2)
        cx, cz = px(gx, gz)
        colour = (0, 150, 0) if t.miss_m <= ARRIVED_M else (210, 0, 0)
        draw.line([(cx - 6, cz - 6), (cx + 6, cz + 6)], fill=colour, width=2)
        draw.line([(cx - 6, cz + 6), (cx + 6, cz - 6)], fill=colour, width=2)
    ox, oz = px(0.0, 0.0)
    draw.ellipse([ox - 5, oz - 5, ox + 5, oz + 5], outline=(0, 0, 0), width=2)
    draw.line([(ox, oz), (ox, oz - 14)], fill=(0, 0, 0), width=2)
    draw.text((8, 8), f"{trial.pack} on {trial.character}: walks to targets, top view (1 m grid)", fill=(0, 0, 0))
    image.save(path)

