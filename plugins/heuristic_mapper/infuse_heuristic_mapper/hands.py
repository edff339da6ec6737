"""Fingers: which chains below a wrist are the thumb, index, middle, ring and pinky.

The thumb is named or numbered first, else the chain that leaves the hand at an angle, whose
knuckle lies off the row of the other knuckles and that starts near the wrist, when it clearly
scores above the rest; the other fingers are matched to the digits across the palm from the thumb. Metacarpal and
palm joints (a first bone that starts at the wrist) are not finger joints. A hand without an
identifiable thumb and at least two other fingers (a mitten) keeps its fingers unmapped, and so does
a stylized hand of fewer than five digits whose thumb is not named (which digit is missing cannot
be told); fingers named each as one finger keep their names.
"""
from __future__ import annotations

import numpy as np

from .matching import best_matching
from .view import SkeletonView, length, lengths

FINGER_ORDER = ("index", "middle", "ring", "pinky")
_NOT_FINGER = ("prop", "control", "secondary", "face")


def _finger_roots(view: SkeletonView, roots: list[int], wrist_pos: np.ndarray, depth: int = 0) -> list[int]:
    """Chain starts of the fingers: a joint parenting several chains (a palm) is replaced by them."""
    out: list[int] = []
    for r in roots:
        info = view.info[r]
        if info.flagged(*_NOT_FINGER):
            continue
        kids = [c for c in view.children[r] if not view.info[c].flagged(*_NOT_FINGER) and view.size[c] >= 2]
        if depth < 2 and len(kids) >= 2:
            out.extend(_finger_roots(view, kids, wrist_pos, depth + 1))
        else:
            out.append(r)
    return out


def _trim(view: SkeletonView, chain: list[int]) -> list[int]:
    """Drop end/nub leaves (not real joints) from the tip of a finger chain."""
    while len(chain) > 1 and view.info[chain[-1]].flagged("end") and not view.children[chain[-1]]:
        chain = chain[:-1]
    return chain


def _drop_metacarpal(view: SkeletonView, chain: list[int], wrist_pos: np.ndarray) -> list[int]:
    """A finger starts at its knuckle: leading helper, metacarpal and palm joints are dropped, and a
    first joint that starts at the wrist (a metacarpal by position) too."""
    while len(chain) > 1:
        first = view.info[chain[0]]
        if first.flagged("metacarpal", "helper") or first.has("palm") or _coincides_with_child(view, chain[0]):
            chain = chain[1:]
        else:
            break
    if len(chain) < 2:
        return chain
    tip = view.P[view.far[chain[0]]]
    reach = length(tip - wrist_pos)
    if reach > 1e-9 and length(view.P[chain[0]] - wrist_pos) < 0.3 * reach:
        return chain[1:]
    return chain


def _drop_helpers(view: SkeletonView, chain: list[int]) -> list[int]:
    """A thumb starts at its first real joint: leading helper joints (named so, or sitting exactly
    where their only child is) are dropped."""
    while len(chain) > 1 and (view.info[chain[0]].flagged("helper") or _coincides_with_child(view, chain[0])):
        chain = chain[1:]
    return chain


def _coincides_with_child(view: SkeletonView, j: int) -> bool:
    kids = view.children[j]
    return len(kids) == 1 and view.bone[kids[0]] < 1e-4 * view.scale


def assign_fingers(view: SkeletonView, roots: list[int], wrist_pos: np.ndarray) -> tuple[dict[str, list[int]], str]:
    """Finger name -> chain joints (finger segments 1..4), and a note. Empty when unidentifiable."""
    starts = _finger_roots(view, roots, wrist_pos)
    chains = {r: _trim(view, view.main_chain(r, 6)) for r in starts}
    chains = {r: c for r, c in chains.items() if c and not (len(c) == 1 and view.info[c[0]].flagged("end"))
              and not all(view.info[j].flagged("helper") for j in c)}  # a lone helper is no digit
    if sum(len(c) >= 2 for c in chains.values()) >= 2:  # jointed digits: a lone joint beside them is a prop or helper
        chains = {r: c for r, c in chains.items() if len(c) >= 2}
    if len(chains) < 3:
        return _few_digits(view, chains, wrist_pos)
    tips = np.array([view.P[view.far[r]] for r in chains])
    dirs = tips - wrist_pos
    norms = np.linalg.norm(dirs, axis=1, keepdims=True)
    dirs = dirs / np.maximum(norms, 1e-9)
    keys = list(chains)
    # thumb: named, else the chain that diverges most from the others and starts nearest the wrist
    named = [r for r in keys if view.info[r].has("thumb")]
    numbered = _numbered_thumb(view, keys)
    thumb = None
    if len(named) == 1:
        thumb, why = named[0], "named thumb"
    elif numbered is not None:
        thumb, why = numbered, "lowest-numbered finger (thumb)"
    elif len(keys) < 5:
        return {}, f"{len(keys)} digits and none named thumb: a stylized hand, digits left unmapped"
    else:
        score = _thumb_scores(view, [chains[r] for r in keys], dirs, wrist_pos)
        i = int(np.argmax(score))
        if score[i] - np.partition(score, -2)[-2] >= THUMB_MARGIN:
            thumb, why = keys[i], "the digit that diverges, off the knuckles' row, next to the wrist (thumb)"
    if thumb is None:
        return {}, "no thumb can be told apart: digits left unmapped"
    others = [r for r in keys if r != thumb]
    if len(others) < 2:
        return {}, "a thumb and a single finger (mitten): digits left unmapped"
    out = {"thumb": _drop_helpers(view, chains[thumb])[:4]}
    for name, r in _order_fingers(view, thumb, others, wrist_pos, dirs.mean(axis=0)):
        out[name] = _drop_metacarpal(view, chains[r], wrist_pos)[:4]
    return out, why


#: How much better the likeliest thumb must score than the next digit (see :func:`_thumb_scores`).
THUMB_MARGIN = 0.25


def _thumb_scores(view: SkeletonView, chains: list[list[int]], dirs: np.ndarray, wrist_pos: np.ndarray) -> np.ndarray:
    """(D,) how much each of D >= 5 digit chains looks like the thumb, from three facts of a hand in
    any pose: the thumb's direction from the wrist diverges from the others' (1 per 30 degrees),
    its knuckle lies off the row the other knuckles make (1.5 per width of that row) and it starts
    nearer the wrist (1 for the whole difference to the farthest knuckle). ``dirs``: (D, 3) unit
    directions from the wrist to each digit's tip."""
    knuckles = np.array([view.P[_drop_metacarpal(view, chain, wrist_pos)[0]] for chain in chains])
    count = len(chains)
    diverge = np.zeros(count)
    off_row = np.zeros(count)
    for i in range(count):
        rest = np.delete(np.arange(count), i)
        mean_dir = dirs[rest].mean(axis=0)
        mean_dir /= max(length(mean_dir), 1e-9)
        diverge[i] = np.degrees(np.arccos(np.clip(float(dirs[i] @ mean_dir), -1.0, 1.0)))
        row = knuckles[rest] - knuckles[rest].mean(axis=0)
        along = np.linalg.svd(row, full_matrices=False)[2][0]  # the knuckles' row direction
        width = max(float(np.ptp(row @ along)), 1e-9)
        offset = knuckles[i] - knuckles[rest].mean(axis=0)
        off_row[i] = length(offset - (offset @ along) * along) / width
    reach = lengths(knuckles - wrist_pos)
    return diverge / 30.0 + 1.5 * off_row + (1.0 - reach / max(float(reach.max()), 1e-9))


def _few_digits(view: SkeletonView, chains: dict[int, list[int]], wrist_pos: np.ndarray) -> tuple[dict[str, list[int]], str]:
    """One or two digit chains: a named thumb is kept; beside it a single-joint "fingers" segment
    (CMU) is the index; a second chain of several joints makes a mitten, left unmapped. Without a
    thumb, fingers each named as one finger keep their names."""
    thumbs = [r for r in chains if view.info[r].has("thumb")]
    if not thumbs:
        # a numbered finger name (HandMiddle1), not a word for part of the hand (MiddleHand)
        named = {r: view.info[r].roles & set(FINGER_ORDER) if view.info[r].numbers else set() for r in chains}
        if chains and all(len(v) == 1 for v in named.values()) and len({min(v) for v in named.values()}) == len(chains):
            return ({min(named[r]): _drop_metacarpal(view, chains[r], wrist_pos)[:4] for r in chains},
                    "fingers named, no thumb")
    if len(thumbs) != 1:
        return {}, f"{len(chains)} digit chain(s) and no named thumb: digits left unmapped"
    thumb = thumbs[0]
    others = [r for r in chains if r != thumb]
    if not others:
        return {"thumb": _drop_helpers(view, chains[thumb])[:4]}, "a thumb and no other finger"
    finger = _drop_metacarpal(view, chains[others[0]], wrist_pos)
    if len(finger) == 1:
        return {"thumb": _drop_helpers(view, chains[thumb])[:4], "index": finger}, \
            "a thumb and one segment for all fingers"
    return {}, "a thumb and a single finger (mitten): digits left unmapped"


def _numbered_thumb(view: SkeletonView, keys: list[int]) -> int | None:
    """Biped/MakeHuman style "finger0..4" or "finger1..5": the lowest first number is the thumb."""
    nums = []
    for r in keys:
        info = view.info[r]
        if not info.has("finger") or not info.numbers or info.roles & {"index", "middle", "ring", "pinky", "thumb"}:
            return None
        nums.append(info.numbers[0])
    ordered = sorted(nums)
    if len(nums) != 5 or ordered != list(range(ordered[0], ordered[0] + 5)):
        return None
    return keys[int(np.argmin(nums))]


#: Finger matching costs: per step between a chain's place across the palm and a digit's, and for a
#: chain named as that digit (negative) or as another one.
ACROSS_STEP = 0.5
MATCHED_CHAINS = 6  # chains matched at most (a hand with many digit-like chains: hair, straps, claws)
NAMED_DIGIT = -2.0
NAMED_OTHER = 2.0


def _order_fingers(view: SkeletonView, thumb: int, others: list[int], wrist_pos: np.ndarray,
                   axis: np.ndarray) -> list[tuple[str, int]]:
    """(finger name, chain start) of the non-thumb fingers: one least-cost matching of the chains to
    the digits index..pinky, from each chain's place across the palm counted from the thumb side
    and its name (a hand without a ring finger keeps its named pinky); chains past the fourth from
    the thumb may stay unmatched."""
    axis = axis / max(length(axis), 1e-9)
    side = view.P[thumb] - wrist_pos
    side = side - np.dot(side, axis) * axis
    if length(side) < 1e-9:
        side = view.P[view.far[thumb]] - wrist_pos
        side = side - np.dot(side, axis) * axis
    side /= max(length(side), 1e-9)

    # knuckle positions: a finger chain's start, past any metacarpal
    def across(r: int) -> float:
        chain = _drop_metacarpal(view, view.main_chain(r, 6), wrist_pos)
        return float(np.dot(view.P[chain[0]] - wrist_pos, side))
    ordered = sorted(others, key=lambda r: -across(r))  # from the thumb side
    # only chains that could be index..pinky are matched: named ones, then the nearest the thumb
    named_chains = [r for r in ordered if view.info[r].roles & set(FINGER_ORDER)]
    keep = set(named_chains[:MATCHED_CHAINS])
    keep.update([r for r in ordered if r not in keep][:MATCHED_CHAINS - len(keep)])
    ordered = [r for r in ordered if r in keep]
    digits = len(FINGER_ORDER)
    columns = max(digits, len(ordered))  # columns past the pinky: no digit
    cost = np.zeros((len(ordered), columns))
    for rank, r in enumerate(ordered):
        cost[rank, :digits] = ACROSS_STEP * np.abs(rank - np.arange(digits))
        cost[rank, digits:] = ACROSS_STEP * max(0, digits - rank)
        named = view.info[r].roles & set(FINGER_ORDER)
        if len(named) == 1:
            role = next(iter(named))
            cost[rank, :digits] += [NAMED_DIGIT if f == role else NAMED_OTHER for f in FINGER_ORDER]
    columns_of, _ = best_matching(cost)
    return [(FINGER_ORDER[c], r) for r, c in zip(ordered, columns_of.tolist()) if c < digits]
