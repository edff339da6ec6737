"""Shared pieces of the live tests: a scene file of corpus characters, ``infuse serve`` started as a real
process (its ports read from its first line), and a WebSocket client that keeps every message."""
from __future__ import annotations

import asyncio
import itertools
import json
import os
import re
import signal
import struct
import subprocess
import sys
import threading
import time
from contextlib import contextmanager
from pathlib import Path

import numpy as np
from websockets.asyncio.client import connect

from corpus_data import corpus_file

BML_NS = "http://www.bml-initiative.org/bml/bml-1.0"
SBM_NS = "http://ict.usc.edu"
INFUSE = Path(sys.executable).with_name("infuse")
_READY = re.compile(r"ws://([\d.]+):(\d+)/\s+http://[\d.]+:(\d+)/")


def scene_file(folder: Path, fps: int = 60, blocks: str = "") -> Path:
    """Bob (Mixamo Xbot, walks) and Ann (Ready Player Me, speaks, reaches), a cup; ``blocks`` TOML appended."""
    xbot = corpus_file("runxaway-models/Xbot.glb")
    rpm = corpus_file("talkinghead/avatars/brunette-t.glb")
    path = folder / "live.toml"
    path.write_text(f'''fps = {fps}
[[character]]
name = "bob"
file = "{xbot}"
position = [-1.6, 0.0, -1.2]
facing = [0.0, 0.0, 0.9]
packs = ["locomotion-male"]

[[character]]
name = "ann"
file = "{rpm}"
position = [0.0, 0.0, 2.0]
facing = [0.0, 0.0, 0.8]
packs = ["reaching"]

[[object]]
name = "cup"
position = [0.18, 1.22, 1.73]
size = 0.09
{blocks}''')
    return path


@contextmanager
def serving(scene: Path, *options: str, timeout_s: float = 120.0):
    """``infuse serve SCENE --port 0`` running; yields (process, websocket port, http port). Stopped with
    SIGINT (Ctrl-C) at the end, and its exit checked: 0 and a last line saying it stopped."""
    process = subprocess.Popen([str(INFUSE), "serve", str(scene), "--port", "0", "--http-port", "0", "--quiet", *options],
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=dict(os.environ))
    lines: list[str] = []
    ready = threading.Event()

    def read():
        for line in process.stdout:
            lines.append(line)
            if _READY.search(line):
                ready.set()
    threading.Thread(target=read, daemon=True).start()
    deadline = time.monotonic() + timeout_s
    while not ready.wait(0.1):
        if process.poll() is not None or time.monotonic() > deadline:
            process.kill()
            raise AssertionError(f"infuse serve did not start: {''.join(lines)}{process.stderr.read()}")
    match = _READY.search("".join(lines))
    try:
        yield process, int(match[2]), int(match[3])
    finally:
        if process.poll() is None:
            process.send_signal(signal.SIGINT)
        try:
            code = process.wait(20)
        except subprocess.TimeoutExpired:
            process.kill()
            raise AssertionError("infuse serve did not stop on Ctrl-C")
        stderr = process.stderr.read()
        assert code == 0, stderr
        time.sleep(0.05)
        assert "stopped after" in "".join(lines), "".join(lines) + stderr


def decode_binary_frame(data: bytes) -> dict:
    """A binary frame message as the JSON one reads (lists of floats), decoded independently of the server."""
    (length,) = struct.unpack_from("<I", data, 0)
    header = json.loads(data[4:4 + length])
    values = np.frombuffer(data, dtype="<f4", offset=4 + length)
    characters, at = {}, 0
    for name, joints, morphs, *translated in header["characters"]:
        rotations = values[at:at + 4 * joints]
        root = values[at + 4 * joints:at + 4 * joints + 3]
        weights = values[at + 4 * joints + 3:at + 4 * joints + 3 + morphs]
        characters[name] = {"rotations": rotations.tolist(), "root": root.tolist(), "morphs": weights.tolist()}
        at += 4 * joints + 3 + morphs
        if translated == [True]:
            characters[name]["translations"] = values[at:at + 3 * joints].tolist()
            at += 3 * joints
    assert at == len(values)
    return {"type": "frame", "frame": header["frame"], "time": header["time"], "characters": characters}


class Recorder:
    """A WebSocket client on its own event loop thread: :meth:`send` a message, :meth:`wait_for` a reply;
    every message received is kept in :attr:`messages` (frames in :attr:`frames` by frame number)."""

    def __init__(self, port: int, token: str | None = None):
        self.url = f"ws://127.0.0.1:{port}/" + (f"?token={token}" if token else "")
        self.messages: list[dict] = []
        self.frames: dict[int, dict] = {}
        self._tags = itertools.count(1)
        self._loop = asyncio.new_event_loop()
        self._socket = None
        self._closed = threading.Event()
        self._opened = threading.Event()
        threading.Thread(target=self._loop.run_forever, daemon=True).start()
        task = asyncio.run_coroutine_threadsafe(self._run(), self._loop)
        deadline = time.monotonic() + 10
        while not self._opened.wait(0.01):
            if task.done():
                self._loop.call_soon_threadsafe(self._loop.stop)
                task.result()  # raises why the connection failed
            assert time.monotonic() < deadline, "could not connect"

    async def _run(self):
        async with connect(self.url, max_size=None) as socket:
            self._socket = socket
            self._opened.set()
            async for text in socket:
                message = decode_binary_frame(text) if isinstance(text, bytes) else json.loads(text)
                if message["type"] == "frame":
                    self.frames[message["frame"]] = message
                else:
                    self.messages.append(message)
        self._closed.set()

    def send(self, message: dict | str) -> None:
        text = message if isinstance(message, str) else json.dumps(message)
        asyncio.run_coroutine_threadsafe(self._socket.send(text), self._loop).result(5)

    def wait_for(self, predicate, timeout_s: float = 20.0) -> dict:
        deadline = time.monotonic() + timeout_s
        seen = 0
        while time.monotonic() < deadline:
            while seen < len(self.messages):
                message = self.messages[seen]
                seen += 1
                if predicate(message):
                    return message
            time.sleep(0.005)
        raise AssertionError(f"no such message within {timeout_s} s; got {[m.get('type') for m in self.messages][-20:]}")

    def request(self, message: dict, timeout_s: float = 20.0) -> dict:
        """Send ``message`` with a fresh request tag and return its reply (accepted, subscribed, status or error)."""
        tag = next(self._tags)
        self.send({**message, "request": tag})
        return self.wait_for(lambda m: m.get("request") == tag, timeout_s)

    def close(self) -> None:
        if self._socket is not None:
            asyncio.run_coroutine_threadsafe(self._socket.close(), self._loop).result(5)
        self._loop.call_soon_threadsafe(self._loop.stop)
