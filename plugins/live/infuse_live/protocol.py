"""The JSON messages of ``infuse serve``: what clients send, checked, and what the server sends back.

Client to server (one JSON object per WebSocket text message, or an HTTP POST body):

- ``{"type": "bml", "bml": "<bml ...>", "character": "ann", "request": 7}``: BML blocks from the next
  frame on (``character`` optional when each block names its ``characterId``);
- ``{"type": "call", "method": "say", "character": "ann", "args": {"text": "Hi"}}``: the scene builder
  (:data:`METHODS`: ``say``, ``gaze``, ``head``, ``nod``, ``shake``, ``expression``, ``walk_to``, ``reach``,
  ``point``, ``grab``, ``release``);
- ``{"type": "target", "name": "ball", "position": [x, y, z]}``: a named target (added when new) stands
  there from the next frame on;
- ``{"type": "subscribe", "frames": true, "feedback": "all", "format": "binary"}``: receive the pose
  stream (as JSON ``frame`` messages, or binary messages: :func:`~infuse_live.frames.binary_frame`); feedback of every block
  (default: only of the blocks this client sent);
- ``{"type": "status", "blocks": true}``: frame counts and timings (and the last blocks evaluated,
  [first frame, frames] each, to replay the session offline);
- ``{"type": "add", "name": "carl", "file": "carl.glb", "position": [x, y, z], "facing": ..., "packs": [...]}``:
  a character joins the running scene (only when the server allows it: ``--allow-add``).

``request`` is optional and echoed in the reply. Server to client: ``hello`` on connect (characters with
their joints, parents, morph targets and model URL), ``character`` (one that joined, the same facts),
``accepted`` (block ids and the frame they start
on), ``feedback`` (``kind``: blockProgress, syncPointProgress, warningFeedback, blockPrediction, the event's
fields, and ``xml``: the BML feedback element), ``frame`` (pose stream), ``audio`` (an utterance's WAV
when it starts, ``stop`` when cut), ``status`` and ``error`` (``error``: the exception type, ``message``).
"""
from __future__ import annotations

import json
import math
from dataclasses import asdict, dataclass

from infuse.errors import InputError

#: Builder methods a ``call`` message may name, with the arguments each takes.
METHODS = {
    "say": {"text", "voice"},
    "gaze": {"target", "duration", "influence"},
    "head": {"lexeme", "repeats", "amount"},
    "nod": {"repeats", "amount"},
    "shake": {"repeats", "amount"},
    "expression": {"lexeme", "amount", "duration"},
    "walk_to": {"target", "manner", "speed"},
    "reach": {"target", "action", "hand"},
    "point": {"target", "hand"},
    "grab": {"obj", "hand"},
    "release": {"obj"},
}
TYPES = ("bml", "call", "target", "subscribe", "status", "add")
FORMATS = ("json", "binary")
#: Largest message accepted, bytes.
MAX_MESSAGE_BYTES = 1 << 20


@dataclass(frozen=True)
class Message:
    """A checked client message: ``type``, its fields, and the client's ``request`` tag (echoed)."""

    type: str
    fields: dict
    request: object = None


def parse_message(text: str | bytes, where: str = "message") -> Message:
    """A :class:`Message` from JSON text; :class:`InputError` naming ``where``, the field and the problem."""
    if isinstance(text, bytes):
        try:
            text = text.decode("utf-8")
        except UnicodeDecodeError as exc:
            raise InputError(where, f"byte {exc.start}", "not UTF-8 text") from None
    try:
        doc = json.loads(text)
    except json.JSONDecodeError as exc:
        raise InputError(where, f"line {exc.lineno} column {exc.colno}", f"malformed JSON: {exc.msg}") from None
    if not isinstance(doc, dict):
        raise InputError(where, None, f"expected a JSON object, got {type(doc).__name__}")
    kind = doc.get("type")
    if kind not in TYPES:
        raise InputError(where, "type", f"expected one of {', '.join(TYPES)}, got {kind!r}")
    request = doc.get("request")
    if request is not None and not isinstance(request, (str, int)):
        raise InputError(where, "request", "a request tag is a string or an integer")
    fields = {k: v for k, v in doc.items() if k not in ("type", "request")}
    _check(kind, fields, where)
    return Message(kind, fields, request)


def _check(kind: str, fields: dict, where: str) -> None:
    allowed = {"bml": {"bml", "character"}, "call": {"method", "character", "args"}, "target": {"name", "position"},
               "subscribe": {"frames", "feedback", "format"}, "status": {"blocks"},
               "add": {"name", "file", "position", "facing", "packs"}}[kind]
    for key in fields:
        if key not in allowed:
            raise InputError(where, key, f"unknown field for a {kind!r} message (fields: {', '.join(sorted(allowed)) or 'none'})")
    character = fields.get("character")
    if character is not None and (not isinstance(character, str) or not character):
        raise InputError(where, "character", "a character is named by a non-empty string")
    if kind == "bml" and not (isinstance(fields.get("bml"), str) and fields["bml"].strip()):
        raise InputError(where, "bml", "expected the BML document as a non-empty string")
    if kind == "call":
        method = fields.get("method")
        if method not in METHODS:
            raise InputError(where, "method", f"expected one of {', '.join(METHODS)}, got {method!r}")
        if character is None:
            raise InputError(where, "character", f"{method} needs the character")
        args = fields.get("args", {})
        if not isinstance(args, dict):
            raise InputError(where, "args", "expected an object of arguments")
        for key in args:
            if key not in METHODS[method]:
                raise InputError(where, f"args.{key}", f"{method} takes {', '.join(sorted(METHODS[method]))}")
    if kind == "target":
        if not (isinstance(fields.get("name"), str) and fields["name"] and ":" not in fields["name"]):
            raise InputError(where, "name", "a target is named by a non-empty string without ':'")
        if not _point(fields.get("position")):
            raise InputError(where, "position", "expected [x, y, z]: three finite numbers, metres")
    if kind == "status" and not isinstance(fields.get("blocks", False), bool):
        raise InputError(where, "blocks", "expected true or false")
    if kind == "add":
        if not (isinstance(fields.get("file"), str) and fields["file"]):
            raise InputError(where, "file", "expected the character's file (a path on the server)")
        if "name" in fields and not (isinstance(fields["name"], str) and fields["name"]):
            raise InputError(where, "name", "a character is named by a non-empty string")
        packs = fields.get("packs", [])
        if not (isinstance(packs, list) and all(isinstance(p, str) for p in packs)):
            raise InputError(where, "packs", "expected a list of pack names")
        if "position" in fields and not _point(fields["position"]):
            raise InputError(where, "position", "expected [x, y, z]: three finite numbers, metres")
    if kind == "subscribe":
        if "frames" in fields and not isinstance(fields["frames"], bool):
            raise InputError(where, "frames", "expected true or false")
        if fields.get("feedback", "own") not in ("own", "all", "none"):
            raise InputError(where, "feedback", "expected 'own', 'all' or 'none'")
        if fields.get("format", "json") not in FORMATS:
            raise InputError(where, "format", f"expected one of {', '.join(FORMATS)}")


def _point(value) -> bool:
    return isinstance(value, list) and len(value) == 3 and \
        all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in value)


def feedback_message(event) -> dict:
    """A BML feedback event as a ``feedback`` message (its fields, its kind and its BML XML)."""
    return {"type": "feedback", "kind": event.kind, **asdict(event), "xml": event.to_xml()}


def error_message(exc: BaseException, request=None) -> dict:
    """An ``error`` reply: the exception type and its one-line message."""
    return {"type": "error", "request": request, "error": type(exc).__name__, "message": str(exc)}


def dumps(doc: dict) -> str:
    """Compact JSON text."""
    return json.dumps(doc, ensure_ascii=False, separators=(",", ":"))
