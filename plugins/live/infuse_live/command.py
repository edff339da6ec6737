"""``infuse serve SCENE``: the scene's characters live, driven over WebSocket and HTTP, streamed out.

Loads the characters (and objects, and timed blocks, which play from the moment the service starts) of a
scene file, infuses their packs once, then evaluates the scene against the wall clock
(:class:`infuse.live.LiveScene`) while the servers (:mod:`infuse_live.server`) take BML in and send
feedback, poses, speech audio and VMC out. Ctrl-C (or SIGTERM) stops it.
"""
from __future__ import annotations

import asyncio
import signal
import sys
import threading
from pathlib import Path

from infuse.errors import UsageError
from infuse.live import LiveScene
from infuse.scene.command import build_scene
from infuse.scene.scenefile import read_scene_file

from .hub import Hub
from .server import HOST, LiveServer

DEFAULT_PORT = 8770


def add_arguments(p) -> None:
    p.add_argument("scene", metavar="SCENE", help="scene file (.toml or .xml): characters, objects, blocks to play at start")
    p.add_argument("--fps", type=float, default=60.0, help="frames per second of the live loop (default 60)")
    p.add_argument("--host", default=HOST, help=f"address to listen on (default {HOST}: this machine only)")
    p.add_argument("--port", type=int, default=DEFAULT_PORT, help=f"WebSocket port (default {DEFAULT_PORT}; 0: a free one)")
    p.add_argument("--http-port", type=int, metavar="N",
                   help="HTTP port: the live viewer page and POST (default: the WebSocket port + 1; 0: a free one)")
    p.add_argument("--token", help="clients must send this token (?token=... or Authorization: Bearer ...)")
    p.add_argument("--vmc", metavar="HOST:PORT", action="append", default=[],
                   help="send one character over the VMC protocol (OSC/UDP) to a receiver, e.g. 127.0.0.1:39539 (repeatable)")
    p.add_argument("--vmc-character", metavar="NAME", help="the character sent over VMC (default: the first)")
    p.add_argument("--allow-add", action="store_true",
                   help="let clients add characters from files this machine can read (an 'add' message)")
    p.add_argument("--quiet", action="store_true", help="do not print warnings (clients still get them as feedback)")


def _endpoint(text: str) -> tuple[str, int]:
    host, sep, port = text.rpartition(":")
    if not sep or not host or not port.isdigit() or not 0 < int(port) < 65536:
        raise UsageError(f"--vmc {text!r}: expected HOST:PORT, e.g. 127.0.0.1:39539")
    return host, int(port)


def _interrupt(signum, frame):
    raise KeyboardInterrupt


def run(args) -> int:
    if not (args.fps > 0 and args.fps <= 240):
        raise UsageError("--fps must be between 0 and 240 frames per second")
    for option in ("port", "http_port"):
        value = getattr(args, option)
        if value is not None and not 0 <= value <= 65535:
            raise UsageError(f"--{option.replace('_', '-')} must be between 0 and 65535")
    http_port = args.http_port if args.http_port is not None else (args.port + 1 if args.port else 0)
    receivers = [_endpoint(v) for v in args.vmc]
    spec = read_scene_file(args.scene)
    spec.fps = float(args.fps)
    scene = build_scene(spec, quiet=args.quiet)
    if not scene.characters:
        raise UsageError(f"{args.scene}: the scene has no character to serve")
    vmc_character = args.vmc_character or next(iter(scene.characters))
    scene.character(vmc_character)
    if args.host not in (HOST, "localhost", "::1") and not args.token:
        print(f"infuse serve: warning: listening on {args.host} without --token: anyone who reaches it can drive the scene",
              file=sys.stderr)

    from infuse.three import ensure_vendor

    from .page import LiveSite
    from .vmc import VmcSender

    live = LiveScene(scene)
    site = LiveSite(scene, ensure_vendor(), Path(args.scene).name)
    server = LiveServer(lambda loop: Hub(live, loop, lambda name: f"/characters/{name}.glb", args.allow_add), args.host,
                        args.port, http_port, args.token, site)
    senders = [VmcSender(live, vmc_character, host, port) for host, port in receivers]
    previous = {}
    if threading.current_thread() is threading.main_thread():
        previous = {sig: signal.signal(sig, _interrupt) for sig in (signal.SIGINT, signal.SIGTERM)}
    try:
        asyncio.run(_serve(server, live, senders, args))
    except KeyboardInterrupt:
        pass
    finally:
        live.stop()
        for sender in senders:
            sender.close()
        for sig, handler in previous.items():
            signal.signal(sig, handler)
    summary = live.stats.summary()
    print(f"infuse serve: stopped after {summary['shown']} frames ({summary['missed']} missed)", flush=True)
    return 0


async def _serve(server: LiveServer, live: LiveScene, senders, args) -> None:
    task = asyncio.create_task(server.run())
    while not server.ready.is_set():
        if task.done():
            task.result()  # a port that cannot be bound stops here, with its message
        await asyncio.sleep(0.01)
    live.start()
    for sender in senders:
        sender.start()
    loop = asyncio.get_running_loop()
    for sig in (signal.SIGINT, signal.SIGTERM):
        try:  # stopped by the loop itself, not by an exception raised wherever the signal lands
            loop.add_signal_handler(sig, server.shutdown)
        except (NotImplementedError, RuntimeError, ValueError):  # no loop signal handlers here: KeyboardInterrupt
            pass
    vmc = "".join(f"  vmc {s.host}:{s.port} ({s.character})" for s in senders)
    print(f"infuse serve: {len(live.scene.characters)} characters at {live.fps:g} fps; "
          f"ws://{args.host}:{server.port}/  http://{args.host}:{server.http_port}/{vmc}  (Ctrl-C stops)", flush=True)
    try:
        while not task.done():  # the loop thread failing stops the service, with its error
            await asyncio.wait({task}, timeout=0.25)
            if live.error is not None:
                raise live.error
        task.result()
    finally:
        server.shutdown()
        if not task.done():
            await task
