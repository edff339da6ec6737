"""The data tables of the package (``data/*.toml``), loaded once and checked.

- ``visemes.toml``: common phoneme -> viseme class, dominance per class, and the viseme sets.
- ``names.toml``: how face channels are recognised from morph target / expression / pose names.
- ``expressions.toml``: FACS action units and facial lexemes -> channels of each vocabulary.
"""
from __future__ import annotations

import tomllib
from dataclasses import dataclass
from functools import lru_cache
from importlib import resources

import numpy as np

from infuse.speech import common_phonemes

#: Viseme sets in the order detection prefers them.
VISEME_SETS = ("oculus", "arkit", "vrm", "smartbody", "smartbody_diphone", "jaw")


def _load(name: str) -> dict:
    return tomllib.loads(resources.files("infuse_lipsync").joinpath(f"data/{name}").read_text(encoding="utf-8"))


@dataclass(frozen=True)
class VisemeSet:
    """One viseme set: its ``channels`` and, per common phoneme, the target ``(C,)`` (rows of ``targets``,
    in ``phonemes`` order); ``rest`` and ``closure`` are the silence and bilabial poses."""

    name: str
    description: str
    channels: tuple[str, ...]
    phonemes: tuple[str, ...]
    targets: np.ndarray
    rest: np.ndarray
    closure: np.ndarray


@lru_cache(maxsize=1)
def viseme_table() -> dict:
    doc = _load("visemes.toml")
    visemes = doc["visemes"]
    missing = [p for p in common_phonemes() if p not in doc["phoneme_to_viseme"]]
    if missing:
        raise ValueError(f"visemes.toml: phonemes without a viseme: {missing}")
    for p, v in doc["phoneme_to_viseme"].items():
        if v and v not in visemes:
            raise ValueError(f"visemes.toml: phoneme {p!r} maps to unknown viseme {v!r}")
    if set(doc["dominance"]) != set(visemes):
        raise ValueError("visemes.toml: [dominance] must list every viseme")
    for name in VISEME_SETS:
        rows = doc["sets"][name]["visemes"]
        if set(rows) != set(visemes):
            raise ValueError(f"visemes.toml: set {name!r} must map every viseme")
    return doc


def phoneme_viseme(phoneme: str) -> str:
    """The viseme class of a common phoneme ("" for transparent phonemes such as "hh")."""
    return viseme_table()["phoneme_to_viseme"].get(phoneme, "")


@lru_cache(maxsize=None)
def viseme_set(name: str) -> VisemeSet:
    doc = viseme_table()
    spec = doc["sets"][name]
    rows = {p: (spec.get("phonemes", {}).get(p) if p in spec.get("phonemes", {}) else spec["visemes"].get(v, {}))
            for p, v in doc["phoneme_to_viseme"].items()}
    channels: list[str] = []
    for row in list(spec["visemes"].values()) + list(spec.get("phonemes", {}).values()):
        for c in row:
            if c not in channels:
                channels.append(c)
    phonemes = tuple(doc["phoneme_to_viseme"])
    index = {c: i for i, c in enumerate(channels)}

    def vector(row: dict) -> np.ndarray:
        v = np.zeros(len(channels))
        for c, w in row.items():
            v[index[c]] = float(w)
        return v

    targets = np.array([vector(rows[p]) for p in phonemes]).reshape(len(phonemes), len(channels))
    return VisemeSet(name, spec["description"], tuple(channels), phonemes, targets,
                     vector(spec["visemes"]["sil"]), vector(spec["visemes"][spec["closure"]]))


@lru_cache(maxsize=1)
def dominance_arrays() -> tuple[tuple[str, ...], np.ndarray, np.ndarray, np.ndarray]:
    """Per common phoneme (in ``visemes.toml`` order): ``(phonemes, alpha, theta_before, theta_after)``;
    transparent phonemes have alpha 0."""
    doc = viseme_table()
    phonemes = tuple(doc["phoneme_to_viseme"])
    alpha, before, after = [], [], []
    for p in phonemes:
        v = doc["phoneme_to_viseme"][p]
        d = doc["dominance"].get(v, {"alpha": 0.0, "theta_before": 1.0, "theta_after": 1.0})
        alpha.append(d["alpha"] if v else 0.0)
        before.append(d["theta_before"])
        after.append(d["theta_after"])
    return phonemes, np.array(alpha), np.array(before), np.array(after)


@lru_cache(maxsize=1)
def names_table() -> dict:
    return _load("names.toml")


@lru_cache(maxsize=1)
def expressions_table() -> dict:
    doc = _load("expressions.toml")
    vocab = names_table()["vocabularies"]
    for au, spec in doc["action_units"].items():
        for voc, row in spec.items():
            if voc == "name":
                continue
            channels = vocab[voc]["channels"] if voc in vocab else viseme_set(voc).channels
            bad = [c for c in row if c not in channels]
            if bad:
                raise ValueError(f"expressions.toml: {au} names unknown {voc} channels {bad}")
    for lex, spec in doc["lexemes"].items():
        bad = [a for a in spec.get("action_units", {}) if a not in doc["action_units"]]
        if bad:
            raise ValueError(f"expressions.toml: lexeme {lex} names unknown action units {bad}")
    return doc
