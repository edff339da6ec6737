"""FACS action units and facial lexemes (smile, frown, surprise, raised brows, blink...) on a character.

An expression is a lexeme name (``"smile"``), an action unit (``"AU12"`` or ``"12"``) or a mix
``{"AU6": 0.5, "AU12": 1.0}``. :func:`expression_targets` maps it onto what the character offers
(``expressions.toml``): a lexeme's direct entry for a vocabulary the character has (VRM's "happy",
SmartBody's "112_happy" pose) wins; otherwise each action unit goes to the first vocabulary, in
:data:`AU_VOCABULARY_ORDER`, that both has an entry for it and is offered by the character.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from infuse.errors import UsageError

from .channels import FaceChannels
from .tables import expressions_table

AU_VOCABULARY_ORDER = ("arkit", "smartbody_facs", "vrm_expressions", "oculus", "vrm", "jaw")


@dataclass(frozen=True)
class Expression:
    """An expression held from ``start_s`` to ``end_s`` at ``intensity`` (0..1), eased in and out over ``ramp_s``."""

    name: str | dict
    intensity: float = 1.0
    start_s: float = 0.0
    end_s: float = float("inf")
    ramp_s: float = 0.25


def action_units(expression) -> dict[str, float]:
    """``{AU: intensity}`` of a lexeme, an action unit or a mix (raises :class:`UsageError` if unknown)."""
    table = expressions_table()
    if isinstance(expression, dict):
        out = {}
        for au, w in expression.items():
            out.update({k: v * float(w) for k, v in action_units(au).items()})
        return out
    name = str(expression).strip()
    key = name if name.upper().startswith("AU") else f"AU{name}"
    if key.upper() in {k.upper() for k in table["action_units"]}:
        return {next(k for k in table["action_units"] if k.upper() == key.upper()): 1.0}
    if name.lower() in table["lexemes"]:
        return dict(table["lexemes"][name.lower()].get("action_units", {}))
    raise UsageError(f"unknown expression {name!r}; lexemes: {', '.join(table['lexemes'])}; action units: "
                     f"{', '.join(table['action_units'])}")


def expression_targets(expression, face: FaceChannels, intensity: float = 1.0, direct: bool = True) -> dict[str, float]:
    """Target (morph target, VRM expression, face pose or the jaw joint) -> weight for ``expression``.
    ``direct=False`` goes through the action units even where the character has the lexeme's own
    expression (whole-face expressions have no sides: a one-sided request needs the action units)."""
    table = expressions_table()
    channels: dict[tuple[str, str], float] = {}
    lexeme = table["lexemes"].get(str(expression).lower()) if not isinstance(expression, dict) else None
    own = [v for v in AU_VOCABULARY_ORDER if v in lexeme and _offers(face, v, lexeme[v])] if direct and lexeme else []
    if lexeme and own:
        for c, w in lexeme[own[0]].items():
            channels[(own[0], c)] = channels.get((own[0], c), 0.0) + w
    else:
        for au, level in action_units(expression).items():
            spec = table["action_units"][au]
            vocab = next((v for v in AU_VOCABULARY_ORDER if v in spec and _offers(face, v, spec[v])), None)
            if vocab is None:
                continue
            for c, w in spec[vocab].items():
                channels[(vocab, c)] = channels.get((vocab, c), 0.0) + w * level
    targets: dict[str, float] = {}
    for (vocab, c), w in channels.items():
        if vocab == "jaw":
            binds = [] if face.jaw is None else [(face.jaw, 1.0)]
        else:
            binds = face.vocabularies[vocab].get(c, [])
        for target, bw in binds:
            targets[target] = min(1.0, targets.get(target, 0.0) + w * bw * intensity)
    return targets


def _offers(face: FaceChannels, vocabulary: str, channels: dict) -> bool:
    """Whether the character binds any of ``channels`` of ``vocabulary`` (a vocabulary found by a few of its
    names, VRM's "happy" and "sad" read as SmartBody's, may lack the others)."""
    if vocabulary == "jaw":
        return face.jaw is not None
    bound = face.vocabularies.get(vocabulary, {})
    return any(bound.get(c) for c in channels)


def envelope(times: np.ndarray, start_s: float, end_s: float, ramp_s: float) -> np.ndarray:
    """(K,) 0..1: eases in (smoothstep) over ``ramp_s`` from ``start_s``, out over ``ramp_s`` before ``end_s``."""
    r = max(ramp_s, 1e-9)
    up = np.clip((times - start_s) / r, 0.0, 1.0)
    down = np.clip((end_s - times) / r, 0.0, 1.0)
    x = np.minimum(up, down)
    return x * x * (3.0 - 2.0 * x)


def expression_tracks(expressions: list[Expression], face: FaceChannels, times: np.ndarray) -> dict[str, np.ndarray]:
    """Target -> (K,) weights of the ``expressions`` over ``times`` (summed, clipped to 0..1)."""
    out: dict[str, np.ndarray] = {}
    end = float(times[-1]) if len(times) else 0.0
    for e in expressions:
        env = envelope(times, e.start_s, min(e.end_s, end), e.ramp_s)
        for target, w in expression_targets(e.name, face, e.intensity).items():
            out[target] = np.clip(out.get(target, 0.0) + w * env, 0.0, 1.0)
    return out
