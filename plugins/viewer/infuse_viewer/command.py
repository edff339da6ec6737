"""``infuse view FILE|FOLDER``: show characters and clips in a browser, write the page as one HTML file, or a PNG of it."""
from __future__ import annotations

import os
import re
import signal
import sys
import threading
import webbrowser
from pathlib import Path

from infuse.atomic import atomic_open
from infuse.cli.map_command import add_mapping_options
from infuse.errors import InfuseError, UsageError
from infuse.mapping import read_map

from .content import LOW_CONFIDENCE, prepare, sources
from .page import offline_page
from .server import HOST, Site, ViewerServer
from infuse.three import ensure_vendor

DEFAULT_PORT = 8765


def add_arguments(p) -> None:
    p.add_argument("path", metavar="FILE|FOLDER",
                   help="a character or motion file (any readable format), or a folder: every .glb in it")
    p.add_argument("--port", type=int, help=f"port on {HOST} (default {DEFAULT_PORT}, or a free one when it is taken)")
    p.add_argument("--no-open", action="store_true", help="do not open a browser, only print the URL")
    p.add_argument("--html", metavar="OUT.html", help="write the page as one offline HTML file instead of serving it")
    p.add_argument("--screenshot", metavar="OUT.png", help="write a PNG of the page (headless Chromium) instead of serving it")
    p.add_argument("--time", type=float, default=0.0, metavar="SECONDS", help="with --screenshot: the time to show (default 0)")
    p.add_argument("--clip", help="with --screenshot: the clip to show (default: the first)")
    p.add_argument("--size", default="1000x640", metavar="WxH", help="with --screenshot: page size in pixels (default 1000x640)")
    p.add_argument("--targets", metavar="TARGETS.json", help="gaze/reach targets (default: <stem>.targets.json beside the file)")
    p.add_argument("--low-confidence", type=float, default=LOW_CONFIDENCE, metavar="C",
                   help=f"highlight joints mapped with a confidence below C (default {LOW_CONFIDENCE})")
    p.add_argument("--verbose", action="store_true", help="log every request the server answers")
    add_mapping_options(p)


def _has_display() -> bool:
    """Whether a graphical browser can open (a console browser would take over the terminal)."""
    return sys.platform in ("darwin", "win32") or bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


def _interrupt(signum, frame):
    raise KeyboardInterrupt


def _write_html(args, found, options, title) -> int:
    vendor = ensure_vendor()
    prepared = []
    for source in found:
        try:
            prepared.append(prepare(source, **options))
        except InfuseError as exc:
            if len(found) == 1:
                raise
            print(f"infuse view: skipping {source.path.name}: {exc}", file=sys.stderr)
    if not prepared:
        raise UsageError(f"{args.path}: none of its files could be read")
    with atomic_open(args.html, "w", encoding="utf-8") as handle:
        handle.write(offline_page(title, vendor, prepared))
    print(f"wrote {args.html} ({len(prepared)} file{'s' if len(prepared) > 1 else ''}, "
          f"{Path(args.html).stat().st_size / 1e6:.1f} MB)")
    return 0


def _screenshot(args, found, options, title) -> int:
    from . import screenshot

    size = re.fullmatch(r"(\d+)x(\d+)", args.size)
    if not size or not (100 <= int(size[1]) <= 8000 and 100 <= int(size[2]) <= 8000):
        raise UsageError("--size must be WIDTHxHEIGHT in pixels, 100 to 8000 each (e.g. 1000x640)")
    site = Site(found, ensure_vendor(), title, **options)
    clips = site.prepared(0).info["clips"]  # a file that cannot be read stops here, with its exit code
    if args.clip is not None and args.clip not in clips:
        raise UsageError(f"{found[0].path}: no clip named {args.clip!r}; the file has: {', '.join(clips) or 'none'}")
    with ViewerServer(site, 0, verbose=args.verbose) as server:
        screenshot.take(server.url, args.screenshot, int(size[1]), int(size[2]), args.time, args.clip)
    print(f"wrote {args.screenshot}")
    return 0


def _serve(args, found, options, title) -> int:
    site = Site(found, ensure_vendor(), title, **options)
    if len(found) == 1:
        site.prepared(0)  # a single file that cannot be read stops here, with its exit code
    try:
        server = ViewerServer(site, DEFAULT_PORT if args.port is None else args.port, verbose=args.verbose)
    except UsageError:
        if args.port is not None:
            raise
        server = ViewerServer(site, 0, verbose=args.verbose)
    previous = {}
    if threading.current_thread() is threading.main_thread():
        # Ctrl-C stops even when started with SIGINT ignored (a background job); `kill` stops as cleanly.
        previous = {sig: signal.signal(sig, _interrupt) for sig in (signal.SIGINT, signal.SIGTERM)}
    try:  # entered before the URL is printed, so an interrupt right after it still stops cleanly
        print(f"infuse view: serving {title} at {server.url}  (Ctrl-C stops)", flush=True)
        if not args.no_open and _has_display():
            webbrowser.open(server.url)
        while server.thread.is_alive():
            server.thread.join(0.5)
    except KeyboardInterrupt:
        pass
    finally:
        server.close()
        for sig, handler in previous.items():
            signal.signal(sig, handler)
    print("infuse view: stopped", flush=True)
    return 0


def run(args) -> int:
    if not 0.0 <= args.low_confidence <= 1.0:
        raise UsageError("--low-confidence must be between 0 and 1")
    if args.port is not None and not 0 <= args.port <= 65535:
        raise UsageError("--port must be between 0 and 65535")
    found = sources(args.path, args.targets)
    saved_map = read_map(args.map_file) if args.map_file else None  # a bad map file stops before anything is shown
    options = {"mapper": args.mapper, "saved_map": saved_map, "low_confidence": args.low_confidence}
    title = Path(args.path).resolve().name
    if args.html and args.screenshot:
        raise UsageError("give --html or --screenshot, not both")
    if args.html:
        return _write_html(args, found, options, title)
    if args.screenshot:
        return _screenshot(args, found, options, title)
    return _serve(args, found, options, title)
