"""Live characters against the wall clock: frame time, latency and frames missed at 60 fps, and the
service under a flood of bad input.

For 1, 10 and 50 characters (Mixamo Xbots and Ready Player Me avatars in a ring, each with its
locomotion pack): everyone idles, blinks, breathes and looks at a neighbour with saccades; a third of
them walk in toward the middle of the ring or back out to their places, a third speak (lip sync) and
nod, round after round (every 4 s). The scene runs in a :class:`infuse.live.LiveScene` for
``--seconds`` (default 60), and the benchmark prints:

- frame time: the milliseconds the loop spends evaluating a frame (mean, median, 99th percentile, max
  over the blocks evaluated, per frame), the loop thread's CPU milliseconds per frame (what a machine
  to itself would take) and the part of it outside the controllers (the runtime's and the loop's own
  bookkeeping, taking the frames out), and the block size the loop settled on (1: frame by frame);
- latency: from a BML message (a nod) to the wall-clock moment the frame whose time is the block's start
  is shown, for :data:`PROBES` messages at random points of a frame (target: at most one frame plus
  10 ms; how many took longer is printed too);
- the same over a WebSocket: the servers of ``infuse serve`` run in process, and a client sends the nod's
  BML and times it to the first binary frame at or after the frame the reply names;
- frames missed: frames evaluated too late to be shown on time (target: none up to 10 characters), and
  how late the frames shown were (99th percentile and max, ms after they were due);
- encoding the last frame as a JSON ``frame`` message and as a binary message (mean milliseconds).

Then ``infuse serve``'s servers run in process with 10 characters while one client sends 1,000 bad
messages a second (malformed JSON, unknown characters, malformed BML) and another subscribes to the
pose stream and never reads: the frames missed meanwhile, and the replies counted.

    python benchmarks/live.py [--seconds 60] [--counts 1,10,50] [--no-flood]

Wall-clock figures on a shared 2-core machine; the load average is printed with them. The corpus is read
from INFUSE_CORPUS (default ../shared/corpus from the repository root).
"""
from __future__ import annotations

import argparse
import asyncio
import json
import math
import multiprocessing
import os
import random
import threading
import time
import timeit
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

import infuse
from infuse.errors import UsageError
from infuse.live import LiveScene
from infuse.mapping import map_skeleton
from infuse.scene import Scene

REPO = Path(__file__).resolve().parents[1]
CORPUS = Path(os.environ.get("INFUSE_CORPUS", REPO.parent / "shared" / "corpus")).resolve()
FPS = 60.0
#: BML messages timed per cast, through LiveScene.bml and over a WebSocket each.
PROBES = 60
CAST = (("runxaway-models/Xbot.glb", "locomotion-male"), ("talkinghead/avatars/brunette-t.glb", "locomotion-female"))
BML_NS = "http://www.bml-initiative.org/bml/bml-1.0"
LINES = ("Good morning. Did you sleep well?", "The storm kept me up for a while, though.",
         "Shall we walk down to the river after breakfast?", "Careful, the coffee is still hot.")


def build(count: int) -> Scene:
    """``count`` characters in a ring of radius 1.5 m + 0.25 m per character, facing the centre."""
    scene = Scene(fps=FPS, quiet=True)
    prepared = []
    for path, pack in CAST:
        asset = infuse.load(CORPUS / path)
        prepared.append((infuse.Character(Path(path).stem, asset, map_skeleton(asset)), pack))
    radius = 1.5 + 0.25 * count
    for k in range(count):
        character, pack = prepared[k % 2]
        angle = 2 * math.pi * k / max(count, 1)
        scene.add_character(character, f"c{k}", position=(radius * math.sin(angle), 0.0, radius * math.cos(angle)),
                            facing=(0.0, 0.0, 0.0) if count > 1 else None, packs=[pack])
    return scene


def direct(live: LiveScene, count: int, stop: threading.Event) -> None:
    """Rounds of behaviour until ``stop``: gazes with saccades once, then walks, speech and nods."""
    names = list(live.scene.characters)
    for k, name in enumerate(names):
        if count > 1:
            live.bml(name, f'<bml xmlns="{BML_NS}" xmlns:sbm="http://ict.usc.edu" id="look{k}">'
                           f'<gazeShift id="g" target="{names[(k + 1) % count]}"/><sbm:saccade id="s" mode="listen"/></bml>')
    homes = {name: (float(live.scene.runtime.rig(name).position[0]), float(live.scene.runtime.rig(name).position[2]))
             for name in names}  # where each stands in the ring, before any walk
    inside: set[str] = set()  # those that walked in toward the middle last
    round_ = 0
    while not stop.is_set():
        for k, name in enumerate(names):
            role = (k + round_) % 3
            try:
                if role == 0:  # in toward the middle, then back out to its place in the ring
                    x, z = homes[name]
                    live.walk_to(name, (x, z) if name in inside else (0.3 * x, 0.3 * z))
                    inside ^= {name}
                elif role == 1:
                    live.say(name, LINES[(k + round_) % len(LINES)])
                    live.nod(name)
            except UsageError:
                if stop.is_set():  # the scene stopped while this call waited
                    return
                raise
        round_ += 1
        stop.wait(4.0)


def latency(live: LiveScene, samples: int = PROBES) -> list[float]:
    """Seconds from a nod's BML to the moment the first frame at or after its start is shown, at random
    points of a frame."""
    shown: list[tuple[int, float]] = []
    ready = threading.Condition()

    def keep(frame):
        with ready:
            shown.append((frame.index, frame.wall_s))
            ready.notify_all()
    unsubscribe = live.on_frame(keep)
    name = next(iter(live.scene.characters))
    out = []
    for k in range(samples):
        time.sleep(random.uniform(0.05, 0.2))
        submitted = time.perf_counter()
        block = live.bml(name, f'<bml xmlns="{BML_NS}" id="probe{k}"><head id="h" lexeme="NOD"/></bml>')[0]
        index = round(live.scene.scheduler.blocks[block].start_s * live.fps)
        with ready:
            ready.wait_for(lambda: shown and shown[-1][0] >= index, 5.0)
            out.append(next((wall for i, wall in shown if i >= index), math.inf) - submitted)
            shown.clear()
    unsubscribe()
    return out


async def ws_latency(port: int, character: str, samples: int = PROBES) -> list[float]:
    """Seconds from sending a nod's BML over the WebSocket to receiving the first binary frame at or after
    the frame its reply says it starts on (received before the reply or after it), at random points of
    a frame."""
    from websockets.asyncio.client import connect

    out = []
    async with connect(f"ws://127.0.0.1:{port}/", max_size=None) as ws:
        await ws.send(json.dumps({"type": "subscribe", "frames": True, "format": "binary", "feedback": "none"}))
        for k in range(samples):
            await asyncio.sleep(random.uniform(0.05, 0.2))
            sent = time.perf_counter()
            await ws.send(json.dumps({"type": "bml", "character": character, "request": k, "bml":
                                      f'<bml xmlns="{BML_NS}" id="wsprobe{k}"><head id="h" lexeme="NOD"/></bml>'}))
            start, frames = None, []  # frames received since: (index, seconds), the reply may come after some
            while start is None or not frames or frames[-1][0] < start:
                message = await ws.recv()
                if isinstance(message, bytes):
                    size = int.from_bytes(message[:4], "little")
                    frames.append((json.loads(message[4:4 + size])["frame"], time.perf_counter()))
                elif json.loads(message).get("request") == k:
                    start = json.loads(message)["frame"]
            out.append(next(at for index, at in frames if index >= start) - sent)
    return out


def ws_latency_of(port: int, character: str) -> list[float]:
    """:func:`ws_latency` run to its end (in a process of its own, as a client program is: a client in the
    server's process would wait for the loop's thread to hand it Python's interpreter lock)."""
    return asyncio.run(ws_latency(port, character))


def run_count(count: int, seconds: float) -> dict:
    from infuse_live.frames import binary_frame, frame_text
    from infuse_live.hub import Hub
    from infuse_live.server import LiveServer

    started = time.perf_counter()
    scene = build(count)
    live = LiveScene(scene)
    live.warm_up()
    load_s = time.perf_counter() - started
    stop = threading.Event()
    server = LiveServer(lambda loop: Hub(live, loop), port=0, http_port=None)
    serving = threading.Thread(target=lambda: asyncio.run(server.run()), daemon=True)
    serving.start()
    server.ready.wait(30)
    client = ProcessPoolExecutor(1, mp_context=multiprocessing.get_context("spawn"))  # a program of its own,
    client.submit(int).result(120)  # started before the loop is
    with live:
        director = threading.Thread(target=direct, args=(live, count, stop), daemon=True)
        director.start()
        time.sleep(max(seconds - 2 * PROBES * 0.15, 1.0))  # the probes take about 0.15 s each
        delays = latency(live)
        ws_delays = client.submit(ws_latency_of, server.port, next(iter(scene.characters))).result(120)
        stop.set()
        director.join(10)
        summary = live.stats.summary()
    client.shutdown()
    server.shutdown()
    serving.join(10)
    ms = np.asarray(live.stats.evaluate_ms)
    frame = live.last_frame
    json_ms, binary_ms = (timeit.timeit(lambda: encode(frame), number=200) / 200 * 1e3 for encode in (frame_text, binary_frame))
    return {"count": count, "load_s": load_s, "shown": summary["shown"], "missed": summary["missed"],
            "block": summary["block_frames"], "cpu_ms": summary["cpu_mean_ms"],
            "outside_ms": summary["cpu_mean_ms"] - summary["controllers_cpu_mean_ms"],
            "mean_ms": float(ms.mean()), "p50_ms": float(np.median(ms)), "p99_ms": float(np.percentile(ms, 99)),
            "late_p99_ms": summary["late_p99_ms"], "late_max_ms": summary["late_max_ms"],
            "max_ms": float(ms.max()), "latency_ms": np.array(delays) * 1e3, "ws_latency_ms": np.array(ws_delays) * 1e3,
            "json_ms": json_ms, "binary_ms": binary_ms}


def flood(seconds: float) -> dict:
    """The servers in process with 10 idle characters; 1,000 bad messages a second and a client that never reads."""
    from websockets.asyncio.client import connect

    from infuse_live.hub import Hub
    from infuse_live.server import LiveServer

    live = LiveScene(build(10))
    server = LiveServer(lambda loop: Hub(live, loop), port=0, http_port=None)
    thread = threading.Thread(target=lambda: asyncio.run(server.run()), daemon=True)
    thread.start()
    server.ready.wait(30)
    bad = ["{not json", json.dumps({"type": "bml", "character": "nobody", "bml": "<bml/>"}),
           json.dumps({"type": "bml", "character": "c0", "bml": "<bml id='x'><head></bml>"}), json.dumps({"type": "dance"})]

    async def clients() -> dict:
        url = f"ws://127.0.0.1:{server.port}/"
        async with connect(url, max_queue=1) as stalled, connect(url, max_size=None) as sender:
            await stalled.send(json.dumps({"type": "subscribe", "frames": True, "feedback": "all"}))
            replies = 0

            async def count():
                nonlocal replies
                async for text in sender:
                    replies += json.loads(text)["type"] == "error"
            counter = asyncio.create_task(count())
            before, start, sent = live.stats.summary(), time.perf_counter(), 0
            while time.perf_counter() - start < seconds:
                for _ in range(10):
                    await sender.send(bad[sent % len(bad)])
                    sent += 1
                await asyncio.sleep(max(0.0, start + sent / 1000.0 - time.perf_counter()))
            flooded_s = time.perf_counter() - start
            after = live.stats.summary()
            while replies < sent and time.perf_counter() - start < seconds + 60.0:
                await asyncio.sleep(0.05)
            all_answered_s = time.perf_counter() - start
            counter.cancel()
            return {"sent": sent, "replies": replies, "seconds": flooded_s, "answered_s": all_answered_s,
                    "shown": after["shown"] - before["shown"], "missed": after["missed"] - before["missed"]}

    with live:
        time.sleep(1.0)
        result = asyncio.run(clients())
    server.shutdown()
    thread.join(10)
    return result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--seconds", type=float, default=60.0, help="seconds each cast runs live (default 60)")
    parser.add_argument("--counts", default="1,10,50", help="numbers of characters (default 1,10,50)")
    parser.add_argument("--no-flood", action="store_true", help="skip the bad-input flood")
    args = parser.parse_args()
    random.seed(0)
    print(f"live at {FPS:g} fps for {args.seconds:g} s per cast; load average {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores")
    print("| characters | load + warm-up s | frame ms mean | p50 | p99 | max | CPU ms mean | outside controllers | block | "
          "frames shown | missed | late ms p99 | max | latency ms median | max | over target | over WebSocket median | max | "
          "over target | JSON frame ms | binary frame ms |")
    print("|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    target_ms = 1e3 / FPS + 10.0
    for count in (int(c) for c in args.counts.split(",")):
        r = run_count(count, args.seconds)
        print(f"| {count} | {r['load_s']:.1f} | {r['mean_ms']:.2f} | {r['p50_ms']:.2f} | {r['p99_ms']:.2f} | "
              f"{r['max_ms']:.2f} | {r['cpu_ms']:.2f} | {r['outside_ms']:.2f} | {r['block']} | {r['shown']} | {r['missed']} | {r['late_p99_ms']:.1f} | {r['late_max_ms']:.1f} | "
              f"{np.median(r['latency_ms']):.1f} | {r['latency_ms'].max():.1f} | {(r['latency_ms'] > target_ms).sum()} of {len(r['latency_ms'])} | "
              f"{np.median(r['ws_latency_ms']):.1f} | {r['ws_latency_ms'].max():.1f} | "
              f"{(r['ws_latency_ms'] > target_ms).sum()} of {len(r['ws_latency_ms'])} | "
              f"{r['json_ms']:.2f} | {r['binary_ms']:.3f} |", flush=True)
    if not args.no_flood:
        f = flood(min(args.seconds, 10.0))
        print(f"flood: {f['sent']} bad messages in {f['seconds']:.1f} s, {f['replies']} error replies "
              f"(all by {f['answered_s']:.1f} s); meanwhile {f['shown']} frames shown, {f['missed']} missed "
              f"(10 idle characters, one client never reading)")
    print(f"load average after: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
