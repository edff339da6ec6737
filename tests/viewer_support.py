"""Shared pieces of the viewer tests: headless Chromium through Playwright, test data written here
(a wave clip for a corpus character, a tone as WAV, a targets sidecar) and GLB facts read independently."""
from __future__ import annotations

import io
import json
import os
import shutil
import struct
import tempfile
import wave
from contextlib import contextmanager
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

import infuse
from infuse import quaternions as quat
from infuse.kinematics import forward_kinematics
from infuse.mapping import map_skeleton

CHROMIUM = Path("/usr/bin/chromium")
CHROMIUM_ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                 "--disable-background-networking", "--disable-component-update", "--disable-sync"]
UNDER_CI = os.environ.get("CI", "").lower() == "true"
VIEWPORT = {"width": 800, "height": 520}


def require_browser():
    """Playwright's sync API; fails under CI and skips elsewhere when Chromium or Playwright is missing."""
    try:
        from playwright.sync_api import sync_playwright
    except ImportError:
        sync_playwright = None
    if sync_playwright is None or not CHROMIUM.is_file():
        message = "the viewer tests need Debian's chromium and playwright (make setup installs both)"
        if UNDER_CI:
            pytest.fail(message)
        pytest.skip(message)
    return sync_playwright


@contextmanager
def chromium_context():
    """A persistent Chromium context on a fresh profile folder, removed afterwards."""
    sync_playwright = require_browser()
    profile = tempfile.mkdtemp(prefix="infuse-chromium-")
    try:
        with sync_playwright() as p:
            context = p.chromium.launch_persistent_context(
                profile, executable_path=str(CHROMIUM), args=CHROMIUM_ARGS, headless=True, viewport=VIEWPORT)
            try:
                yield context
            finally:
                context.close()
    finally:
        shutil.rmtree(profile, ignore_errors=True)


class ViewerPage:
    """One page of the viewer with its console errors recorded; a context manager that closes it."""

    def __init__(self, context, url: str):
        self.page = context.new_page()
        self.errors: list[str] = []
        self.page.on("console", lambda m: self.errors.append(m.text) if m.type == "error" else None)
        self.page.on("pageerror", lambda e: self.errors.append(str(e)))
        self.page.goto(url, timeout=120_000)
        self.page.wait_for_function("window.infuseViewer && (window.infuseViewer.ready || window.infuseViewer.error)",
                                    timeout=120_000)
        error = self.page.evaluate("window.infuseViewer.error")
        assert error is None, error

    def state(self) -> dict:
        return self.page.evaluate("window.infuseViewer.state()")

    def frames(self) -> None:
        """Wait for a frame drawn after everything done so far (the page draws only after a change)."""
        self.page.evaluate("window.infuseViewer.nextFrame()")

    def show_time(self, seconds: float) -> None:
        self.page.evaluate(f"window.infuseViewer.pause(); window.infuseViewer.setTime({seconds})")
        self.frames()

    def screenshot(self, path: Path | None = None) -> np.ndarray:
        """(H, W, 3) uint8 pixels of the page (also saved to ``path``)."""
        data = self.page.screenshot(path=str(path) if path else None)
        return np.asarray(Image.open(io.BytesIO(data)).convert("RGB"))

    def clip_list(self) -> list[str]:
        return self.page.eval_on_selector_all("#clips li", "items => items.map(li => li.dataset.clip)")

    def close(self) -> None:
        self.page.close()

    def __enter__(self) -> "ViewerPage":
        return self

    def __exit__(self, *exc) -> None:
        self.close()  # a page left open keeps rendering and slows every later one


def changed_fraction(a: np.ndarray, b: np.ndarray, threshold: int = 24) -> float:
    """Fraction of pixels whose colour differs by more than ``threshold`` in some channel."""
    return float(np.mean(np.abs(a.astype(np.int16) - b.astype(np.int16)).max(axis=-1) > threshold))


def glb_animation_names(path: Path) -> list[str]:
    """Animation names of a binary glTF, read from its JSON chunk here (not through infuse)."""
    data = path.read_bytes()
    length = struct.unpack_from("<I", data, 12)[0]
    doc = json.loads(data[20:20 + length])
    return [a.get("name") or f"animation{i}" for i, a in enumerate(doc.get("animations", []))]


def add_wave_clip(asset, name: str = "wave", fps: float = 30.0, seconds: float = 2.0):
    """The asset with one clip: the left arm lowered, the right arm raised and waving, the chest swaying.

    Each turn is about a world axis in the rest pose (+Z is the character's front), so it does not
    depend on how the file orients its joints.
    """
    sk = asset.skeleton
    mapping = map_skeleton(asset)
    frames = int(round(seconds * fps)) + 1
    t = np.arange(frames) / fps
    rest_rot, _ = forward_kinematics(sk, sk.rest_rotations[None], sk.rest_translations[:1])
    local = np.broadcast_to(sk.rest_rotations, (frames, sk.num_joints, 4)).copy()

    def turn(canonical: str, angles: np.ndarray) -> None:
        j = sk.index[mapping[canonical]]
        parent = rest_rot[0, sk.parents[j]] if sk.parents[j] >= 0 else quat.identity()
        world = quat.from_axis_angle(np.broadcast_to([0.0, 0.0, 1.0], (frames, 3)), angles)
        local[:, j] = quat.multiply(quat.multiply(quat.conjugate(parent), quat.multiply(world, parent)), local[:, j])

    turn("l_shoulder", np.full(frames, -1.2))
    turn("r_shoulder", np.full(frames, -0.9))
    turn("r_elbow", -0.5 + 0.6 * np.sin(2 * np.pi * 1.5 * t))
    turn("spine2", 0.08 * np.sin(2 * np.pi * 0.5 * t))
    root = np.broadcast_to(sk.rest_translations[0], (frames, 3)).copy()
    asset.motions = {name: infuse.Motion(sk, fps, local, root, name=name)}
    return asset


def write_tone(path: Path, seconds: float = 2.0, rate: int = 16000, hz: float = 440.0) -> Path:
    """A mono 16-bit WAV sine tone."""
    samples = (0.3 * 32767 * np.sin(2 * np.pi * hz * np.arange(int(seconds * rate)) / rate)).astype("<i2")
    with wave.open(str(path), "wb") as out:
        out.setnchannels(1)
        out.setsampwidth(2)
        out.setframerate(rate)
        out.writeframes(samples.tobytes())
    return path


TARGETS = {
    "gaze": {"position": [0.8, 1.6, 1.0]},
    "reach_right": {"times": [0.0, 1.0, 2.0], "positions": [[-0.6, 1.5, 0.4], [-0.5, 1.9, 0.5], [-0.6, 1.5, 0.4]],
                    "from": "r_wrist"},
}
