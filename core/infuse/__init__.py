"""infuse: turn any humanoid 3D model into an animated character.

Conventions, stated once for the whole package: metres and seconds; right-handed axes with +Y up
and +Z the character's forward (+X its left); quaternions (x, y, z, w), scalar last.
"""
from __future__ import annotations

__version__ = "0.1.0"

from .asset import Asset, Character  # noqa: E402
from .errors import (  # noqa: E402
    InfuseError, InputError, MissingFeatureError, NotHumanoidError, UnsupportedFormatError, UnusableInputError, UsageError,
)
from .fileio import load, save  # noqa: E402
from .hookspecs import hookimpl  # noqa: E402
from .kinematics import batch_fk, forward_kinematics, motion_fk  # noqa: E402
from .motion import Motion  # noqa: E402
from .skeleton import Skeleton  # noqa: E402

__all__ = [
    "Asset", "Character", "InfuseError", "InputError", "MissingFeatureError", "NotHumanoidError",
    "UnsupportedFormatError", "UnusableInputError", "UsageError", "load", "save", "hookimpl",
    "batch_fk", "forward_kinematics", "motion_fk", "Motion", "Skeleton", "__version__",
]
