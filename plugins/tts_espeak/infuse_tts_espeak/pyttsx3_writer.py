"""pyttsx3 (driver ``espeak``) writes the WAV, in a child process.

A child process because libespeak-ng keeps one synthesis callback per process: pyttsx3's driver and
the timing pass (:mod:`.library`) would take it from each other. The child also runs in parallel
with the timing pass.

pyttsx3's ``runAndWait()`` can return before the espeak driver has written the file (the driver
writes it from espeak's callback when the message ends, after the loop may have stopped), so the
child waits until the WAV on disk is complete: its header's data size matches the file size and
the size stays the same between two looks.

Run as ``python -m infuse_tts_espeak.pyttsx3_writer OUT.wav --voice en --rate 175 --volume 1.0``
with the text on standard input (UTF-8). Exit codes: 0 written, 3 pyttsx3 or espeak-ng missing,
4 timed out, 1 anything else; the reason is on standard error.
"""
from __future__ import annotations

import argparse
import os
import struct
import subprocess
import sys
import time
from pathlib import Path

POLL_S = 0.005
EXIT_MISSING = 3
EXIT_TIMEOUT = 4


def wav_data_complete(path: Path) -> bool:
    """True when ``path`` is a RIFF/WAVE file whose ``data`` chunk holds as many bytes as its header says."""
    try:
        size = path.stat().st_size
        with open(path, "rb") as f:
            head = f.read(12)
            if len(head) < 12 or head[:4] != b"RIFF" or head[8:12] != b"WAVE":
                return False
            offset = 12
            while True:
                chunk = f.read(8)
                if len(chunk) < 8:
                    return False
                chunk_id, chunk_size = chunk[:4], struct.unpack("<I", chunk[4:])[0]
                offset += 8
                if chunk_id == b"data":
                    return chunk_size > 0 and size == offset + chunk_size
                offset += chunk_size + (chunk_size & 1)
                f.seek(offset)
    except OSError:
        return False


def wait_for_complete_wav(path: Path, timeout_s: float) -> bool:
    """Wait until ``path`` is a complete WAV whose size no longer changes; False on timeout."""
    deadline = time.monotonic() + timeout_s
    last_size = -1
    while time.monotonic() < deadline:
        if wav_data_complete(path):
            size = path.stat().st_size
            if size == last_size:
                return True
            last_size = size
        time.sleep(POLL_S)
    return False


def default_timeout_s(text: str) -> float:
    """Generous: espeak-ng synthesizes many times faster than real time."""
    return 20.0 + len(text) / 200.0


def _child(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description="write speech to a WAV with pyttsx3 (driver espeak)")
    parser.add_argument("out")
    parser.add_argument("--voice", default="en")
    parser.add_argument("--rate", type=int, default=175)
    parser.add_argument("--volume", type=float, default=1.0)
    parser.add_argument("--timeout", type=float, default=None)
    args = parser.parse_args(argv)
    text = sys.stdin.buffer.read().decode("utf-8")
    out = Path(args.out)
    try:
        import pyttsx3
    except ImportError as exc:
        print(f"pyttsx3 is not installed ({exc}); install it with: pip install pyttsx3", file=sys.stderr)
        return EXIT_MISSING
    try:
        engine = pyttsx3.init(driverName="espeak")
    except Exception as exc:  # pyttsx3 reports a missing libespeak-ng as a RuntimeError at import/init
        print(f"pyttsx3 could not start its espeak driver: {type(exc).__name__}: {exc}", file=sys.stderr)
        return EXIT_MISSING
    engine.setProperty("voice", args.voice)
    engine.setProperty("rate", args.rate)
    engine.setProperty("volume", args.volume)
    out.unlink(missing_ok=True)
    engine.save_to_file(text, str(out))
    engine.runAndWait()
    timeout = args.timeout if args.timeout is not None else default_timeout_s(text)
    if not wait_for_complete_wav(out, timeout):
        print(f"pyttsx3 did not finish {out.name} within {timeout:g} s", file=sys.stderr)
        return EXIT_TIMEOUT
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(0)  # skip interpreter teardown: pyttsx3's espeak driver can abort when libespeak-ng shuts down


def start(text: str, out: Path, voice: str, rate: int, volume: float, timeout_s: float) -> subprocess.Popen:
    """Start the child writing ``text`` to ``out``; finish with :func:`finish`."""
    proc = subprocess.Popen(
        [sys.executable, "-m", "infuse_tts_espeak.pyttsx3_writer", str(out), "--voice", voice, "--rate", str(int(rate)),
         "--volume", repr(float(volume)), "--timeout", repr(float(timeout_s))],
        stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    assert proc.stdin is not None  # piped
    try:
        proc.stdin.write(text.encode("utf-8"))
        proc.stdin.close()
    except BrokenPipeError:  # the child failed before reading; finish() reports why
        pass
    proc.stdin = None  # written and closed: communicate() must not touch it again
    return proc


def finish(proc: subprocess.Popen, timeout_s: float) -> tuple[int, str]:
    """Wait for the child; returns its exit code and standard error (the child is killed on timeout)."""
    try:
        _, err = proc.communicate(timeout=timeout_s + 10.0)
    except subprocess.TimeoutExpired:
        proc.kill()
        _, err = proc.communicate()
        return EXIT_TIMEOUT, f"pyttsx3 did not finish within {timeout_s:g} s"
    return proc.returncode, err.decode("utf-8", "replace").strip()


if __name__ == "__main__":
    sys.exit(_child())
