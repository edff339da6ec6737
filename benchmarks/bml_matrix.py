"""Every behaviour element docs/bml.md lists, realized on three characters, measured on the output.

For each behaviour (a row: a small BML block exercising it) and each character (X Bot, the Ready Player
Me avatar, SmartBody's Brad; each infused with the built-in locomotion, reaching, gestures and postures
packs), a scene plays the block; an identical scene without it is the baseline. A cell is

- **realized** when the joints or weights the behaviour should move (its channels: the head's joints,
  the arms', the face's joints and morph weights...; all of them, or some and a warning says why not the
  others) differ from the baseline's by more than
  :data:`ANGLE_DEG` (joint rotations), :data:`SHIFT_M` (joint translations, the pelvis's path) or
  :data:`WEIGHT` (morph weights) within the behaviour's timing (its start, one frame early at most, to its
  end and :data:`AFTER_S` more; to the scene's end when it persists); the figure is the largest difference;
- **warns** when it does not, and warningFeedback about it says why (the text);
- a **failure** otherwise: it neither moves nor says why.

Speech is realized when its audio is heard in its span, and its mouth moves where the character has a
face; ``wait`` when the nod it delays starts at its end; ``event`` when its sync point's feedback comes
at its time.

    python benchmarks/bml_matrix.py [--rows gaze,head] [--characters xbot,rpm] [--write-docs]

``--write-docs`` writes the table into docs/bml.md between its behaviour-matrix markers.
The corpus is read from INFUSE_CORPUS (default ../shared/corpus from the repository root).
"""
from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
CORPUS = Path(os.environ.get("INFUSE_CORPUS", REPO.parent / "shared" / "corpus")).resolve()
DOCS = REPO / "docs" / "bml.md"
BEGIN, END = "<!-- behaviour matrix -->", "<!-- end of behaviour matrix -->"

FPS = 30.0
#: Smallest change of a joint's local rotation counted as movement, degrees.
ANGLE_DEG = 2.0
#: The same for the chest, which breathing turns about a degree.
CHEST_ANGLE_DEG = 0.5
#: Smallest change of a joint's local translation, or of the pelvis's place, counted as movement, metres.
SHIFT_M = 0.002
#: Smallest change of a morph weight counted as movement.
WEIGHT = 0.05
#: Smallest RMS (16-bit samples) of speech counted as heard.
AUDIO_RMS = 100.0
#: Seconds after a behaviour's end still counted as its timing (a blend out).
AFTER_S = 0.6
#: Seconds a scene runs past the end of its block.
TAIL_S = 1.0


@dataclass(frozen=True)
class Cast:
    """A character of the matrix: its file in the corpus and the packs it is infused with."""

    key: str
    label: str
    path: str
    packs: tuple[str, ...]


CAST = (Cast("xbot", "X Bot", "runxaway-models/Xbot.glb", ("locomotion-male", "reaching", "gestures", "postures")),
        Cast("rpm", "RPM avatar", "talkinghead/avatars/brunette-t.glb",
             ("locomotion-female", "reaching", "gestures", "postures")),
        Cast("brad", "SmartBody Brad", "smartbody/ChrBrad/ChrBrad.sk",
             ("locomotion-male", "reaching", "gestures", "postures")))

#: Scene objects, in front of the character (facing +Z; +X its left) as fractions of its head's height:
#: a cup and a shelf within the right hand's reach, a lamp up to the left.
OBJECTS = {"cup": (-0.13, 0.8, 0.19), "shelf": (-0.2, 0.8, 0.15), "lamp": (0.8, 0.95, 1.2)}

BML10 = 'xmlns="http://www.bml-initiative.org/bml/bml-1.0" xmlns:sbm="http://ict.usc.edu"'


@dataclass(frozen=True)
class Row:
    """A behaviour of docs/bml.md: how the table names it, its family, the behaviours of its block (the
    measured one has id ``x``), the channels it should move, the SmartBody dialect or BML 1.0, and BML
    played before it (a grab before a put-down) at 0.3 s; the block starts at :attr:`at_s`, and the scene
    runs :attr:`seconds` from then at least (what persists shows over them). Its timing is the measured
    behaviour's (:attr:`timed_by`: another behaviour of the block, which it delays), or the whole block's
    (:attr:`whole_block`: what a generator adds around it).
    :attr:`block_attributes` go on the ``<bml>`` element (``infuse:`` ones)."""

    name: str
    family: str
    body: str
    channels: tuple[str, ...]
    smartbody: bool = False
    before: str = ""
    at_s: float = 0.5
    seconds: float = 5.0
    whole_block: bool = False
    timed_by: str = "x"
    block_attributes: str = ""


ROWS = (
    Row("speech", "BML 1.0", '<speech id="x"><text>Hello there, nice to meet you.</text></speech>', ("audio", "mouth")),
    Row("gaze", "BML 1.0", '<gaze id="x" target="lamp" influence="HEAD"/>', ("head",)),
    Row("gazeShift", "BML 1.0", '<gazeShift id="x" target="lamp" influence="HEAD"/>', ("head",)),
    Row("headDirectionShift", "BML 1.0", '<headDirectionShift id="x" target="lamp"/>', ("head",)),
    Row("head", "BML 1.0", '<head id="x" lexeme="NOD" repetition="2"/>', ("head",)),
    Row("faceLexeme", "BML 1.0", '<faceLexeme id="x" lexeme="RAISE_BROWS" amount="1"/>', ("face",)),
    Row("faceShift", "BML 1.0", '<faceShift id="x" lexeme="SMILE"/>', ("face",)),
    Row("faceFacs", "BML 1.0", '<faceFacs id="x" au="12" side="BOTH" amount="1"/>', ("face",)),
    Row("posture", "BML 1.0", '<posture id="x"><stance type="STANDING"/><pose part="ARMS" lexeme="HANDS_ON_HIPS"/>'
                              '</posture>', ("body",)),
    Row("postureShift", "BML 1.0", '<postureShift id="x"><stance type="STANDING"/>'
                                   '<pose part="ARMS" lexeme="ARMS_CROSSED"/></postureShift>', ("body",)),
    Row("postureShift (sitting)", "BML 1.0", '<postureShift id="x"><stance type="SITTING"/>'
                                             '<pose part="ARMS" lexeme="HANDS_ON_LAP"/></postureShift>', ("body",)),
    Row("gesture", "BML 1.0", '<gesture id="x" lexeme="BEAT" mode="RIGHT_HAND"/>', ("arms",)),
    Row("pointing", "BML 1.0", '<pointing id="x" target="lamp"/>', ("arms",)),
    Row("locomotion", "BML 1.0", '<locomotion id="x" target="0 1.5" manner="walk"/>', ("path",)),
    Row("wait", "BML 1.0", '<wait id="x" max-wait="1.0"/><head id="n" lexeme="NOD" start="x:end"/>', ("delay",),
        timed_by="n"),
    Row("event", "BML 1.0", '<event id="x" message="hello" start="0.5"/>', ("feedback",)),
    Row("face (SmartBody)", "SmartBody", '<face id="x" type="facs" au="1" side="BOTH" amount="1" end="1.5"/>',
        ("face",), smartbody=True),
    Row("body posture", "SmartBody", '<body id="x" posture="ChrBrad@Idle01_ArmsCrossed01"/>', ("body",),
        smartbody=True),
    Row("greta:torso", "Greta", '<greta:torso id="x" lexeme="BodyRecline"/>', ("body",)),
    Row("animation", "SmartBody", '<animation id="x" name="wave_right"/>', ("arms",), smartbody=True),
    Row("blend", "SmartBody", '<blend id="x" name="walk_turn_left" sbm:wrap-mode="Once"/>', ("body",), smartbody=True),
    Row("sbm:reach touch", "SmartBody", '<sbm:reach id="x" target="cup" sbm:action="touch"/>', ("arms",),
        smartbody=True),
    Row("sbm:reach pick-up", "SmartBody", '<sbm:reach id="x" target="cup" sbm:action="pick-up"/>', ("arms", "object"),
        smartbody=True),
    Row("sbm:reach put-down", "SmartBody", '<sbm:reach id="x" target="shelf" sbm:action="put-down"/>',
        ("arms", "placed"), smartbody=True, before='<sbm:grab id="g" target="cup"/>', at_s=2.5),
    Row("sbm:reach point-at", "SmartBody", '<sbm:reach id="x" target="lamp" sbm:action="point-at"/>', ("arms",),
        smartbody=True),
    Row("sbm:grab", "SmartBody", '<sbm:grab id="x" target="cup"/>', ("arms", "object"), smartbody=True),
    Row("sbm:grab release", "SmartBody", '<sbm:grab id="x" target="cup" sbm:grab-state="release"/>', ("arms",),
        smartbody=True, before='<sbm:grab id="g" target="cup"/>', at_s=2.5),
    Row("touch", "SmartBody", '<touch id="x" target="cup"/>', ("arms",), smartbody=True),
    Row("sbm:constraint", "SmartBody", '<sbm:constraint id="x" effector="r_wrist" target="cup" end="2"/>', ("arms",),
        smartbody=True),
    Row("saccade", "SmartBody", '<saccade id="x" mode="talk"/>', ("eyes",), smartbody=True, seconds=10.0),
    Row("sbm:noise", "SmartBody", '<sbm:noise id="x" joints="skullbase spine3" frequency="1" scale="0.1"/>', ("head",),
        smartbody=True),
    Row("infuse:nonverbal", "infuse", '<speech id="x"><text>I really think this is a good idea, and you will like it.'
                                      '</text></speech>', ("arms", "head"), whole_block=True, block_attributes='infuse:nonverbal="true"'),
    Row("bmlt:blinkemitter", "ASAP", '<bmlt:blinkemitter id="x" avgwaitingtime="0.5" range="0.2"/>', ("eyelids",)),
    Row("bmlt:breathingemitter", "ASAP", '<bmlt:breathingemitter id="x"/>', ("chest",)),
)

_NAMESPACES = {"bmlt": 'xmlns:bmlt="http://hmi.ewi.utwente.nl/bmlt"', "greta": 'xmlns:greta="VIBNameSpace"'}


def document(row: Row, block: str, body: str) -> str:
    """The BML text of one block of ``row`` (SmartBody's ``<act><bml>`` or a BML 1.0 block)."""
    if row.smartbody:
        return f'<act><bml id="{block}">{body}</bml></act>'
    extra = " ".join(ns for prefix, ns in _NAMESPACES.items() if f"<{prefix}:" in body)
    if row.block_attributes:
        extra += f' xmlns:infuse="urn:infuse:bml" {row.block_attributes}'
    return f'<bml {BML10} {extra} id="{block}">{body}</bml>'


# -- characters and scenes ------------------------------------------------------------------------------
@lru_cache(maxsize=None)
def character(key: str):
    """The cast member ``key`` loaded and mapped (once)."""
    import infuse
    from infuse.mapping import map_skeleton

    cast = next(c for c in CAST if c.key == key)
    asset = infuse.load(CORPUS / cast.path)
    return infuse.Character(cast.key, asset, map_skeleton(asset))


def head_height_m(key: str) -> float:
    """Height of the character's head joint (skullbase) in its rest pose, metres."""
    c = character(key)
    return float(c.skeleton.rest_global_positions[c.skeleton.index[c.mapping["skullbase"]], 1])


def scene_for(key: str, cache: str):
    """A scene holding the character ``key`` (named ``c``, infused, no idle defaults) and the objects."""
    from infuse.scene import Scene

    cast = next(c for c in CAST if c.key == key)
    scene = Scene(fps=FPS, quiet=True, idle=False, pack_cache=cache)
    scene.add_character(character(key), "c", packs=cast.packs)
    h = head_height_m(key)
    for name, (x, y, z) in OBJECTS.items():
        scene.add_object(name, (x * h, y * h, z * h), size=0.08)
    return scene


@dataclass
class Cell:
    """One behaviour on one character: ``status`` "realized", "warns" or "fails"; what was measured
    (``figure``), the warningFeedback about it (``warning``)."""

    row: str
    character: str
    status: str
    figure: str = ""
    warning: str = ""

    def text(self) -> str:
        if self.status == "realized":
            return f"realized: {self.figure}" + (f" (warns: {self.warning})" if self.warning else "")
        if self.status == "warns":
            return f"warns: {self.warning}"
        return f"FAILS: {self.figure}"


def play(row: Row, key: str, cache: str):
    """The scene of ``row`` on ``key``, evaluated to its end."""
    scene = scene_for(key, cache)
    if row.before:
        scene.bml("c", document(row, "before", row.before), at=0.3)
    scene.bml("c", document(row, "b", row.body), at=row.at_s)
    scene.run(max(scene.end_time + TAIL_S, row.at_s + row.seconds))
    return scene


def measure(row: Row, key: str, cache: str, baselines: dict) -> Cell:
    """Play ``row`` on ``key`` and compare its output with the baseline's (see the module doc)."""
    scene = play(row, key, cache)
    warnings = [e for e in scene.feedback.log if e.kind == "warningFeedback" and e.id in ("b:x", "b", "c")]
    warning = "; ".join(dict.fromkeys(w.description for w in warnings))
    record = scene.scheduler.blocks["b"]
    activation = next((a for a in record.activations if a.behaviour == row.timed_by), None)
    if activation is None:
        return Cell(row.name, key, "warns" if warning else "fails", "" if warning else "not scheduled, no warning", warning)
    motion = scene.motion("c")
    frames = motion.num_frames
    base = baseline(row, key, cache, frames, baselines)
    begin, finish = (record.start_s, record.end_s) if row.whole_block else (activation.start, activation.end)
    start = int(round(begin * FPS))
    end = frames if activation.persistent else min(frames, int(round((finish + AFTER_S) * FPS)) + 1)
    figures, still = [], []
    for channel in row.channels:
        ok, figure = _channel(channel, key, scene, motion, base, start, end, activation)
        if figure:
            figures.append(figure)
        if not ok:
            still.append(channel)
    if len(still) < len(row.channels) and (not still or warning):  # what did not move, a warning explains
        return Cell(row.name, key, "realized", ", ".join(figures), warning)
    if not warning:
        figures.append(f"{', '.join(still)}: nothing moved, no warning")
    return Cell(row.name, key, "warns" if warning else "fails", ", ".join(figures), warning)


def baseline(row: Row, key: str, cache: str, frames: int, baselines: dict):
    """The character's motion in the same scene without the row's block (with what it plays before), at
    least ``frames`` long."""
    have = baselines.get((key, row.before))
    if have is None or have.num_frames < frames:
        scene = scene_for(key, cache)
        if row.before:
            scene.bml("c", document(row, "before", row.before), at=0.3)
        scene.run(max(frames, int(10 * FPS)) / FPS)
        have = baselines[(key, row.before)] = scene.motion("c")
    return have


# -- channels -------------------------------------------------------------------------------------------
_LEGS = ("hip", "knee", "ankle", "forefoot", "toe")


def joints_of_channel(key: str, channel: str) -> np.ndarray:
    """Indices of the joints of ``channel`` on the character ``key``."""
    c = character(key)
    sk = c.skeleton
    canonical = c.mapping.inverse()
    names = {j: canonical.get(n, "") for j, n in enumerate(sk.names)}
    if channel in ("face", "mouth", "eyelids"):  # below the head: face joints, eyes, jaw
        skull = sk.index[c.mapping["skullbase"]]
        below, parents = {skull}, sk.parents
        for j in range(len(sk.names)):
            p = parents[j]
            while p >= 0 and p not in below:
                p = parents[p]
            if p >= 0:
                below.add(j)
        below.discard(skull)
        return np.array(sorted(below), dtype=np.int64)
    if channel == "eyes":
        return np.array([j for j, n in names.items() if n.startswith("eyeball_")], dtype=np.int64)
    if channel == "head":
        return np.array([j for j, n in names.items() if n == "skullbase" or n.startswith("neck")], dtype=np.int64)
    if channel == "arms":
        return np.array([j for j, n in names.items() if n[:2] in ("l_", "r_") and n.split("_", 1)[1] not in _LEGS
                         ], dtype=np.int64)
    if channel == "chest":
        return np.array([j for j, n in names.items() if n.startswith("spine") or "clavicular" in n], dtype=np.int64)
    return np.array([j for j, n in names.items() if n], dtype=np.int64)  # body: every mapped joint


def _angle_deg(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(F, J) angle between the rotations ``a`` and ``b`` (F, J, 4), degrees."""
    return np.degrees(2.0 * np.arccos(np.clip(np.abs(np.sum(a * b, axis=-1)), 0.0, 1.0)))


def _morphs(channel: str, names) -> np.ndarray:
    """Columns of the morph weights ``channel`` watches (the eyelids: blink shapes; the eyes: look shapes;
    the mouth and face: all)."""
    if channel in ("eyelids", "eyes"):
        word = "blink" if channel == "eyelids" else "look"
        return np.array([i for i, n in enumerate(names) if word in n.lower()], dtype=np.int64)
    if channel in ("face", "mouth"):
        return np.arange(len(names))
    return np.zeros(0, dtype=np.int64)


def _channel(channel, key, scene, motion, base, start, end, activation) -> tuple[bool, str]:
    """Whether ``channel`` of the character ``key`` moved within frames ``start - 1`` .. ``end`` (and not
    before), and the figure."""
    first = max(start - 1, 0)
    if channel == "audio":
        track = scene.audio("c")
        if track is None:
            return False, ""
        samples, rate = track
        span = samples[int(activation.start * rate):int(activation.end * rate)].astype(np.float64)
        rms = float(np.sqrt(np.mean(span ** 2))) if span.size else 0.0
        return rms > AUDIO_RMS, f"audio RMS {rms:.0f}"
    if channel == "feedback":
        got = [e for e in scene.feedback.log if e.kind == "syncPointProgress" and (e.block, e.behaviour) == ("b", "x")]
        if not got:
            return False, ""
        late = abs(float(got[0].global_time) - activation.start)
        return late < 1.0 / FPS, f"syncPointProgress b:x:{got[0].sync} at {float(got[0].global_time):.2f} s"
    if channel == "delay":
        joints = joints_of_channel(key, "head")
        diff = _angle_deg(motion.local_rotations[:, joints], base.local_rotations[:len(motion.local_rotations), joints])
        over = np.nonzero(diff.max(axis=1) > ANGLE_DEG)[0]
        if not over.size:
            return False, ""
        wait_end = next(a.end for a in scene.scheduler.blocks["b"].activations if a.behaviour == "x")
        return over[0] >= int(round(wait_end * FPS)) - 1, f"the nod starts at {over[0] / FPS:.2f} s, the wait ends at {wait_end:.2f} s"
    if channel == "object":
        track = scene.object_track("cup")
        travel = float(np.linalg.norm(track[first:end] - track[first], axis=1).max()) if end > first else 0.0
        return travel > 0.05, f"cup moved {travel * 100:.0f} cm"
    if channel == "placed":  # the cup ends on the shelf
        track = scene.object_track("cup")
        off = float(np.linalg.norm(track[-1] - np.asarray(scene.locate("shelf"))))
        return off < 0.01, f"the cup ends {off * 100:.1f} cm from the shelf"
    if channel == "path":
        from infuse import motion_fk

        rig = scene.runtime.rig("c")
        _, pos = motion_fk(motion)
        _, bpos = motion_fk(base.replace(local_rotations=base.local_rotations[:motion.num_frames],
                                         root_translations=base.root_translations[:motion.num_frames],
                                         joint_translations=None if base.joint_translations is None
                                         else base.joint_translations[:motion.num_frames],
                                         morph_weights=base.morph_weights[:motion.num_frames]))
        pelvis = rig.joint("base")
        gap = np.linalg.norm((pos[:, pelvis] - bpos[:, pelvis])[:, [0, 2]], axis=1)
        return _verdict(gap, first, end, 0.05, "pelvis {:.2f} m from where it stood")
    joints = joints_of_channel(key, channel)
    n = motion.num_frames
    moved, figure = False, ""
    if joints.size:
        diff = _angle_deg(motion.local_rotations[:, joints], base.local_rotations[:n, joints]).max(axis=1)
        moved, figure = _verdict(diff, first, end, CHEST_ANGLE_DEG if channel == "chest" else ANGLE_DEG,
                                 channel + " {:.1f}°")
        if channel != "body" and (motion.joint_translations is not None or base.joint_translations is not None):
            shift = np.linalg.norm(_translations(motion, joints) - _translations(base, joints)[:n], axis=-1).max(axis=1)
            ok, f = _verdict(shift, first, end, SHIFT_M, channel + " {:.1f} mm", 1000.0)
            if ok and not moved:
                moved, figure = ok, f
    columns = _morphs(channel, motion.morph_names)
    if columns.size and motion.morph_weights.size:
        below = _weights(base, [motion.morph_names[i] for i in columns])[:n]
        weights = np.abs(motion.morph_weights[:, columns] - below).max(axis=1)
        ok, f = _verdict(weights, first, end, WEIGHT, channel + " morph weights {:.2f}")
        if ok:
            moved, figure = True, f if not moved else f"{figure}, {f}"
    return moved, figure


def _translations(motion, joints: np.ndarray) -> np.ndarray:
    """(F, len(joints), 3) local translations of ``joints``, metres (the rest offsets where the motion has none)."""
    if motion.joint_translations is not None:
        return motion.joint_translations[:, joints]
    return np.broadcast_to(motion.skeleton.rest_translations[joints], (motion.num_frames, len(joints), 3))


def _weights(motion, names: list[str]) -> np.ndarray:
    """(F, len(names)) the motion's weights of the morph targets ``names`` (0 for those it does not animate)."""
    out = np.zeros((motion.num_frames, len(names)))
    have = {n: i for i, n in enumerate(motion.morph_names)}
    for k, name in enumerate(names):
        if name in have and motion.morph_weights.size:
            out[:, k] = motion.morph_weights[:, have[name]]
    return out


def _verdict(diff: np.ndarray, first: int, end: int, threshold: float, label: str, scale: float = 1.0) -> tuple[bool, str]:
    """Whether ``diff`` (F,) exceeds ``threshold`` within ``first``..``end`` and nowhere before, and the
    largest value there formatted by ``label``."""
    inside = diff[first:end]
    if not inside.size or inside.max() <= threshold:
        return False, ""
    early = diff[:first]
    if early.size and early.max() > threshold:
        return False, "moved before its start"
    return True, label.format(float(inside.max()) * scale)


# -- the whole matrix -----------------------------------------------------------------------------------
def run(rows=ROWS, cast=CAST, verbose: bool = True) -> list[Cell]:
    """Every cell of ``rows`` × ``cast``; printed as they come when ``verbose``."""
    cells = []
    baselines: dict = {}
    with tempfile.TemporaryDirectory(prefix="infuse-bml-matrix-") as cache:
        for row in rows:
            for member in cast:
                started = time.perf_counter()
                try:
                    cell = measure(row, member.key, cache, baselines)
                except Exception as exc:  # a crash is a failure of that cell; the matrix goes on
                    cell = Cell(row.name, member.key, "fails", f"{type(exc).__name__}: {exc}")
                cells.append(cell)
                if verbose:
                    print(f"{row.name:24s} {member.key:5s} {time.perf_counter() - started:5.1f} s  {cell.text()}",
                          flush=True)
    return cells


def table(cells: list[Cell], rows=ROWS, cast=CAST) -> str:
    """The matrix as a Markdown table: a row per behaviour, a column per character."""
    by = {(c.row, c.character): c for c in cells}
    lines = ["| behaviour | BML | " + " | ".join(m.label for m in cast) + " |",
             "|---|---|" + "---|" * len(cast)]
    for row in rows:
        shown = row.body if not row.block_attributes else f"<bml {row.block_attributes}>{row.body}</bml>"
        shown = shown if not row.before else f"{row.before} then {shown}"
        lines.append(f"| {row.name} | `{shown}` | "
                     + " | ".join(by[(row.name, m.key)].text().replace("|", "/") for m in cast) + " |")
    return "\n".join(lines)


def write_docs(cells: list[Cell]) -> None:
    """Put the table into docs/bml.md between the markers (kept as they are)."""
    text = DOCS.read_text(encoding="utf-8")
    if BEGIN not in text or END not in text:
        raise SystemExit(f"{DOCS}: the markers {BEGIN} and {END} are missing")
    head, rest = text.split(BEGIN, 1)
    _, tail = rest.split(END, 1)
    DOCS.write_text(f"{head}{BEGIN}\n{table(cells)}\n{END}{tail}", encoding="utf-8")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--rows", help="comma-separated row names (default: all)")
    parser.add_argument("--characters", help="comma-separated keys: " + ", ".join(c.key for c in CAST))
    parser.add_argument("--write-docs", action="store_true", help="write the table into docs/bml.md")
    args = parser.parse_args(argv)
    if not (CORPUS / "labels").is_dir():
        raise SystemExit(f"no corpus at {CORPUS} (set INFUSE_CORPUS)")
    rows = ROWS if not args.rows else tuple(r for r in ROWS if r.name in args.rows.split(","))
    cast = CAST if not args.characters else tuple(c for c in CAST if c.key in args.characters.split(","))
    started = time.perf_counter()
    cells = run(rows, cast)
    print(f"\n{sum(c.status == 'realized' for c in cells)} realized, {sum(c.status == 'warns' for c in cells)} warn, "
          f"{sum(c.status == 'fails' for c in cells)} fail, of {len(cells)} cells ({time.perf_counter() - started:.0f} s)")
    print(table(cells, rows, cast))
    if args.write_docs:
        if rows != ROWS or cast != CAST:
            raise SystemExit("--write-docs needs the whole matrix")
        if any(c.status == "fails" for c in cells):
            raise SystemExit("docs/bml.md not written: some cells fail")
        write_docs(cells)
    return 0 if all(c.status != "fails" for c in cells) else 1


if __name__ == "__main__":
    sys.exit(main())
