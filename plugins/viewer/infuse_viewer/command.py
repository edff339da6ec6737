"""``infuse view FILE|FOLDER``: show characters and clips in a browser, or write the page as one HTML file."""
from __future__ import annotations

import os
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
from .vendor import ensure_vendor

DEFAULT_PORT = 8765


def add_arguments(p) -> None:
    p.add_argument("path", metavar="FILE|FOLDER",
                   help="a character or motion file (any readable format), or a folder: every .glb in it")
    p.add_argument("--port", type=int, help=f"port on {HOST} (default {DEFAULT_PORT}, or a free one when it is taken)")
    p.add_argument("--no-open", action="store_true", help="do not open a browser, only print the URL")
    p.add_argument("--html", metavar="OUT.html", help="write the page as one offline HTML file instead of serving it")
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
    print(f"infuse view: serving {title} at {server.url}  (Ctrl-C stops)", flush=True)
    if not args.no_open and _has_display():
        webbrowser.open(server.url)
    previous = None
    if threading.current_thread() is threading.main_thread():  # `kill` stops as cleanly as Ctrl-C
        previous = signal.signal(signal.SIGTERM, _interrupt)
    try:
        while server.thread.is_alive():
            server.thread.join(0.5)
    except KeyboardInterrupt:
        pass
    finally:
        server.close()
        if previous is not None:
            signal.signal(signal.SIGTERM, previous)
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
    if args.html:
        return _write_html(args, found, options, title)
    return _serve(args, found, options, title)
