"""The network side of ``infuse serve``: a WebSocket server and an HTTP server on one asyncio loop.

- WebSocket ``ws://HOST:PORT/``: JSON messages both ways (:mod:`infuse_live.protocol`);
- HTTP ``http://HOST:HTTP_PORT/``: ``GET /`` the live viewer page (three.js), ``GET /live.json`` where
  the WebSocket is, ``GET /characters/<name>.glb`` each character's model, ``GET /status``, and
  ``POST /`` one message (JSON, or BML XML with ``?character=NAME``) answered with its reply.

With a token, a WebSocket client sends ``?token=T`` in its URL or ``Authorization: Bearer T``; so does an
HTTP client (the page gets it from its own URL).
"""
from __future__ import annotations

import asyncio
import hmac
import json
import threading
from http import HTTPStatus
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from urllib.parse import parse_qs, unquote, urlsplit

from websockets.asyncio.server import serve
from websockets.exceptions import ConnectionClosed

from infuse.errors import UsageError

from .hub import Hub
from .protocol import MAX_MESSAGE_BYTES, dumps

HOST = "127.0.0.1"


def authorized(token: str | None, path: str, headers) -> bool:
    """Whether a request carries ``token`` (always, without a token)."""
    if not token:
        return True
    given = parse_qs(urlsplit(path).query).get("token", [""])[0]
    bearer = headers.get("Authorization", "") or ""
    if bearer.startswith("Bearer "):
        given = given or bearer[len("Bearer "):]
    return hmac.compare_digest(given.encode(), token.encode())


class LiveServer:
    """Serves a :class:`Hub` over WebSocket (``port``) and HTTP (``http_port``) on ``host``; ``site``
    answers the HTTP GETs (:class:`infuse_live.page.LiveSite`)."""

    def __init__(self, hub_factory, host: str = HOST, port: int = 0, http_port: int | None = 0, token: str | None = None,
                 site=None):
        self.host, self.port, self.http_port, self.token = host, port, http_port, token
        self.site = site
        self._hub_factory = hub_factory
        self.hub: Hub | None = None
        self._ws = None
        self._http: ThreadingHTTPServer | None = None
        self.loop: asyncio.AbstractEventLoop | None = None
        self.ready = threading.Event()
        self._stopped: asyncio.Event | None = None

    # -- running --------------------------------------------------------------------------------------
    async def run(self) -> None:
        """Serve until :meth:`shutdown`."""
        self.loop = asyncio.get_running_loop()
        self._stopped = asyncio.Event()
        self.hub = self._hub_factory(self.loop)
        try:
            self._ws = await serve(self._connection, self.host, self.port, max_size=MAX_MESSAGE_BYTES, max_queue=64,
                                   process_request=self._check_request, ping_interval=20, ping_timeout=20,
                                   write_limit=1 << 20)
        except OSError as exc:
            raise UsageError(f"cannot listen on {self.host}:{self.port}: {exc.strerror or exc}") from None
        self.port = self._ws.sockets[0].getsockname()[1]
        if self.http_port is not None:
            try:
                self._http = _HttpServer((self.host, self.http_port), self)
            except OSError as exc:
                self._ws.close()
                raise UsageError(f"cannot listen on {self.host}:{self.http_port}: {exc.strerror or exc}") from None
            self.http_port = self._http.server_address[1]
            threading.Thread(target=self._http.serve_forever, name="infuse-live-http", daemon=True).start()
        self.ready.set()
        try:
            await self._stopped.wait()
        finally:
            if self._http is not None:
                self._http.shutdown()
                self._http.server_close()
            self._ws.close()
            await self._ws.wait_closed()
            self.hub.close()

    def shutdown(self) -> None:
        """Stop serving (from any thread)."""
        if self.loop is not None and self._stopped is not None:
            self.loop.call_soon_threadsafe(self._stopped.set)

    # -- WebSocket ------------------------------------------------------------------------------------
    def _check_request(self, connection, request):
        if not authorized(self.token, request.path, request.headers):
            return connection.respond(HTTPStatus.UNAUTHORIZED, "a token is needed: ?token=... or Authorization: Bearer ...\n")
        return None

    async def _connection(self, websocket) -> None:
        hub = self.hub
        client = hub.connect(websocket.send, websocket.transport.abort)
        writer = asyncio.create_task(self._write(client, websocket))
        try:
            async for text in websocket:
                if client.closed:
                    break
                await hub.handle(client, text)
        except ConnectionClosed:
            pass
        finally:
            hub.disconnect(client)
            writer.cancel()

    @staticmethod
    async def _write(client, websocket) -> None:
        try:
            await client.write()
        except ConnectionClosed:
            pass

    # -- HTTP -----------------------------------------------------------------------------------------
    def post(self, body: bytes, query: dict, timeout_s: float = 150.0) -> dict:
        """Answer one HTTP POST (from an HTTP server thread): a JSON message, or BML XML."""
        text = body.decode("utf-8", errors="replace").lstrip()
        if text.startswith("<"):
            message = {"type": "bml", "bml": text}
            if query.get("character"):
                message["character"] = query["character"][0]
            body = dumps(message).encode("utf-8")
        future = asyncio.run_coroutine_threadsafe(self.hub.handle(None, body, "POST body"), self.loop)
        return future.result(timeout_s)[0]


class _HttpServer(ThreadingHTTPServer):
    daemon_threads = True

    def __init__(self, address, live_server: LiveServer):
        self.live_server = live_server
        super().__init__(address, _HttpHandler)


class _HttpHandler(BaseHTTPRequestHandler):
    server_version = "infuse-serve"
    protocol_version = "HTTP/1.1"

    def log_message(self, format, *args):  # quiet: errors go back to the client
        pass

    def _live(self) -> LiveServer:
        return self.server.live_server

    def _allowed(self) -> bool:
        if authorized(self._live().token, self.path, self.headers):
            return True
        self._send(HTTPStatus.UNAUTHORIZED, b'{"type":"error","error":"Unauthorized","message":"a token is needed"}',
                   "application/json")
        return False

    def do_GET(self):
        if not self._allowed():
            return
        path = unquote(urlsplit(self.path).path)
        live = self._live()
        if path == "/status":
            self._send(HTTPStatus.OK, json.dumps(live.post(b'{"type":"status"}', {})).encode(), "application/json")
            return
        if path == "/live.json":
            doc = {"websocket_port": live.port, "token_required": bool(live.token)}
            self._send(HTTPStatus.OK, json.dumps(doc).encode(), "application/json")
            return
        found = live.site.answer(path) if live.site is not None else None
        if found is None:
            self._send(HTTPStatus.NOT_FOUND, b"not found\n", "text/plain")
            return
        self._send(HTTPStatus.OK, *found, shared=True)

    def do_POST(self):
        if not self._allowed():
            return
        try:
            length = int(self.headers.get("Content-Length", "0"))
        except ValueError:
            length = -1
        if not 0 < length <= MAX_MESSAGE_BYTES:
            self._send(HTTPStatus.BAD_REQUEST, dumps({"type": "error", "error": "InputError",
                                                      "message": f"POST body: expected 1 to {MAX_MESSAGE_BYTES} bytes with a Content-Length"}).encode(),
                       "application/json")
            return
        body = self.rfile.read(length)
        reply = self._live().post(body, parse_qs(urlsplit(self.path).query))
        status = HTTPStatus.OK if reply.get("type") != "error" else \
            HTTPStatus.SERVICE_UNAVAILABLE if reply.get("error") == "BusyError" else HTTPStatus.BAD_REQUEST
        self._send(status, dumps(reply).encode("utf-8"), "application/json")

    def _send(self, status, body: bytes, mime: str, shared: bool = False) -> None:
        """Answer; ``shared``: pages from other origins may read it too (models and scripts for one's own page)."""
        self.send_response(status)
        self.send_header("Content-Type", mime)
        if shared:
            self.send_header("Access-Control-Allow-Origin", "*")
        self.send_header("Content-Length", str(len(body)))
        self.send_header("Cache-Control", "no-store")
        self.end_headers()
        self.wfile.write(body)
