"""``infuse serve`` under bad input: malformed JSON, unknown characters, invalid BML, a flood of 1,000
messages a second and a client that never reads. Each message gets its error reply, nothing else changes,
and the frames keep coming at the frame rate. Also HTTP POST and the token."""
from __future__ import annotations

import base64
import json
import os
import socket
import time
import urllib.error
import urllib.request

import pytest

from live_support import BML_NS, Recorder, scene_file, serving

NOD = f'<bml xmlns="{BML_NS}" id="nod"><head id="h1" lexeme="NOD"/></bml>'


def _stalled_client(port: int) -> socket.socket:
    """A WebSocket client with a 4 KB receive buffer that subscribes to the pose stream and never reads."""
    raw = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    raw.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
    raw.connect(("127.0.0.1", port))
    key = base64.b64encode(os.urandom(16)).decode()
    raw.sendall((f"GET / HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
                 f"Sec-WebSocket-Key: {key}\r\nSec-WebSocket-Version: 13\r\n\r\n").encode())
    head = b""
    while b"\r\n\r\n" not in head:
        head += raw.recv(1)
    assert head.startswith(b"HTTP/1.1 101"), head
    payload = json.dumps({"type": "subscribe", "frames": True, "feedback": "all"}).encode()
    mask = os.urandom(4)
    raw.sendall(bytes([0x81, 0x80 | len(payload)]) + mask + bytes(b ^ mask[i % 4] for i, b in enumerate(payload)))
    return raw


def test_bad_input_flood_and_a_stalled_client_leave_the_frame_rate_alone(tmp_path):
    with serving(scene_file(tmp_path, fps=60)) as (process, port, _):
        stalled = _stalled_client(port)
        watcher = Recorder(port)
        watcher.wait_for(lambda m: m["type"] == "hello")
        watcher.request({"type": "subscribe", "frames": True, "feedback": "none"})
        flood = Recorder(port)
        flood.wait_for(lambda m: m["type"] == "hello")
        bad = ["{not json", "[1, 2]", json.dumps({"type": "dance"}),
               json.dumps({"type": "bml", "character": "zed", "bml": NOD}),
               json.dumps({"type": "bml", "character": "ann", "bml": "<bml id='x'><head id='h' lexeme='NOD'></bml>"}),
               json.dumps({"type": "call", "method": "say", "character": "ann", "args": {"text": "hi", "loud": True}}),
               json.dumps({"type": "target", "name": "ball", "position": [0, "up", 1]}),
               json.dumps({"type": "target", "name": "ball", "position": [0.1, 1.5, 0.7]})]
        before = watcher.request({"type": "status"})
        frames_before, started = len(watcher.frames), time.monotonic()
        sent = 0
        while time.monotonic() - started < 3.0:  # 1,000 messages a second for 3 s
            for _ in range(10):
                flood.send(bad[sent % len(bad)])
                sent += 1
            time.sleep(max(0.0, started + sent / 1000.0 - time.monotonic()))
        elapsed = time.monotonic() - started
        frames_during = len(watcher.frames) - frames_before
        after = watcher.request({"type": "status"})
        replies = [m for m in flood.messages if m["type"] in ("error", "accepted")]
        deadline = time.monotonic() + 30
        while len(replies) < sent and time.monotonic() < deadline:
            time.sleep(0.05)
            replies = [m for m in flood.messages if m["type"] in ("error", "accepted")]
        assert len(replies) == sent  # every message answered
        errors = [m for m in replies if m["type"] == "error"]
        kinds = {m["error"] for m in errors}
        assert {"InputError", "UsageError"} <= kinds, kinds
        assert all(m["message"] for m in errors)
        malformed = next(m for m in errors if "malformed JSON" in m["message"])
        assert "line 1 column 2" in malformed["message"]
        invalid_bml = next(m for m in errors if "malformed XML" in m["message"])
        assert invalid_bml["error"] == "InputError" and "line 1" in invalid_bml["message"]
        unknown = next(m for m in errors if "'zed'" in m["message"])
        assert unknown["error"] == "UsageError" and "bob, ann" in unknown["message"]
        moved = [m for m in replies if m["type"] == "accepted"]
        assert moved and all(m["target"] == "ball" for m in moved)  # the good ones among them still work
        # the frames kept coming, and the clock held: nothing missed while flooded and stalled
        shown, missed = after["shown"] - before["shown"], after["missed"] - before["missed"]
        assert shown >= 0.9 * 60 * elapsed and missed <= shown // 50, (shown, missed, elapsed)
        assert frames_during >= 0.5 * shown, (frames_during, shown)  # and they reached a client (in this busy process)
        # and the scene still takes BML
        nod = watcher.request({"type": "bml", "character": "ann", "bml": NOD})
        assert nod["type"] == "accepted" and nod["blocks"] == ["nod"]
        # a warning found while the speech is synthesized ahead goes to the client that asked
        said = flood.request({"type": "call", "method": "say", "character": "ann", "args": {"text": "Hello.", "voice": "no-such-voice"}})
        assert said["type"] == "accepted", said
        warning = flood.wait_for(lambda m: m.get("kind") == "warningFeedback" and "no-such-voice" in m["description"])
        assert "unknown" in warning["description"] and warning["xml"].startswith("<warningFeedback")
        watcher.close()
        flood.close()
        stalled.close()


def test_http_post_and_token(tmp_path):
    with serving(scene_file(tmp_path), "--token", "s3cret") as (process, port, http_port):
        url = f"http://127.0.0.1:{http_port}/"

        def post(body: bytes, query: str = "", token: str | None = "s3cret"):
            request = urllib.request.Request(url + query, data=body, method="POST")
            if token:
                request.add_header("Authorization", f"Bearer {token}")
            try:
                with urllib.request.urlopen(request, timeout=20) as answer:
                    return answer.status, json.loads(answer.read())
            except urllib.error.HTTPError as exc:
                return exc.code, json.loads(exc.read())

        status, reply = post(NOD.encode(), "?character=ann")
        assert status == 200 and reply["type"] == "accepted" and reply["blocks"] == ["nod"]
        status, reply = post(b'{"type": "bml", "bml": "<bml"}')
        assert status == 400 and reply["error"] == "InputError"
        status, reply = post(json.dumps({"type": "call", "method": "nod", "character": "bob"}).encode())
        assert status == 200 and reply["type"] == "accepted"
        status, reply = post(json.dumps({"type": "add", "file": "elsewhere.glb"}).encode())
        assert status == 400 and "--allow-add" in reply["message"]
        status, reply = post(NOD.encode(), "?character=ann", token=None)
        assert status == 401
        status, reply = post(NOD.encode(), "?character=ann", token="wrong")
        assert status == 401
        with pytest.raises(Exception, match="401"):
            Recorder(port)
        client = Recorder(port, token="s3cret")
        assert client.wait_for(lambda m: m["type"] == "hello")["fps"] == 60
        client.close()
