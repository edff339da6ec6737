"""Gaze and reach targets drawn by the viewer, read from a JSON sidecar ``<stem>.targets.json``.

The file is one object, target name -> a fixed point or a track (metres, core frame: +Y up, +Z the
character's front)::

    {
      "door":       [0.0, 1.0, 2.0],
      "gaze":       {"position": [0.4, 1.6, 1.5]},
      "reach_left": {"times": [0.0, 1.0, 2.0],
                     "positions": [[0.3, 1.0, 0.4], [0.4, 1.2, 0.5], [0.3, 1.0, 0.4]],
                     "from": "l_wrist"}
    }

- ``times`` in seconds on the clip's timeline, strictly increasing; ``positions`` one [x, y, z]
  per time. The page interpolates linearly and holds the first/last position outside the track.
- ``kind`` (optional): ``"gaze"``, ``"reach"`` or ``"point"``; by default a name starting with
  ``gaze`` is a gaze target, one starting with ``reach`` a reach target, anything else a point.
- ``from`` (optional): a canonical joint name; the page draws a line from that joint to the
  target. Gaze targets default to ``"skullbase"``.
"""
from __future__ import annotations

import json
import math
from pathlib import Path

from infuse.canonical import is_canonical
from infuse.errors import InputError

KINDS = ("gaze", "reach", "point")
SUFFIX = ".targets.json"


def sidecar_for(model: Path) -> Path:
    """Where the targets of ``model`` are looked for: ``<folder>/<stem>.targets.json``."""
    return model.with_name(model.stem + SUFFIX)


def _point(value, file, place) -> list[float]:
    if not isinstance(value, list) or len(value) != 3:
        raise InputError(file, place, "expected a point [x, y, z] in metres")
    for v in value:
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
            raise InputError(file, place, "expected three finite numbers [x, y, z]")
    return [float(v) for v in value]


def parse_targets(doc, file: str | Path = "<targets>") -> list[dict]:
    """Validate a targets document; returns ``[{name, kind, from, times, positions}]`` (a fixed
    point becomes a one-key track at time 0). Malformed input raises :class:`InputError`."""
    if not isinstance(doc, dict):
        raise InputError(file, None, "expected an object {target name: [x, y, z] or {times, positions}}")
    out = []
    for name, spec in doc.items():
        if isinstance(spec, list):
            spec = {"position": spec}
        if not isinstance(spec, dict):
            raise InputError(file, name, "expected [x, y, z], {\"position\": ...} or {\"times\": ..., \"positions\": ...}")
        unknown = set(spec) - {"position", "times", "positions", "kind", "from"}
        if unknown:
            raise InputError(file, f"{name}.{sorted(unknown)[0]}", "unknown key (expected position, times, positions, kind, from)")
        if "position" in spec:
            if "times" in spec or "positions" in spec:
                raise InputError(file, name, "give either position or times and positions, not both")
            times, positions = [0.0], [_point(spec["position"], file, f"{name}.position")]
        else:
            times, positions = spec.get("times"), spec.get("positions")
            if not isinstance(times, list) or not isinstance(positions, list) or not times:
                raise InputError(file, name, "a track needs non-empty lists times and positions")
            if len(times) != len(positions):
                raise InputError(file, name, f"{len(times)} times but {len(positions)} positions")
            for k, t in enumerate(times):
                if isinstance(t, bool) or not isinstance(t, (int, float)) or not math.isfinite(t):
                    raise InputError(file, f"{name}.times[{k}]", "expected a finite number of seconds")
                if k and t <= times[k - 1]:
                    raise InputError(file, f"{name}.times[{k}]", "times must be strictly increasing")
            times = [float(t) for t in times]
            positions = [_point(p, file, f"{name}.positions[{k}]") for k, p in enumerate(positions)]
        default_kind = next((k for k in ("gaze", "reach") if name.lower().startswith(k)), "point")
        kind = spec.get("kind", default_kind)
        if kind not in KINDS:
            raise InputError(file, f"{name}.kind", f"expected one of {', '.join(KINDS)}")
        joint = spec.get("from", "skullbase" if kind == "gaze" else None)
        if joint is not None and (not isinstance(joint, str) or not is_canonical(joint)):
            raise InputError(file, f"{name}.from", f"{joint!r} is not a canonical joint name")
        out.append({"name": str(name), "kind": kind, "from": joint, "times": times, "positions": positions})
    return out


def read_targets(path: str | Path) -> list[dict]:
    """Read and validate a targets sidecar (see the module doc)."""
    path = Path(path)
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise InputError(path, None, "targets file not found") from None
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise InputError(path, None, f"not a JSON targets file: {exc}") from None
    return parse_targets(doc, path)


def to_file_frame(targets: list[dict], facing_turned: bool) -> list[dict]:
    """Positions in the glTF scene's frame: a model the reader turned to face +Z (VRM 0.x faces -Z,
    ``Asset.facing_turned``) is shown unturned, so its targets turn 180 degrees about +Y with it."""
    if not facing_turned:
        return targets
    return [dict(t, positions=[[-x, y, -z] for x, y, z in t["positions"]]) for t in targets]
