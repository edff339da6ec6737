"""BML 1.0 blocks for the scene's builder API (``scene.say``, ``scene.gaze``, ``scene.nod``...).

Each function returns the text of one ``<bml>`` block with one behaviour, so what the builder asks for
goes through the same parser, scheduler and realizer as any document. Values are escaped; numbers are
written in full precision. SmartBody elements (``sbm:reach``) declare their namespace.
"""
from __future__ import annotations

from xml.sax.saxutils import escape, quoteattr

from ..bml.names import BML_NS, SBM_NS


def _attributes(values: dict) -> str:
    out = []
    for key, value in values.items():
        if value is None:
            continue
        if isinstance(value, float):
            value = repr(value)
        out.append(f" {key}={quoteattr(str(value))}")
    return "".join(out)


def block(block_id: str, character: str, behaviour: str, composition: str = "MERGE") -> str:
    """A ``<bml>`` block (BML 1.0 namespace, ``sbm`` declared) holding ``behaviour`` (XML text)."""
    return (f'<bml xmlns="{BML_NS}" xmlns:sbm="{SBM_NS}"{_attributes({"id": block_id, "characterId": character})}'
            f'{_attributes({"composition": composition if composition != "MERGE" else None})}>{behaviour}</bml>')


def element(name: str, attributes: dict, content: str | None = None) -> str:
    """One element with ``attributes`` (None values left out) and optional XML ``content``."""
    if content is None:
        return f"<{name}{_attributes(attributes)}/>"
    return f"<{name}{_attributes(attributes)}>{content}</{name}>"


def speech_text(text: str) -> str:
    """Speech text for ``<text>``: plain text escaped; BML ``<sync id="..."/>`` marks already in it are kept."""
    if "<sync" in text or "<mark" in text:
        return text  # marked-up text: the parser checks it
    return escape(text)


def point_text(point) -> str:
    """A ground point ``(x, z)`` or ``(x, y, z)`` as locomotion's ``"x z"``."""
    values = [float(v) for v in point]
    if len(values) == 3:
        values = [values[0], values[2]]
    if len(values) != 2:
        raise ValueError(f"a point on the ground is (x, z) or (x, y, z), got {point!r}")
    return f"{values[0]!r} {values[1]!r}"
