"""Small helpers shared by the handlers: reading attribute values and building timing models."""
from __future__ import annotations

import math

from infuse.bml import BehaviourError, TimingModel

TRUE_WORDS = {"true", "1", "yes", "on"}


class Notes(list):
    """Warnings collected while building one behaviour."""


def number(behaviour, names, default: float, notes: Notes, minimum: float | None = None,
           maximum: float | None = None) -> float:
    """A float attribute (first of ``names`` present), or ``default`` with a note when it is not a number or out of range."""
    names = (names,) if isinstance(names, str) else tuple(names)
    text = behaviour.attribute(*names)
    if text is None:
        return default
    try:
        value = float(text)
    except ValueError:
        notes.append(f"{names[0]}={text!r} is not a number" + ("" if math.isnan(default) else f"; {default:g} is used"))
        return default
    if not math.isfinite(value) or (minimum is not None and value < minimum) or (maximum is not None and value > maximum):
        notes.append(f"{names[0]}={text!r} is out of range" + ("" if math.isnan(default) else f"; {default:g} is used"))
        return default
    return value


def optional_number(behaviour, names, notes: Notes, minimum: float | None = None,
                    maximum: float | None = None) -> float | None:
    """Like :func:`number`, but None when the attribute is absent or unusable."""
    value = number(behaviour, names, float("nan"), notes, minimum, maximum)
    return None if math.isnan(value) else value


def flag(behaviour, names, default: bool = False) -> bool:
    names = (names,) if isinstance(names, str) else tuple(names)
    text = behaviour.attribute(*names)
    return default if text is None else text.strip().lower() in TRUE_WORDS


def word(behaviour, names, default: str | None = None) -> str | None:
    """A trimmed string attribute, or ``default``."""
    names = (names,) if isinstance(names, str) else tuple(names)
    text = behaviour.attribute(*names)
    return default if text is None or not text.strip() else text.strip()


def floats(text: str, count: int | None = None) -> list[float] | None:
    """Space or comma separated numbers; None when any is not a number (or the count differs)."""
    try:
        values = [float(v) for v in text.replace(",", " ").split()]
    except ValueError:
        return None
    return values if count is None or len(values) == count else None


def require(value, message: str):
    if value is None:
        raise BehaviourError(message)
    return value


def with_sbm(*names: str) -> set[str]:
    """Each name both plain and with the ``sbm:`` prefix (SmartBody writes either)."""
    return {n for name in names for n in (name, f"sbm:{name}")}


def clip_model(context, name: str | None, default: dict, speed: float = 1.0) -> tuple[TimingModel, str]:
    """Timing from a behaviour pack's clip when one is known, else ``default``; both divided by ``speed``.

    Returns the model and where its timing came from (``"clip"`` or ``"default"``).
    """
    points = context.clip_timing(name) if name else None
    source = "clip"
    if not points or "end" not in points:
        points, source = default, "default"
    points = dict(points)
    points.setdefault("start", 0.0)
    return TimingModel.from_points({k: v / speed for k, v in points.items()}), source
