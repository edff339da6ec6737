"""The gaze model as data: joint groups, their limits, smoothing and speeds, and what influence reaches.

Groups, bottom to top, with SmartBody's canonical joints. Limits are degrees (heading, pitch up,
pitch down, roll) for the whole group; the joints of a group share it equally. The cervical limits of
the published model (45 / 45 / 90 / 35 over spine4, spine5 and skullbase, a third each) are split
here into the neck (two thirds: spine4, spine5) and the head (one third: skullbase), so a neck with
fewer joints still reaches as far. The eyes are two joints side by side, each with the full limit.

Smoothing per frame: s = 0.01 + (1 - smooth^(dt*30)) * 0.99 of the distance left (smooth 0: instant).
Speeds are degrees per second of the group's rotation (the neck and head share the head's 180 deg/s
in the proportion of their limits).
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np


@dataclass(frozen=True)
class GroupSettings:
    """One joint group: canonical ``joints``; limits in degrees; ``smooth`` in [0, 1); ``speed_deg_s``."""

    name: str
    joints: tuple[str, ...]
    heading_deg: float
    up_deg: float
    down_deg: float
    roll_deg: float
    smooth: float
    speed_deg_s: float

    def with_changes(self, **changes) -> "GroupSettings":
        return replace(self, **changes)

    @property
    def limits_rad(self) -> np.ndarray:
        """(heading, up, down, roll) in radians."""
        return np.radians([self.heading_deg, self.up_deg, self.down_deg, self.roll_deg])


GROUPS: tuple[GroupSettings, ...] = (
    # WHOLE turns the pelvis (and everything on it) about the vertical.
    GroupSettings("body", ("base",), 180.0, 0.0, 0.0, 0.0, 0.6, 60.0),
    GroupSettings("lumbar", ("spine1", "spine2"), 30.0, 15.0, 15.0, 10.0, 0.6, 60.0),
    GroupSettings("thoracic", ("spine3",), 15.0, 6.0, 6.0, 5.0, 0.6, 60.0),
    GroupSettings("cervical", ("spine4", "spine5"), 60.0, 30.0, 30.0, 70.0 / 3.0, 0.5, 120.0),
    GroupSettings("head", ("skullbase",), 30.0, 15.0, 15.0, 35.0 / 3.0, 0.5, 60.0),
    GroupSettings("eyes", ("eyeball_left", "eyeball_right"), 40.0, 35.0, 35.0, 0.0, 0.0, 1000.0),
)
GROUP_NAMES: tuple[str, ...] = tuple(g.name for g in GROUPS)
EYES = GROUP_NAMES.index("eyes")

#: BML influence -> the groups that move (eyes always do).
INFLUENCES: dict[str, tuple[str, ...]] = {
    "EYES": ("eyes",),
    "HEAD": ("cervical", "head", "eyes"),
    "SHOULDER": ("thoracic", "cervical", "head", "eyes"),
    "WAIST": ("lumbar", "thoracic", "cervical", "head", "eyes"),
    "WHOLE": ("body", "lumbar", "thoracic", "cervical", "head", "eyes"),
}
DEFAULT_INFLUENCE = "WAIST"

#: Other names of the groups (SmartBody's sbm:joint-range and priority-joint words, BML influence words).
GROUP_ALIASES: dict[str, str] = {
    "BODY": "body", "PELVIS": "body", "BACK": "lumbar", "LUMBAR": "lumbar", "WAIST": "lumbar", "CHEST": "thoracic",
    "THORAX": "thoracic", "THORACIC": "thoracic", "SHOULDER": "thoracic", "NECK": "cervical", "CERVICAL": "cervical",
    "HEAD": "head", "SKULL": "head", "SKULLBASE": "head", "CRANIAL": "head", "EYES": "eyes", "EYE": "eyes",
    "OPTICAL": "eyes", "EYEBALL": "eyes",
}

#: Chain slots the solver works on, bottom to top (canonical joints); each slot's parent slot (-1: the
#: world); each slot's group. The eyes are the last two slots, side by side on the head.
SLOTS: tuple[str, ...] = ("base", "spine1", "spine2", "spine3", "spine4", "spine5", "skullbase", "eyeball_left", "eyeball_right")
SLOT_PARENTS: tuple[int, ...] = (-1, 0, 1, 2, 3, 4, 5, 6, 6)
SLOT_GROUPS: tuple[int, ...] = tuple(next(i for i, g in enumerate(GROUPS) if s in g.joints) for s in SLOTS)
#: Slots by what they are: the head's, the eyes' (left, right) and the neck's.
HEAD_SLOT = SLOTS.index("skullbase")
EYE_SLOTS: tuple[int, int] = (SLOTS.index("eyeball_left"), SLOTS.index("eyeball_right"))
NECK_SLOTS: tuple[int, ...] = tuple(s for s, g in enumerate(SLOT_GROUPS) if GROUP_NAMES[g] == "cervical")

#: Offset directions (BML offsetDirection) as polar angles in degrees: 0 = the character's right, 90 = up.
OFFSET_DIRECTIONS: dict[str, float] = {
    "RIGHT": 0.0, "UPRIGHT": 45.0, "UP": 90.0, "UPLEFT": 135.0, "LEFT": 180.0, "DOWNLEFT": 225.0, "DOWN": 270.0,
    "DOWNRIGHT": 315.0,
}


def group_name(word: str) -> str:
    """The group a word names (``"NECK"`` -> ``"cervical"``); ValueError for an unknown word."""
    key = word.strip()
    if key.lower() in GROUP_NAMES:
        return key.lower()
    if key.upper() in GROUP_ALIASES:
        return GROUP_ALIASES[key.upper()]
    raise ValueError(f"unknown gaze joint group {word!r}; known: {', '.join(GROUP_NAMES)}")


def smoothing_factor(smooth, dt: float) -> np.ndarray:
    """Share of the remaining distance covered in one frame of ``dt`` seconds (SmartBody's formula)."""
    smooth = np.clip(np.asarray(smooth, dtype=np.float64), 0.0, 0.999999)
    return 0.01 + (1.0 - smooth ** (dt * 30.0)) * 0.99
