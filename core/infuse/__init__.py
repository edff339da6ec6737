"""infuse: turn any humanoid 3D model into an animated character.

Conventions, stated once for the whole package: metres and seconds; right-handed axes with +Y up
and +Z the character's forward (+X its left); quaternions (x, y, z, w), scalar last.

The names below are imported on first use, so ``import infuse`` (and ``infuse --version``) does not
load numpy, scipy or any plugin; submodules (``infuse.registry``, ``infuse.runtime``...) load the
same way. :mod:`infuse.api` lists what plugins may import.
"""
from __future__ import annotations

import importlib

__version__ = "0.1.0"

#: Public name -> the submodule that defines it.
_EXPORTS: dict[str, str] = {
    "Asset": "asset", "Character": "asset",
    "InfuseError": "errors", "InputError": "errors", "MissingFeatureError": "errors", "NotHumanoidError": "errors",
    "UnsupportedFormatError": "errors", "UnusableInputError": "errors", "UsageError": "errors",
    "load": "fileio", "save": "fileio",
    "hookimpl": "hookspecs",
    "batch_fk": "kinematics", "forward_kinematics": "kinematics", "motion_fk": "kinematics",
    "Motion": "motion",
    "Skeleton": "skeleton",
}

__all__ = [*_EXPORTS, "__version__"]


def __getattr__(name: str):
    module = _EXPORTS.get(name)
    if module is not None:
        value = getattr(importlib.import_module(f"{__name__}.{module}"), name)
        globals()[name] = value
        return value
    try:
        return importlib.import_module(f"{__name__}.{name}")
    except ModuleNotFoundError as exc:
        if exc.name != f"{__name__}.{name}":
            raise
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
