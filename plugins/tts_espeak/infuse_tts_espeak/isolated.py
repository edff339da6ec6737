"""The timing synthesis in a fresh process, so it starts from the same state as pyttsx3's.

libespeak-ng keeps state from one utterance to the next that moves phoneme boundaries by a few
samples (the same text synthesized twice in one process differs slightly): only two syntheses that
both start from a freshly initialised library produce the same audio. pyttsx3 runs in its own fresh child
(:mod:`.pyttsx3_writer`); this module runs the timing pass in another one, in parallel.

The child is :mod:`.timing_child`.
"""
from __future__ import annotations

import json
import subprocess
import sys

import numpy as np

from infuse.errors import InputError, MissingFeatureError, UnusableInputError

from .library import Event


def start(text: str, voice: str, rate: int, volume: int, ssml: bool, library: str | None) -> subprocess.Popen:
    """Start the timing child; collect its result with :func:`finish`."""
    cmd = [sys.executable, "-m", "infuse_tts_espeak.timing_child", "--voice", voice, "--rate", str(int(rate)),
           "--volume", str(int(volume))]
    if ssml:
        cmd.append("--ssml")
    if library:
        cmd += ["--library", str(library)]
    proc = subprocess.Popen(cmd, stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    assert proc.stdin is not None  # piped
    try:
        proc.stdin.write(text.encode("utf-8"))
        proc.stdin.close()
    except BrokenPipeError:  # the child failed before reading; finish() reports why
        pass
    proc.stdin = None  # written and closed: communicate() must not touch it again
    return proc


def finish(proc: subprocess.Popen, timeout_s: float) -> tuple[np.ndarray, int, list[Event]]:
    """The child's ``(samples (N,) int16, sample_rate, events)``; its errors are raised here as infuse errors."""
    try:
        out, err = proc.communicate(timeout=timeout_s)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.communicate()
        raise UnusableInputError(None, f"espeak-ng did not finish the timing pass within {timeout_s:g} s") from None
    head, _, body = out.partition(b"\n")
    try:
        doc = json.loads(head) if head else {}
    except json.JSONDecodeError:
        doc = {}
    if proc.returncode != 0 or "events" not in doc:
        problem = doc.get("problem") or err.decode("utf-8", "replace").strip()[-500:] or f"exit code {proc.returncode}"
        if proc.returncode == 2:
            raise InputError(None, doc.get("place"), problem)
        if proc.returncode == 3:
            raise MissingFeatureError(None, problem)
        raise UnusableInputError(None, f"the espeak-ng timing pass failed: {problem}")
    samples = np.frombuffer(body, dtype="<i2")
    if len(samples) != doc["samples"]:
        raise UnusableInputError(None, f"the espeak-ng timing pass returned {len(samples)} of {doc['samples']} samples")
    events = [Event(k, int(s), int(ms), int(pos), int(n), name) for k, s, ms, pos, n, name in doc["events"]]
    return samples.astype(np.int16), int(doc["sample_rate"]), events

