"""``infuse pack build FOLDER``: analyse a pack's clips and store the results in the pack.

Writes the manifest's analysis file (JSON: mapping, per-clip contacts, steps, cycles, keys and
parameters, the tessellations, a validation report and a fingerprint of the files) and an ``.npz``
beside it holding the skeleton and clip arrays. See :mod:`infuse.packs.analysis` for what is measured.
"""
from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from .. import __version__, fileio
from ..atomic import atomic_path
from ..contacts import feet
from ..errors import UnusableInputError
from ..kinematics import batch_fk
from ..mapping import map_skeleton
from .analysis import analyse_clip, blend_groups, coordinates_of, headings, locomotion_parameters, resolution_of
from .coverage import coverage, describe_coverage
from .cuts import without_cuts
from .denoise import denoised
from .cycles import (STRAIGHTEN_DEG_S, alignment, close_loop, closest_loop_end, stands_still, straighten, strides,
                     transition_kind)
from .manifest import read_manifest
from .order import content_order
from .pack import FORMAT_VERSION, Pack, fingerprint, load_clip, on_skeleton
from .tessellation import Tessellation

#: A looping clip whose last frame turns a joint more than this from its first (degrees) does not loop.
LOOP_TOLERANCE_DEG = 12.0
#: A take holding no full stride is one stride recorded as a loop (Bandai's runs and dashes: its last
#: frame within 0-12 degrees of its first on every joint below the pelvis) unless its ends differ by
#: more than this (degrees): a start's or stop's legs stand at one end and walk at the other (50 degrees).
ONE_STRIDE_LOOP_DEG = 25.0


def loop_gap(motion, base: int) -> float:
    """The largest turn (degrees) of a joint below the pelvis ``base`` from a motion's first frame to its last."""
    from .. import quaternions as quat

    rot = motion.local_rotations
    return float(np.degrees(quat.angle_between(rot[0, base + 1:], rot[-1, base + 1:])).max()) if len(rot) > 1 else 0.0


def validate(kind: str, clips: list[dict], motions: dict, tessellations: dict, base: int) -> list[str]:
    """Problems worth a person's attention, one sentence each (empty when all is well)."""
    problems = []
    for c in clips:
        m = motions[c["name"]]
        if c["loop"] and m.num_frames > 2:
            # The pelvis and above carry the facing; below it, a loop's last frame repeats its first.
            ang = loop_gap(m, base)
            if ang > LOOP_TOLERANCE_DEG:
                problems.append(f"{c['name']}: marked as a loop but its last frame differs from its first by {ang:.0f} deg")
        if kind == "locomotion" and c["role"] == "cycle" and not c["steps"]:
            problems.append(f"{c['name']}: no foot steps found")
        for note in c.get("notes", []):
            problems.append(f"{c['name']}: {note}")
    for group, t in tessellations.items():
        if len(t["labels"]) < 2:
            problems.append(f"blend space {group!r} has fewer than two examples")
    return problems


def usable_cycles(entries, motions: dict, clips: list[dict], fks: list, index: dict[str, int], mapping) -> None:
    """Make a locomotion pack's recorded clips usable as blend examples, in place (:mod:`.cycles`):
    transitions recognized by what they do (``transition``; a take given as a cycle that is one, or
    that holds no full stride and does not loop as a whole, is not blended; a loop is a cycle as given), cycles straightened, aligned with their travel and closed, then analysed again on
    the same stride. Each change is in the clip's ``derived`` record and ``motions`` holds the result."""
    for i, (entry, info) in enumerate(zip(entries, clips)):
        if info["role"] not in ("cycle", "other") or (info["loop"] and info["role"] == "cycle"):
            if info["role"] == "cycle":
                _derive(entry, info, i, motions, clips, fks, index, mapping)
            continue
        g_pos = fks[i][1]
        what = transition_kind(np.asarray(info["contacts"], dtype=bool).T, g_pos[:, index["base"]], headings(g_pos, index),
                               info["fps"], info["leg_length"], len(info["steps"]))
        if what is not None:
            info["transition"] = what
            if info["role"] == "cycle":
                info["role"] = "other"
                info["notes"].append("no foot steps: not locomotion, not blended" if what == "none"
                                     else f"a {what}, not a steady cycle: not blended")
            continue
        gap = loop_gap(motions[entry.name], index["base"])
        if info["role"] == "cycle" and not strides(info["steps"]) and gap > ONE_STRIDE_LOOP_DEG:
            info["role"] = "other"
            info["notes"].append(f"no full stride and its ends differ by {gap:.0f} deg (not one stride looping): not blended")
        elif info["role"] == "cycle":
            _derive(entry, info, i, motions, clips, fks, index, mapping)
    _find_idle(motions, clips, fks, index)


def _find_idle(motions: dict, clips: list[dict], fks: list, index: dict[str, int]) -> None:
    """A pack given no idle takes the longest take that stands still throughout (:func:`.cycles.stands_still`)
    as its idle, closed into a loop: a third party's folder names no roles. In place, as :func:`usable_cycles`."""
    if any(c["role"] == "idle" for c in clips):
        return
    hands = [index[k] for k in ("l_wrist", "r_wrist") if k in index]
    soles = [index[k] for k in ("l_ankle", "r_ankle", "l_forefoot", "r_forefoot") if k in index]
    rank = {n: k for k, n in enumerate(content_order(motions))}
    standing = [i for i, c in enumerate(clips) if c.get("transition") == "none" and hands
                and stands_still(np.asarray(c["contacts"], dtype=bool).T, fks[i][1][:, index["base"]], fks[i][1][:, hands],
                                 fks[i][1][:, soles], c["fps"], c["leg_length"])]
    if not standing:
        return
    i = max(standing, key=lambda k: (clips[k]["frames"], -rank[clips[k]["name"]]))
    info = clips[i]
    motion, gap = close_loop(motions[info["name"]], (0, info["frames"] - 1))
    motions[info["name"]] = motion
    fks[i] = batch_fk([motion])[0]
    root, heading = fks[i][1][:, index["base"]], headings(fks[i][1], index)
    info.update(role="idle", loop=True, cycle=[0, info["frames"] - 1], keys=[0.0, info["duration"] / 2.0, info["duration"]],
                parameters=locomotion_parameters(root, heading, (0, info["frames"] - 1), info["fps"]),
                derived={"closed_deg": gap})
    info.pop("transition")
    info["notes"] = [n for n in info["notes"] if "not locomotion" not in n and "uniform keys" not in n]
    info["notes"].append("stands still throughout (both feet down, the hands near the body): the pack's idle")


def _derive(entry, info: dict, i: int, motions: dict, clips: list[dict], fks: list, index: dict[str, int], mapping) -> None:
    """Straighten, align and close cycle ``i`` (see :func:`usable_cycles`); a low-passed take's cycle
    ends on the frame, within its low-pass's reach, whose pose comes nearest its first."""
    p, cycle = info["parameters"], tuple(info["cycle"])
    motion = motions[entry.name]
    end = closest_loop_end(motion.local_rotations, cycle, info.get("low_passed_frames", 1) - 1)
    if end != cycle[1]:
        left, right = info["keys"][:2]  # a stride from right strike to right strike ends on its right key
        right = end / info["fps"] if abs(right * info["fps"] - cycle[1]) < 0.5 else right
        cycle = (cycle[0], end)
        info["keys"] = [left, right, left + (end - cycle[0]) / info["fps"]]
        info["parameters"] = p = locomotion_parameters(fks[i][1][:, index["base"]], headings(fks[i][1], index), cycle, info["fps"])
    turn = p["turn_rate"] if abs(np.degrees(p["turn_rate"])) < STRAIGHTEN_DEG_S else 0.0
    align = alignment(p["direction"])
    derived: dict[str, float] = {}
    if turn or align:
        motion = straighten(motion, p, cycle, turn, align)
        derived.update(straightened_deg_s=float(np.degrees(turn)), aligned_deg=float(np.degrees(align)))
    motion, gap = close_loop(motion, cycle, p["turn_rate"] - turn)
    derived["closed_deg"] = gap
    fks[i] = batch_fk([motion])[0]
    again = analyse_clip(motion, entry, "locomotion", index, mapping, fks[i], cycle=(cycle, info["keys"]))
    if align:  # closing turned the root back by part of its gap: align the closed cycle with its travel again
        motion = straighten(motion, again["parameters"], cycle, 0.0, alignment(again["parameters"]["direction"]))
        fks[i] = batch_fk([motion])[0]
        again = analyse_clip(motion, entry, "locomotion", index, mapping, fks[i], cycle=(cycle, info["keys"]))
    motions[entry.name] = motion
    again["notes"] = info["notes"] + again["notes"]
    again["derived"] = derived
    clips[i] = again


def build_pack(folder, mapper: str | None = None) -> Pack:
    """Analyse the pack at ``folder`` (or its manifest path) and write its analysis; returns the built :class:`Pack`."""
    manifest = read_manifest(folder)
    digest, records = fingerprint(manifest)
    skeleton_asset = fileio.load(manifest.skeleton) if manifest.skeleton.suffix.lower() != ".skm" else None
    motions = {}
    for entry in manifest.clips:
        m = load_clip(entry.file, manifest.skeleton)
        if skeleton_asset is None:
            skeleton_asset = fileio.load(entry.file)
        motions[entry.name] = m
    if skeleton_asset is None:
        raise UnusableInputError(manifest.path, "no clips to read the skeleton of its .skm skeleton file with")
    skeleton = skeleton_asset.skeleton
    motions = {n: on_skeleton(m, skeleton, manifest.clip(n).file).replace(name=n) for n, m in motions.items()}
    dropped: dict[str, tuple[int, int]] = {}
    if manifest.kind == "locomotion":  # a capture's calibration frames at a take's ends are no motion
        for n, m in motions.items():
            motions[n], cut_start, cut_end = without_cuts(m)
            if cut_start or cut_end:
                dropped[n] = (cut_start, cut_end)
    first = motions[content_order(motions)[0]]
    # A rest pose that does not stand (bone-along-one-axis rigs) is mapped on a clip frame (of the
    # clip first by content, so the mapping does not depend on the clips' names or order).
    mapping = map_skeleton(skeleton_asset if skeleton_asset.motions else skeleton_asset.__class__(
        skeleton_asset.path, skeleton_asset.format, skeleton, {first.name: first}), mapper=mapper or "heuristic")
    index = mapping.indices(skeleton)
    missing = [n for n in ("base", "l_hip", "r_hip", "l_knee", "r_knee", "l_ankle", "r_ankle") if n not in index]
    if missing:
        raise UnusableInputError(manifest.path, f"the pack skeleton lacks {', '.join(missing)} after mapping")
    fks = batch_fk(list(motions.values()))
    clips = [analyse_clip(motions[e.name], e, manifest.kind, index, mapping, fk) for e, fk in zip(manifest.clips, fks)]
    for info in clips:
        if info["name"] in dropped:
            cut_start, cut_end = dropped[info["name"]]
            info["notes"].append(f"cut away: {cut_start} frames at its start, {cut_end} at its end (a jump to another pose)")
    if manifest.kind == "locomotion":  # noisy takes low-passed: cycles close and transitions play on poses
        pair = feet(skeleton, mapping, manifest.path)
        for k, info in enumerate(clips):
            motions[info["name"]], half = denoised(motions[info["name"]], pair)
            if half > 1:  # measured again on the poses; its contacts and steps stay those found through the noise
                fks[k] = batch_fk([motions[info["name"]]])[0]
                root, heading = fks[k][1][:, index["base"]], headings(fks[k][1], index)
                info["parameters"] = locomotion_parameters(root, heading, tuple(info["cycle"]), info["fps"])
                info["low_passed_frames"] = half
                info["notes"].append(f"noisy: low-passed over {2 * half + 1} frames")
    if manifest.kind == "locomotion":
        usable_cycles(manifest.clips, motions, clips, fks, index, mapping)
    coords = coordinates_of(manifest.kind)
    tessellations = {}
    rank = {n: k for k, n in enumerate(content_order(motions))}
    for group, members in blend_groups(manifest.kind, clips).items():
        members = sorted(members, key=lambda c: rank[c["name"]])  # examples by content, not by file name
        if members:
            t = Tessellation.build(coords, [c["name"] for c in members], [[c["parameters"][k] for k in coords] for c in members],
                                   resolution=resolution_of(manifest.kind))
            tessellations[group] = t.to_dict()
    report = validate(manifest.kind, clips, motions, tessellations, index["base"])
    covered = coverage(Tessellation.from_dict(tessellations["locomotion"])) if "locomotion" in tessellations else None
    doc = fileio.json_ready({
        "format": FORMAT_VERSION, "pack": manifest.name, "version": manifest.version, "kind": manifest.kind,
        "built_with": __version__, "fingerprint": digest, "files": records,
        "mapping": {"joints": mapping.mapped(), "confidence": {k: mapping.confidence[k] for k in mapping.mapped()},
                    "mapper": mapping.mapper},
        "coordinates": list(coords), "clips": clips, "tessellations": tessellations, "report": report,
        **({"coverage": covered} if covered else {}),
    }, digits=6)
    names = list(motions)
    bounds = np.cumsum([0] + [motions[n].num_frames for n in names])
    arrays: dict[str, Any] = dict(names=np.array(skeleton.names), parents=skeleton.parents, rest_translations=skeleton.rest_translations,
                  rest_rotations=skeleton.rest_rotations, end_site_parents=skeleton.end_site_parents,
                  end_site_offsets=skeleton.end_site_offsets, bounds=bounds,
                  rotations=np.concatenate([motions[n].local_rotations for n in names]),
                  roots=np.concatenate([motions[n].root_translations for n in names]))
    if any(motions[n].joint_translations is not None for n in names):
        arrays["joint_translations"] = np.concatenate([motions[n].local_translations() for n in names])
    npz = manifest.analysis.with_suffix(".npz")
    with atomic_path(npz) as tmp:
        with open(tmp, "wb") as f:
            np.savez_compressed(f, **arrays)
    with atomic_path(manifest.analysis) as tmp:
        Path(tmp).write_text(json.dumps(doc, indent=1) + "\n", encoding="utf-8")
    return Pack(manifest, doc)


def summary(pack: Pack) -> str:
    """A printable summary of a built pack: clips with their parameters, the tessellations, the report."""
    doc = pack.require_built()
    lines = [f"{pack.name} {pack.version} ({pack.kind}): {len(doc['clips'])} clips, mapped by {doc['mapping']['mapper']}"]
    for c in doc["clips"]:
        p = c["parameters"]
        if pack.kind == "locomotion":
            steps = len(c["steps"])
            lines.append(f"  {c['name']:<28} {c['role']:<6} speed {p['speed']:5.2f} m/s  dir {np.degrees(p['direction']):7.1f} deg  "
                         f"turn {np.degrees(p['turn_rate']):7.1f} deg/s  cycle {p['duration']:.2f} s  steps {steps}  "
                         f"keys {', '.join(f'{k:.2f}' for k in c['keys'])}")
            made = c.get("derived") or {}
            if made:
                done = [f"made straight (a {made['straightened_deg_s']:+.1f} deg/s turn taken out)"] if made.get("straightened_deg_s") else []
                done += [f"travel aligned by {made['aligned_deg']:+.1f} deg"] if made.get("aligned_deg") else []
                lines.append("    " + ", ".join(done + [f"loop closed ({made['closed_deg']:.0f} deg at most)"]))
            if c.get("transition"):
                lines.append(f"    does: {c['transition'] if c['transition'] != 'none' else 'no locomotion'}")
        elif pack.kind == "posture":
            lines.append(f"  {c['name']:<28} {c['role']:<7} {'loop' if c['loop'] else 'once'} {c['duration']:.2f} s  "
                         f"tags {', '.join(c['tags'])}")
        elif pack.kind == "gesture":
            lines.append(f"  {c['name']:<28} {c['hand'] or '':<5} " + "  ".join(f"{k} {v:.2f}" for k, v in c["sync"].items())
                         + f"  end {c['duration']:.2f} s")
        else:
            lines.append(f"  {c['name']:<40} {c['role']:<6} {c['hand'] or '':<5} stroke {c.get('stroke', 0):.2f} s  "
                         f"wrist ({p['x']:+.2f}, {p['y']:+.2f}, {p['z']:+.2f}) m")
    for group, t in pack.tessellations().items():
        lines.append(f"  blend space {group}: {t.describe()}")
    if doc.get("coverage"):
        lines += ["  " + line for line in describe_coverage(doc["coverage"])]
    for problem in doc["report"]:
        lines.append(f"  check: {problem}")
    if not doc["report"]:
        lines.append("  check: all clips pass")
    return "\n".join(lines)
