"""Child process of :mod:`.isolated`: one libespeak-ng synthesis from a fresh library state.

``python -m infuse_tts_espeak.timing_child --voice en --rate 175 --volume 100 [--ssml] [--library PATH]``
with the text on standard input (UTF-8). On success: one JSON line ``{"sample_rate", "samples",
"events": [[kind, sample, audio_ms, text_position, length, name], ...]}`` then the samples as
little-endian int16. On failure: exit code 2 (a setting libespeak-ng refuses), 3 (library missing)
or 1, and one JSON line ``{"error", "place", "problem"}``. Standard library only, to start fast.
"""
from __future__ import annotations

import argparse
import json
import sys

from .library import BadSetting, EspeakError, LibraryMissing, espeak


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description="synthesize with libespeak-ng events from a fresh process")
    parser.add_argument("--voice", default="en")
    parser.add_argument("--rate", type=int, default=175)
    parser.add_argument("--volume", type=int, default=100)
    parser.add_argument("--ssml", action="store_true")
    parser.add_argument("--library", default=None)
    args = parser.parse_args(argv)
    text = sys.stdin.buffer.read().decode("utf-8")
    out = sys.stdout.buffer
    try:
        synthesis = espeak(args.library).synthesize(text, args.voice, args.rate, args.volume, ssml=args.ssml)
    except EspeakError as exc:
        code = 2 if isinstance(exc, BadSetting) else 3 if isinstance(exc, LibraryMissing) else 1
        out.write(json.dumps({"error": type(exc).__name__, "place": exc.place, "problem": str(exc)}).encode() + b"\n")
        out.flush()
        return code
    samples = synthesis.samples
    if sys.byteorder != "little":
        samples.byteswap()
    head = {"sample_rate": synthesis.sample_rate, "samples": len(samples),
            "events": [[e.kind, e.sample, e.audio_ms, e.text_position, e.length, e.name] for e in synthesis.events]}
    out.write(json.dumps(head).encode() + b"\n")
    out.write(samples.tobytes())
    out.flush()
    return 0


if __name__ == "__main__":
    sys.exit(main())
