"""The local web server of ``infuse view``: the page, three.js, and each file's GLB, info and audio.

It listens on 127.0.0.1 only and answers a fixed set of routes (no path reaches the file system):

- ``/``: the page; ``/static/viewer.js``; ``/vendor/three/...``: the vendored three.js modules;
- ``/entries/<i>/info.json``, ``/entries/<i>/model.glb``, ``/entries/<i>/audio/<k>.wav``.

Files are prepared (read, converted to GLB, mapped) when the page first asks for them, one at a
time, and kept. A file that cannot be read answers 422 with ``{"error": message}``.
"""
from __future__ import annotations

import json
import re
import threading
from http import HTTPStatus
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from urllib.parse import unquote, urlsplit

from infuse.errors import InfuseError, UsageError

from .content import Prepared, Source, prepare
from .page import served_info, served_page, static_text
from infuse.three import Vendor

HOST = "127.0.0.1"
_ENTRY = re.compile(r"/entries/(\d+)/(info\.json|model\.glb|audio/(\d+)\.wav)")
_RANGE = re.compile(r"bytes=(\d*)-(\d*)")


class Site:
    """What the server answers: the page for ``sources`` and their prepared data."""

    def __init__(self, sources: list[Source], vendor: Vendor, title: str, **prepare_options):
        self.sources = sources
        self.vendor = vendor
        self.page = served_page(title, vendor, sources).encode("utf-8")
        self.viewer_js = static_text("viewer.js").encode("utf-8")
        self.vendor_files = {rel: spec for spec, rel in vendor.modules.items()}
        self._options = prepare_options
        self._prepared: dict[int, Prepared | InfuseError] = {}
        self._lock = threading.Lock()

    def prepared(self, index: int) -> Prepared:
        """The prepared file ``index`` (prepared once; a file that failed raises the same error again)."""
        with self._lock:
            if index not in self._prepared:
                try:
                    self._prepared[index] = prepare(self.sources[index], **self._options)
                except InfuseError as exc:
                    self._prepared[index] = exc
            result = self._prepared[index]
        if isinstance(result, InfuseError):
            raise result
        return result


class _Handler(BaseHTTPRequestHandler):
    server_version = "infuse-view"
    protocol_version = "HTTP/1.1"

    @property
    def site(self) -> Site:
        return self.server.site  # type: ignore[attr-defined]

    def log_message(self, format, *args):  # quiet: the terminal shows the URL and errors only
        if getattr(self.server, "verbose", False):
            super().log_message(format, *args)

    def do_GET(self):
        self._answer(head_only=False)

    def do_HEAD(self):
        self._answer(head_only=True)

    def _answer(self, head_only: bool) -> None:
        path = unquote(urlsplit(self.path).path)
        try:
            found = self._route(path)
        except InfuseError as exc:
            return self._send_json(HTTPStatus.UNPROCESSABLE_ENTITY, {"error": str(exc)}, head_only)
        except Exception as exc:  # a bug: tell the page in one line instead of dropping the connection
            return self._send_json(HTTPStatus.INTERNAL_SERVER_ERROR,
                                   {"error": f"internal error (a bug): {type(exc).__name__}: {exc}"}, head_only)
        if found is None:
            return self._send_json(HTTPStatus.NOT_FOUND, {"error": f"not found: {path}"}, head_only)
        body, mime, cache = found
        self._send(body, mime, cache, head_only)

    def _route(self, path: str) -> tuple[bytes, str, str] | None:
        site = self.site
        if path in ("/", "/index.html"):
            return site.page, "text/html; charset=utf-8", "no-store"
        if path == "/static/viewer.js":
            return site.viewer_js, "text/javascript; charset=utf-8", "no-store"
        if path.startswith("/vendor/") and path[len("/vendor/"):] in site.vendor_files:
            return site.vendor.path(site.vendor_files[path[len("/vendor/"):]]).read_bytes(), "text/javascript; charset=utf-8", "max-age=3600"
        match = _ENTRY.fullmatch(path)
        if not match or int(match[1]) >= len(site.sources):
            return None
        index = int(match[1])
        prepared = site.prepared(index)
        if match[2] == "info.json":
            return json.dumps(served_info(prepared, index)).encode("utf-8"), "application/json", "no-store"
        if match[2] == "model.glb":
            return prepared.glb, "model/gltf-binary", "no-store"
        k = int(match[3])
        if k >= len(prepared.audio):
            return None
        return prepared.audio[k][1].read_bytes(), "audio/wav", "no-store"

    def _send_json(self, status: HTTPStatus, doc: dict, head_only: bool) -> None:
        body = json.dumps(doc).encode("utf-8")
        self.send_response(status)
        self.send_header("Content-Type", "application/json")
        self.send_header("Content-Length", str(len(body)))
        self.end_headers()
        if not head_only:
            self.wfile.write(body)

    def _send(self, body: bytes, mime: str, cache: str, head_only: bool) -> None:
        start, end = 0, len(body)
        status = HTTPStatus.OK
        requested = _RANGE.fullmatch(self.headers.get("Range", "").strip())
        if requested and (requested[1] or requested[2]) and body:  # media elements seek with byte ranges
            if requested[1]:
                start = int(requested[1])
                end = min(int(requested[2]) + 1, len(body)) if requested[2] else len(body)
            else:
                start = max(len(body) - int(requested[2]), 0)
            if start >= len(body) or start >= end:
                self.send_response(HTTPStatus.REQUESTED_RANGE_NOT_SATISFIABLE)
                self.send_header("Content-Range", f"bytes */{len(body)}")
                self.send_header("Content-Length", "0")
                self.end_headers()
                return
            status = HTTPStatus.PARTIAL_CONTENT
        self.send_response(status)
        self.send_header("Content-Type", mime)
        self.send_header("Content-Length", str(end - start))
        self.send_header("Cache-Control", cache)
        self.send_header("Accept-Ranges", "bytes")
        if status == HTTPStatus.PARTIAL_CONTENT:
            self.send_header("Content-Range", f"bytes {start}-{end - 1}/{len(body)}")
        self.end_headers()
        if not head_only:
            self.wfile.write(body[start:end])


class ViewerServer:
    """A running server (in a daemon thread): ``url``, ``close()``; also a context manager."""

    def __init__(self, site: Site, port: int = 0, verbose: bool = False):
        try:
            self._httpd = ThreadingHTTPServer((HOST, port), _Handler)
        except OSError as exc:
            raise UsageError(f"cannot listen on {HOST}:{port}: {exc.strerror or exc}") from None
        self._httpd.daemon_threads = True
        self._httpd.block_on_close = False  # closing must not wait for a browser's idle keep-alive connection
        self._httpd.site = site  # type: ignore[attr-defined]
        self._httpd.verbose = verbose  # type: ignore[attr-defined]
        self.port = self._httpd.server_address[1]
        self.url = f"http://{HOST}:{self.port}/"
        self.thread = threading.Thread(target=self._httpd.serve_forever, name="infuse-view", daemon=True)
        self.thread.start()

    def close(self) -> None:
        """Stop serving and release the port."""
        self._httpd.shutdown()
        self._httpd.server_close()
        self.thread.join(timeout=5)

    def __enter__(self) -> "ViewerServer":
        return self

    def __exit__(self, *exc) -> None:
        self.close()
