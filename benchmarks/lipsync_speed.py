"""A minute of speech from text to WAV and viseme tracks: how long it takes (target: under 1 s).

Runs the default TTS engine (pyttsx3 writes the WAV in a child process while libespeak-ng times
it: in this process the first time, in a fresh child process afterwards) and the lip sync of all
15 Meta/Oculus visemes at 30 fps, and prints the wall-clock times of the first run and of the later
runs (median). For scale it also times the dominance
blend written as a plain Python loop over samples and phonemes, checks that it gives the same
weights, and prints how many times faster the vectorized version is.

    python benchmarks/lipsync_speed.py [--repeat 3] [--fps 30]
"""
from __future__ import annotations

import argparse
import math
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np

from infuse.speech import tts_engine
from infuse_lipsync import coarticulation as co
from infuse_lipsync.lipsync import LipSyncSettings, viseme_curves
from infuse_lipsync.tables import dominance_arrays

TEXT = (
    "Every morning the ferry leaves the harbour at seven, and every morning the same small crowd waits on the pier. "
    "There is the baker with two baskets of bread, the teacher who reads on the crossing, and a boy who counts the "
    "gulls. The captain rings the bell twice, the ropes come loose, and the engine begins its slow, patient song. "
    "Halfway across, the island appears out of the mist: first the lighthouse, then the church, then the long white "
    "wall of the school. Nobody says much. The water is grey and calm, and the air smells of salt and diesel. When the "
    "ferry bumps against the island pier, the boy shouts the number of gulls he has counted, and everybody pretends "
    "to be surprised. In the evening the ferry brings them all back again, tired and quiet, with empty baskets and "
    "full heads. The captain has done this for thirty years. He says the sea is never the same twice, and that is "
    "why he has never been bored. Some winters the crossing is rough, and the spray flies over the deck; some summers "
    "it is so still that the ferry seems to glide on glass. Tomorrow, as always, he will ring the bell twice."
)


def loop_blend(times, starts, ends, targets, alpha, theta_before, theta_after, rest, band=4):
    """The dominance blend, one sample and one phoneme at a time (the reference for the ratio)."""
    out = []
    P = len(starts)
    for t in times:
        j = 0
        while j < P - 1 and ends[j] < t:
            j += 1
        num = [0.0] * len(rest)
        total = 0.0
        for i in range(max(0, j - band), min(P, j + band + 1)):
            if t < starts[i]:
                d = math.exp(-theta_before[i] * (starts[i] - t)) * alpha[i]
            else:
                d = math.exp(-theta_after[i] * max(t - ends[i], 0.0)) * alpha[i]
            total += d
            for c in range(len(rest)):
                num[c] += d * targets[i][c]
        out.append([n / total for n in num] if total > 1e-12 else list(rest))
    return np.array(out)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--fps", type=float, default=30.0)
    args = parser.parse_args()
    engine = tts_engine("espeak")
    settings = LipSyncSettings(fps=args.fps)
    synth_s, tracks_s = [], []
    with tempfile.TemporaryDirectory() as folder:
        wav = Path(folder) / "minute.wav"
        for _ in range(args.repeat):
            started = time.perf_counter()
            utterance = engine.synthesize(TEXT, wav)
            middle = time.perf_counter()
            times, weights, vs = viseme_curves(utterance, "oculus", settings)
            synth_s.append(middle - started)
            tracks_s.append(time.perf_counter() - middle)
    total = [a + b for a, b in zip(synth_s, tracks_s)]
    print(f"speech: {utterance.duration_s:.1f} s of audio, {len(utterance.phonemes)} phonemes, {len(utterance.words)} words "
          f"({utterance.meta.get('wav_writer')}: {utterance.meta.get('alignment')})")
    print(f"viseme tracks ({len(vs.channels)} channels x {len(times)} frames at {args.fps:g} fps): "
          f"{statistics.median(tracks_s) * 1000:.1f} ms")
    # the first synthesis of a process is timed in the process; later ones in a fresh child process
    runs = [("first run", total[:1], synth_s[:1])]
    if len(total) > 1:
        runs.append((f"later runs (median of {len(total) - 1})", total[1:], synth_s[1:]))
    for label, totals, synths in runs:
        figure = statistics.median(totals)
        verdict = "under" if figure < 1.0 else "OVER"
        print(f"{label}: text -> WAV + timings {statistics.median(synths) * 1000:.0f} ms, total {figure * 1000:.0f} ms "
              f"for {utterance.duration_s:.1f} s of speech ({verdict} the 1 s target)")

    # the blend alone, vectorized against the per-sample loop
    starts, ends, names = utterance.phoneme_arrays()
    rows = np.array([vs.phonemes.index(n) for n in names])
    _, alpha, before, after = dominance_arrays()
    blend_args = (times, starts, ends, vs.targets[rows], alpha[rows], before[rows], after[rows], vs.rest)
    started = time.perf_counter()
    fast = co.dominance_blend(*blend_args)
    fast_s = time.perf_counter() - started
    started = time.perf_counter()
    slow = loop_blend(*blend_args)
    slow_s = time.perf_counter() - started
    print(f"dominance blend: vectorized {fast_s * 1000:.2f} ms, per-sample Python loop {slow_s * 1000:.1f} ms "
          f"({slow_s / fast_s:.0f}x faster; max difference {np.abs(fast - slow).max():.1e})")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
