"""Reading the recorded voice: PCM WAV (8, 16, 24 or 32-bit integers, any channel count) -> mono int16."""
from __future__ import annotations

import wave
from pathlib import Path

import numpy as np

from infuse.errors import InputError


def read_wav(path: Path) -> tuple[np.ndarray, int]:
    """``(samples (N,) int16 mono, sample_rate)``; channels are averaged."""
    try:
        with wave.open(str(path), "rb") as f:
            channels, width, rate, frames = f.getnchannels(), f.getsampwidth(), f.getframerate(), f.getnframes()
            raw = f.readframes(frames)
    except (wave.Error, EOFError) as exc:
        raise InputError(path, None, f"not a PCM WAV file ({exc}); convert it, e.g. ffmpeg -i IN -c:a pcm_s16le OUT.wav") from None
    if rate <= 0 or channels <= 0:
        raise InputError(path, "header", f"bad WAV header: {channels} channels at {rate} Hz")
    usable = len(raw) - len(raw) % (width * channels)
    raw = raw[:usable]
    if width == 1:
        data = (np.frombuffer(raw, np.uint8).astype(np.int32) - 128) << 8
    elif width == 2:
        data = np.frombuffer(raw, "<i2").astype(np.int32)
    elif width == 3:
        b = np.frombuffer(raw, np.uint8).reshape(-1, 3).astype(np.int32)
        data = ((b[:, 0] | (b[:, 1] << 8) | (b[:, 2] << 16)) << 8) >> 16  # sign-extend 24 bits, keep the top 16
    elif width == 4:
        data = np.frombuffer(raw, "<i4") >> 16
    else:
        raise InputError(path, "header", f"unsupported sample width of {8 * width} bits")
    mono = data.reshape(-1, channels).mean(axis=1)
    return np.clip(np.round(mono), -32768, 32767).astype(np.int16), rate
