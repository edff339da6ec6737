"""What a gaze keeps per character: its binding to the character's chain, and the turn between blocks.

Arrays are over the chain's S slots (:data:`~infuse_gaze.model.SLOTS`, pelvis to eyes) and the G joint
groups (:data:`~infuse_gaze.model.GROUPS`); angles are (heading, pitch) radians in aligned frames.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from infuse.errors import MissingJointsError
from infuse.runtime.pose import ancestors

from .model import EYE_SLOTS, EYES, GROUP_NAMES, GROUPS, HEAD_SLOT, INFLUENCES, NECK_SLOTS, SLOT_GROUPS, SLOT_PARENTS, SLOTS


@dataclass(frozen=True, eq=False)
class GazeBinding:
    """One gaze bound to one character.

    - ``slot_joints`` (S,): each slot's joint index, -1 where the character lacks it; ``present`` (S,) bool;
    - ``counts`` (G,): the joints each group has (the eyes count 1: they turn side by side);
    - ``active`` (G,) bool: the groups that move; ``fractions`` (G,): the share of the turn left that
      each takes (1 from the priority group up);
    - ``eyes_lead``: the eyes point exactly at the target (else the head does);
    - ``chain_aligned`` (S, 4): each slot's aligned frame (an absent slot repeats its parent's; the
      world's is the body frame);
    - ``columns`` (K,): the joints from the root to the present slots, for the chain's kinematics;
    - ``slot_source`` (S,): each slot's joint among the present ones (an absent slot takes its
      parent's; -1: the world).
    """

    slot_joints: np.ndarray
    present: np.ndarray
    counts: np.ndarray
    active: np.ndarray
    fractions: np.ndarray
    eyes_lead: bool
    chain_aligned: np.ndarray
    columns: np.ndarray
    slot_source: np.ndarray
    _weights: tuple[np.ndarray, np.ndarray] = field(init=False, repr=False)  # origin, lead (see __post_init__)

    @property
    def joints(self) -> np.ndarray:
        """(P,) the joints of the present slots, bottom to top: the joints the gaze turns."""
        return self.slot_joints[self.present]

    def __post_init__(self):
        # What the weights below are made of, worked out once: the gaze's chains are stacked again each
        # time the gazes of a group change (read-only: every caller reads them).
        origin = np.zeros(len(SLOTS))
        origin[list(EYE_SLOTS) if self.has_eyes else HEAD_SLOT] = 1.0
        origin /= origin.sum()
        lead = origin
        if not self.eyes_lead:
            lead = np.zeros(len(SLOTS))
            lead[HEAD_SLOT] = 1.0
        origin.flags.writeable = lead.flags.writeable = False
        object.__setattr__(self, "_weights", (origin, lead))

    @property
    def has_eyes(self) -> bool:
        return bool(self.present[list(EYE_SLOTS)].all())

    def origin_weights(self) -> np.ndarray:
        """(S,) weights of the slots whose mean is where the gaze starts: the eyes, else the head."""
        return self._weights[0]

    def lead_weights(self) -> np.ndarray:
        """(S,) weights of the slots whose mean forward axis the gaze points: the eyes when they lead,
        else the head."""
        return self._weights[1]


def bind_chain(rig, moving: tuple[str, ...], priority_group: str, report: Callable[[str], None]) -> GazeBinding:
    """The :class:`GazeBinding` of a gaze moving the groups ``moving`` with ``priority_group`` pointing at
    the target, on runtime character ``rig``; what the character lacks is reported (``report``), and
    :class:`~infuse.errors.MissingJointsError` raised when it cannot gaze at all."""
    slot_joints = np.array([rig.joint(s) if rig.joint(s) is not None else -1 for s in SLOTS])
    present = slot_joints >= 0
    eyes = list(EYE_SLOTS)
    has_eyes = bool(present[eyes].all())
    if present[eyes].any() and not has_eyes:
        report("only one eye is mapped; gaze leaves the eyes still")
        present[eyes] = False
        slot_joints[eyes] = -1
    if not present[HEAD_SLOT] and not has_eyes:
        if not present[list(NECK_SLOTS)].any():
            raise MissingJointsError(rig.name, "cannot gaze: neither eyes nor a head or neck joint is mapped")
        report("no head joint is mapped; gaze points the neck")
    counts = np.array([sum(present[s] for s in range(len(SLOTS)) if SLOT_GROUPS[s] == g) for g in range(len(GROUPS))])
    counts[EYES] = 1 if has_eyes else 0
    available = {GROUP_NAMES[g] for g in range(len(GROUPS)) if counts[g] > 0}
    chosen = [g for g in moving if g in available]
    if "eyes" in moving and not has_eyes:
        report("has no eyes: gaze turns the head and spine instead")
        if moving == ("eyes",):
            chosen = [g for g in INFLUENCES["HEAD"] if g in available]
    if not chosen:
        raise MissingJointsError(rig.name, f"none of the gaze groups {', '.join(moving)} is mapped")
    priority = GROUP_NAMES.index(priority_group)
    ranks = [GROUP_NAMES.index(g) for g in chosen]
    if priority not in ranks:  # the nearest moving group below it, else the lowest above it
        below = [r for r in ranks if r < priority]
        priority = max(below) if below else min(ranks)
    active = np.zeros(len(GROUPS), dtype=bool)
    active[ranks] = True
    fractions = np.ones(len(GROUPS))
    p_rank = sum(1 for r in ranks if r < priority)
    for r in ranks:
        if r <= priority:
            i_rank = sum(1 for q in ranks if q < r)
            fractions[r] = 1.0 / (p_rank + 1 - i_rank)
    # An absent slot repeats its parent slot, aligned frame included (the world's is the body frame).
    chain_aligned = np.empty((len(SLOTS), 4))
    for s, parent in enumerate(SLOT_PARENTS):
        if present[s]:
            chain_aligned[s] = rig.aligned[slot_joints[s]]
        else:
            chain_aligned[s] = chain_aligned[parent] if parent >= 0 else rig.body
    # Each slot's joint among the present ones (an absent slot takes its parent's; -1: the world).
    source = np.full(len(SLOTS), -1)
    for s, parent in enumerate(SLOT_PARENTS):
        source[s] = np.count_nonzero(present[:s]) if present[s] else (source[parent] if parent >= 0 else -1)
    return GazeBinding(slot_joints=slot_joints, present=present, counts=counts, active=active, fractions=fractions,
                       eyes_lead=bool(priority == EYES and has_eyes), chain_aligned=chain_aligned,
                       columns=np.array(ancestors(rig.skeleton, slot_joints[present])), slot_source=source)


def _zero_turns(rows: int) -> Callable[[], np.ndarray]:
    return lambda: np.zeros((rows, 2))


@dataclass
class GazeState:
    """A character's gaze turn between blocks, whichever of its gazes leads (one look at a time): the
    (heading, pitch) offsets, radians, that the smoothing carries on from.

    - ``groups`` (G, 2): each group's; ``eyes`` (2, 2): each eye's (left, right);
    - ``first`` (G, 2): the groups' in the first pass of a block where characters look at each other's
      faces, which smooths its own way (:func:`~infuse_gaze.solver.solve`).
    """

    groups: np.ndarray = field(default_factory=_zero_turns(len(GROUPS)))
    eyes: np.ndarray = field(default_factory=_zero_turns(len(EYE_SLOTS)))
    first: np.ndarray = field(default_factory=_zero_turns(len(GROUPS)))
