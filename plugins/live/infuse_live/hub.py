"""The clients of a live scene: their messages in, replies, feedback, frames and speech audio out.

Runs on an asyncio event loop; the live scene's loop thread hands it frames and feedback with
``call_soon_threadsafe``. Every client has its own writer: a bounded queue of replies and feedback (a
client that lets :data:`MAX_PENDING` pile up is dropped) and one slot for the latest frame (a client that
reads slower than the frame rate skips frames). Nothing a client does blocks the loop thread or another
client.
"""
from __future__ import annotations

import asyncio
import base64
import io
import itertools
import threading
import wave
from collections import deque
from concurrent.futures import Future, ThreadPoolExecutor

import numpy as np

from infuse.errors import UsageError
from infuse.live import LiveFrame, LiveScene
from infuse.scene.speech import utterance_samples

from .frames import binary_frame, frame_text
from .protocol import Message, dumps, error_message, feedback_message, parse_message

#: Replies and feedback waiting for one client before it is dropped as stalled.
MAX_PENDING = 2000
#: Blocks whose sender is remembered for their feedback (the oldest forgotten first; a block's entry goes
#: when it ends, so only blocks that never end, failed ones, pile up to this).
MAX_OWNED_BLOCKS = 10_000


class Client:
    """One connected client: what it subscribed to and what waits to be sent to it."""

    def __init__(self, number: int, send, drop=lambda: None):
        self.number = number
        self.send = send  # async (text) -> None
        self.drop = drop  # ends the connection at once, unsent data discarded
        self.frames = False
        self.format = "json"
        self.feedback = "own"
        self.pending: deque[str] = deque()
        self.frame: str | bytes | None = None
        self.skipped = 0
        self.closed = False
        self.wake = asyncio.Event()

    def put(self, doc: dict | str) -> None:
        if self.closed:
            return
        if len(self.pending) >= MAX_PENDING:
            self.closed = True
            self.drop()
        else:
            self.pending.append(doc if isinstance(doc, str) else dumps(doc))
        self.wake.set()

    def put_frame(self, message: str | bytes) -> None:
        if self.frame is not None:
            self.skipped += 1
        self.frame = message
        self.wake.set()

    async def write(self) -> None:
        """Send what waits, until the client is closed (runs as the client's own task)."""
        while not self.closed:
            await self.wake.wait()
            self.wake.clear()
            while self.pending and not self.closed:
                await self.send(self.pending.popleft())
            if self.frame is not None and not self.closed:
                text, self.frame = self.frame, None
                await self.send(text)


class Hub:
    """Connects clients to a :class:`~infuse.live.LiveScene` (see the module doc). ``model_url(name)``
    gives the URL of a character's model for the ``hello`` message."""

    def __init__(self, live: LiveScene, loop: asyncio.AbstractEventLoop, model_url=lambda name: None,
                 allow_add: bool = False):
        self.live = live
        self.loop = loop
        self.clients: set[Client] = set()
        self.owners: dict[str, Client] = {}
        self.speaking: dict[str, tuple[str, float]] = {}  # block -> (character, start) of audio sent
        self._numbers = itertools.count(1)
        self._local = threading.local()  # the client a thread acts for (its feedback goes there)
        self._prepare = ThreadPoolExecutor(2, thread_name_prefix="infuse-live-prepare")
        self._model_url = model_url
        self.allow_add = allow_add
        self._unsubscribe = [live.on_frame(self._frame_from_loop), live.on(None, self._feedback_from_loop)]

    def close(self) -> None:
        for unsubscribe in self._unsubscribe:
            unsubscribe()
        self._prepare.shutdown(wait=False, cancel_futures=True)

    # -- clients --------------------------------------------------------------------------------------
    def connect(self, send, drop=lambda: None) -> Client:
        """A new client: ``send(text)`` (async) writes to it, ``drop()`` ends its connection at once."""
        client = Client(next(self._numbers), send, drop)
        self.clients.add(client)
        client.put(self.hello())
        return client

    def disconnect(self, client: Client) -> None:
        client.closed = True
        client.wake.set()
        self.clients.discard(client)
        for block in [b for b, c in self.owners.items() if c is client]:
            del self.owners[block]

    def hello(self) -> dict:
        scene = self.live.scene
        characters = {name: self.character_info(name) for name in list(scene.characters)}
        return {"type": "hello", "fps": self.live.fps, "frame": scene.runtime.frame, "time": scene.time,
                "characters": characters, "targets": sorted(scene.targets), "objects": sorted(scene.objects)}

    def character_info(self, name: str) -> dict:
        """A character's joints (names), parents, morph targets and model URL."""
        rig = self.live.scene.runtime.rig(name)
        return {"joints": list(rig.skeleton.names), "parents": [int(p) for p in rig.skeleton.parents],
                "morphs": list(rig.morph_targets), "model": self._model_url(name)}

    # -- messages in ----------------------------------------------------------------------------------
    async def handle(self, client: Client | None, text: str | bytes, where: str = "message") -> list[dict]:
        """Act on one client message; returns the replies (also queued to ``client``, when given).
        Every mistake becomes an ``error`` reply; nothing else changes."""
        request = None
        try:
            message = parse_message(text, where)
            request = message.request
            reply = await self._act(client, message)
        except Exception as exc:  # noqa: BLE001 - typed errors name the problem; no request ends the service
            reply = error_message(exc, request)
        if client is not None:
            client.put(reply)
        return [reply]

    async def _act(self, client: Client | None, message: Message) -> dict:
        fields, request = message.fields, message.request
        if message.type == "subscribe":
            if client is None:
                raise UsageError("subscribe needs a WebSocket connection")
            client.frames = fields.get("frames", client.frames)
            client.feedback = fields.get("feedback", client.feedback)
            client.format = fields.get("format", client.format)
            return {"type": "subscribed", "request": request, "frames": client.frames, "feedback": client.feedback,
                    "format": client.format}
        if message.type == "status":
            mine = {"frames_skipped": client.skipped} if client is not None else {}  # replaced before it read them
            if fields.get("blocks"):
                mine["blocks"] = [list(b) for b in list(self.live.stats.blocks)]
            return {"type": "status", "request": request, "frame": self.live.scene.runtime.frame,
                    "time": self.live.scene.time, **self.live.stats.summary(), "clients": len(self.clients), **mine}
        if message.type == "target":
            at = await asyncio.wrap_future(self.live.submit(self._move, fields["name"], fields["position"], kind="target"))
            return {"type": "accepted", "request": request, "target": fields["name"], "time": at,
                    "frame": round(at * self.live.fps)}
        if message.type == "add":
            if not self.allow_add:
                raise UsageError("adding characters is off; start infuse serve with --allow-add")
            options = {k: fields[k] for k in ("position", "facing", "packs") if k in fields}
            name = await self.loop.run_in_executor(
                self._prepare, lambda: self.live.add_character(fields["file"], fields.get("name"), **options))
            info = {"type": "character", "name": name, **self.character_info(name)}
            for other in list(self.clients):
                if other is not client:
                    other.put(info)
            return {**info, "type": "accepted", "request": request, "character": name}
        if message.type == "bml":
            submitted = await self.loop.run_in_executor(self._prepare, self._parse_and_submit, client, fields)
        else:
            submitted = await self.loop.run_in_executor(self._prepare, self._prepare_and_submit, client, fields)
        ids, at = await asyncio.wrap_future(submitted)
        ids = ids if isinstance(ids, list) else [ids]
        return {"type": "accepted", "request": request, "blocks": [i for b in ids for i in (b if isinstance(b, list) else [b])],
                "time": at, "frame": round(at * self.live.fps)}

    def _parse_and_submit(self, client: Client | None, fields: dict) -> Future:
        """Parse a bml message's blocks and hand them to the loop, both on the preparing thread: the
        command is queued as soon as it is parsed, not after this server's thread wakes again."""
        blocks, _ = self._on_behalf(client, self.live.parse, fields.get("character"), fields["bml"])
        return self.live.submit(self._on_behalf, client, self.live.schedule, blocks, kind="bml")

    def _prepare_and_submit(self, client: Client | None, fields: dict) -> Future:
        """Check (and prepare) a builder call and hand it to the loop, both on the preparing thread."""
        method, character, arguments = fields["method"], fields["character"], fields.get("args", {})
        prepared, _ = self._on_behalf(client, self.live.prepare_call, method, character, arguments)
        return self.live.submit(self._on_behalf, client, self.live.builder_call, method, character, arguments, prepared,
                                kind=method)

    def _move(self, name: str, position) -> float:
        return self.live.place_target(name, position)

    def _on_behalf(self, client: Client | None, function, *args):
        """Run ``function`` (on the loop thread, or a preparing one) with the feedback it gives routed to
        ``client``; returns its result and the scene time."""
        self._local.submitter = client
        try:
            return function(*args), self.live.scene.time
        finally:
            self._local.submitter = None

    # -- out, from the loop thread --------------------------------------------------------------------
    def _feedback_from_loop(self, event) -> None:
        # on the thread that emits it (the loop's, or a preparing one's): only hand over; the owners are
        # kept on the event loop's thread
        self.loop.call_soon_threadsafe(self._deliver, event, getattr(self._local, "submitter", None))

    def _deliver(self, event, submitter: Client | None) -> None:
        """Feedback to the client whose request gave it (while scheduling or preparing), else to the client
        that sent its block; and to every client that wants all of it."""
        block = getattr(event, "block", None) or str(getattr(event, "id", "")).split(":")[0]
        if submitter is not None and event.kind == "blockPrediction":
            self.owners.pop(block, None)
            self.owners[block] = submitter
            if len(self.owners) > MAX_OWNED_BLOCKS:
                del self.owners[next(iter(self.owners))]
        owner = submitter if submitter is not None else self.owners.get(block)
        text = dumps(feedback_message(event))
        for client in list(self.clients):
            if client.feedback == "all" or (client.feedback == "own" and client is owner):
                client.put(text)
        audio = self._audio(event)
        if audio is not None:
            for client in list(self.clients):
                if client.frames:
                    client.put(audio)
        if event.kind == "blockProgress" and event.sync == "end":
            self.owners.pop(block, None)

    def _audio(self, event) -> dict | None:
        """An ``audio`` message when a speech behaviour starts (its WAV), or a ``stop`` when its block ends
        before the speech does."""
        if event.kind == "syncPointProgress" and event.sync == "start":
            record = self.live.scene.scheduler.blocks.get(event.block)
            activation = record.activation(event.behaviour) if record is not None else None
            if activation is None or activation.controller != "speech":
                return None
            utterance = self.live.scene.speech.utterance(activation.parameters)
            if utterance is None:
                return None
            samples, rate = utterance_samples(utterance)
            self.speaking[event.block] = (event.character, event.global_time)
            return {"type": "audio", "character": event.character, "block": event.block, "behaviour": event.behaviour,
                    "start": event.global_time, "wav": base64.b64encode(_wav(samples, rate)).decode("ascii")}
        if event.kind == "blockProgress" and event.sync == "end" and event.block in self.speaking:
            character, _ = self.speaking.pop(event.block)
            return {"type": "audio", "character": character, "block": event.block, "stop": event.global_time}
        return None

    def _frame_from_loop(self, frame: LiveFrame) -> None:
        self.loop.call_soon_threadsafe(self._send_frame, frame)

    def _send_frame(self, frame: LiveFrame) -> None:
        encoded = {}
        for client in [c for c in self.clients if c.frames and not c.closed]:
            if client.format not in encoded:
                encoded[client.format] = binary_frame(frame) if client.format == "binary" else frame_text(frame)
            client.put_frame(encoded[client.format])


def _wav(samples: np.ndarray, rate: int) -> bytes:
    """Mono int16 ``samples`` at ``rate`` Hz as WAV file bytes."""
    buffer = io.BytesIO()
    with wave.open(buffer, "wb") as out:
        out.setnchannels(1)
        out.setsampwidth(2)
        out.setframerate(int(rate))
        out.writeframes(np.asarray(samples, dtype="<i2").tobytes())
    return buffer.getvalue()
