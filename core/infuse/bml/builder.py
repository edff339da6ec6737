"""The builder API: one call, one BML 1.0 block (``scene.say``, ``scene.gaze``, ``scene.nod``...).

Each call writes the text of one ``<bml>`` block with one behaviour, so what the builder asks for goes
through the same parser, scheduler and realizer as any document. Values are escaped; numbers are
written in full precision. SmartBody elements (``sbm:reach``) declare their namespace.
"""
from __future__ import annotations

from xml.sax.saxutils import escape, quoteattr

from ..errors import UsageError
from .names import BML_NS, SBM_NS


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


class BuilderCalls:
    """The builder calls of a host (a scene) that provides ``_submit(character, what, behaviour, at)``,
    which schedules ``behaviour`` (XML text) in a new block named after ``what`` and returns its id, and
    ``_target_name(target)``, a BML target name for a name or a point."""

    def say(self, character: str, text: str, at: float | None = None, voice: str | None = None) -> str:
        """Speak ``text`` (BML ``<sync id="..."/>`` marks allowed); returns the block id."""
        content = element("text", {}, speech_text(text))
        return self._submit(character, "say", element("speech", {"id": "s1", "voice": voice}, content), at)

    def gaze(self, character: str, target, at: float | None = None, duration: float | None = None,
             influence: str = "HEAD", offset_angle_deg: float | None = None, offset_direction: str | None = None) -> str:
        """Look at ``target`` (a character, an object, ``"character:joint"`` or a point) with ``influence``
        (EYES, HEAD, SHOULDER, WAIST, WHOLE): from now on (a gazeShift), or for ``duration`` seconds."""
        attributes = {"id": "g1", "target": self._target_name(target), "influence": influence,
                      "offsetAngle": offset_angle_deg, "offsetDirection": offset_direction}
        if duration is None:
            return self._submit(character, "gaze", element("gazeShift", attributes), at)
        if not duration > 0:
            raise UsageError("a gaze lasts a positive number of seconds")
        return self._submit(character, "gaze", element("gaze", {**attributes, "start": 0.0, "end": float(duration)}), at)

    def head(self, character: str, lexeme: str = "NOD", at: float | None = None, repeats: float = 1.0,
             amount: float = 0.5, velocity_hz: float | None = None) -> str:
        """A head movement: NOD, SHAKE, TOSS, TILT, WIGGLE, WAGGLE."""
        attributes = {"id": "h1", "lexeme": lexeme, "repetition": float(repeats), "amount": float(amount),
                      "sbm:velocity": None if velocity_hz is None else float(velocity_hz)}
        return self._submit(character, "head", element("head", attributes), at)

    def nod(self, character: str, at: float | None = None, repeats: float = 1.0, amount: float = 0.5) -> str:
        """Nod (down first)."""
        return self.head(character, "NOD", at, repeats, amount)

    def shake(self, character: str, at: float | None = None, repeats: float = 2.0, amount: float = 0.5) -> str:
        """Shake the head (to the character's right first)."""
        return self.head(character, "SHAKE", at, repeats, amount)

    def expression(self, character: str, lexeme: str, at: float | None = None, amount: float = 0.7,
                   duration: float | None = None) -> str:
        """A facial expression (BML faceLexeme: ``smile``, ``RAISE_BROWS``...) for ``duration`` seconds (default
        the natural 1.6 s)."""
        attributes = {"id": "f1", "lexeme": lexeme, "amount": float(amount)}
        if duration is not None:
            attributes.update(start=0.0, end=float(duration))
        return self._submit(character, "face", element("faceLexeme", attributes), at)

    def walk_to(self, character: str, target, at: float | None = None, manner: str = "walk",
                speed: float | None = None) -> str:
        """Walk (jog, run) to a point (x, z) / (x, y, z) or a named object or character (BML locomotion)."""
        where = target if isinstance(target, str) else point_text(target)
        attributes = {"id": "l1", "target": where, "manner": manner, "speed": None if speed is None else float(speed)}
        return self._submit(character, "walk", element("locomotion", attributes), at)

    def point(self, character: str, target, at: float | None = None, hand: str | None = None) -> str:
        """Point at ``target`` (a character, an object, ``"character:joint"`` or a point) with ``hand``: left,
        right or both (default: the hand on the target's side)."""
        modes = {None: None, "left": "LEFT_HAND", "right": "RIGHT_HAND", "both": "BOTH_HANDS"}
        if hand not in modes:
            raise UsageError(f"a pointing hand is left, right or both, not {hand!r}")
        attributes = {"id": "p1", "target": self._target_name(target), "mode": modes[hand]}
        return self._submit(character, "point", element("pointing", attributes), at)

    def grab(self, character: str, obj: str, at: float | None = None, hand: str | None = None) -> str:
        """Take object ``obj`` in a hand (left or right; default: the one on its side) and hold it (sbm:grab)."""
        attributes = {"id": "g1", "target": self._target_name(obj), "sbm:reach-type": hand}
        return self._submit(character, "grab", element("sbm:grab", attributes), at)

    def release(self, character: str, obj: str | None = None, at: float | None = None) -> str:
        """Let go of what the character holds (``obj``: only that object); it stays where the hand leaves it."""
        attributes = {"id": "g1", "target": None if obj is None else self._target_name(obj), "sbm:grab-state": "release"}
        return self._submit(character, "release", element("sbm:grab", attributes), at)

    def reach(self, character: str, target, at: float | None = None, action: str = "touch",
              hand: str | None = None) -> str:
        """Reach for an object (``action``: touch, pick-up, put-down, point-at; ``hand``: left or right)."""
        attributes = {"id": "r1", "target": self._target_name(target), "sbm:action": action, "sbm:reach-type": hand}
        return self._submit(character, "reach", element("sbm:reach", attributes), at)
