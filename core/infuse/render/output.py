"""Image and video files from a :class:`~infuse.render.renderer.Renderer`: PNG, filmstrip PNG, GIF and MP4.

Every file is written atomically (a temporary file beside it, renamed when complete). MP4 frames
are piped to ``ffmpeg`` (set ``INFUSE_FFMPEG`` to use a particular binary).
"""
from __future__ import annotations

import math
import os
import shutil
import subprocess
from pathlib import Path
from typing import Sequence

import numpy as np
from PIL import Image, ImageDraw

from ..atomic import atomic_path
from ..errors import MissingFeatureError, UnusableInputError, UsageError
from .camera import Camera
from .draw import font
from ..progress import Progress
from .renderer import Renderer, Style
from .scene import Figure

SUFFIXES = (".png", ".gif", ".mp4")
STILL_SIZE = (640, 480)
STRIP_TILE = (240, 360)
GIF_MAX_FPS = 25.0  # GIF delays are in 1/100 s and many players clamp short ones; 25 fps is exact
STRIP_COLUMNS = 8


def check_suffix(path: str | Path) -> str:
    """The output kind (``".png"``, ``".gif"``, ``".mp4"``) of ``path``; :class:`UsageError` otherwise."""
    suffix = Path(path).suffix.lower()
    if suffix not in SUFFIXES:
        raise UsageError(f"{path}: cannot render to {suffix or 'a file without extension'!r}; use .png, .gif or .mp4")
    return suffix


def ffmpeg_path() -> str:
    """The ffmpeg executable, or :class:`MissingFeatureError` saying how to install it."""
    chosen = os.environ.get("INFUSE_FFMPEG") or shutil.which("ffmpeg")
    if not chosen or not (os.path.isfile(chosen) and os.access(chosen, os.X_OK)):
        raise MissingFeatureError(None, "MP4 output needs ffmpeg: install it (Debian/Ubuntu: sudo apt-get install ffmpeg; "
                                        "macOS: brew install ffmpeg) or render to .gif or .png")
    return chosen


def select_times(
    figures: Sequence[Figure],
    *,
    frame: int | None = None,
    start: float | None = None,
    end: float | None = None,
    fps: float | None = None,
    count: int | None = None,
    still: bool = False,
) -> np.ndarray:
    """Output times in seconds.

    - ``still``: one time: frame ``frame`` of the first figure, else ``start``, else 0.
    - ``count``: ``count`` times evenly spread from ``start`` to ``end`` (a filmstrip).
    - otherwise every ``1 / fps`` s from ``start`` (default 0) to ``end`` (default: the end of the
      longest figure); ``fps`` defaults to the first figure's rate.
    """
    first = figures[0]
    duration = max(f.duration for f in figures)
    if frame is not None:
        if not 0 <= frame < first.num_frames:
            raise UsageError(f"frame {frame} is out of range: the clip has frames 0..{first.num_frames - 1}")
        if not still:
            raise UsageError("--frame picks one still image; use --start/--end for a range")
        return np.array([frame / first.fps])
    lo = 0.0 if start is None else float(start)
    hi = duration if end is None else float(end)
    if not (math.isfinite(lo) and math.isfinite(hi)) or lo < 0:
        raise UsageError(f"start {lo} s must be a finite time >= 0")
    if lo > duration + 1e-9:
        raise UsageError(f"start {lo:g} s is past the end of the clip ({duration:.3f} s)")
    hi = min(hi, duration)
    if hi < lo:
        raise UsageError(f"end {hi:g} s comes before start {lo:g} s")
    if still:
        return np.array([lo])
    if count is not None:
        if count < 1:
            raise UsageError("a filmstrip needs at least 1 frame")
        return np.linspace(lo, hi, count)
    rate = float(fps or first.fps)
    if not rate > 0:
        raise UsageError(f"fps must be positive, got {fps}")
    return lo + np.arange(int(np.floor((hi - lo) * rate + 1e-9)) + 1) / rate


def write_png(renderer: Renderer, path: str | Path, index: int = 0) -> Path:
    """One frame as a PNG."""
    with atomic_path(path) as tmp:
        renderer.image(index).save(tmp, format="PNG", optimize=True)
    return Path(path)


def filmstrip(renderer: Renderer, title: str = "", columns: int = STRIP_COLUMNS, progress: Progress | None = None) -> Image.Image:
    """Every frame of ``renderer`` as tiles, left to right then top to bottom, under ``title``."""
    n = len(renderer)
    cols = min(n, columns)
    rows = -(-n // cols)
    tw, th = renderer.size
    head = round(max(12, th / 22) * 1.7) if title else 0
    sheet = Image.new("RGB", (tw * cols, th * rows + head), renderer.style.background)
    draw = ImageDraw.Draw(sheet)
    for k in range(n):
        sheet.paste(renderer.image(k, labels=k == 0), ((k % cols) * tw, head + (k // cols) * th))
        if k % cols:
            x = (k % cols) * tw
            draw.line((x, head + (k // cols) * th, x, head + (k // cols + 1) * th - 1), fill=renderer.style.grid)
        if progress:
            progress.advance()
    if title:
        draw.text((head * 0.35, head * 0.18), title, font=font(round(head * 0.62)), fill=renderer.style.text)
    return sheet


def write_strip(renderer: Renderer, path: str | Path, title: str = "", progress: Progress | None = None) -> Path:
    """A filmstrip PNG of every frame of ``renderer`` (see :func:`filmstrip`)."""
    sheet = filmstrip(renderer, title, progress=progress)
    with atomic_path(path) as tmp:
        sheet.save(tmp, format="PNG", optimize=True)
    return Path(path)


def _shared_palette(renderer: Renderer, samples: int = 8) -> Image.Image:
    """A 255-colour palette from a few frames spread over the clip, so colours do not flicker."""
    picks = np.unique(np.linspace(0, len(renderer) - 1, min(samples, len(renderer))).round().astype(int))
    tiles = [renderer.image(int(k)) for k in picks]
    w, h = tiles[0].size
    montage = Image.new("RGB", (w, h * len(tiles)))
    for k, tile in enumerate(tiles):
        montage.paste(tile, (0, k * h))
    return montage.quantize(colors=255, method=Image.Quantize.MEDIANCUT)


def write_gif(renderer: Renderer, path: str | Path, fps: float, progress: Progress | None = None) -> Path:
    """An endlessly looping GIF, one image per renderer frame at ``fps`` (GIF delays are whole 1/100 s)."""
    palette = _shared_palette(renderer)
    frames = []
    for k in range(len(renderer)):
        frames.append(renderer.image(k).quantize(palette=palette, dither=Image.Dither.NONE))
        if progress:
            progress.advance()
    with atomic_path(path) as tmp:
        frames[0].save(tmp, format="GIF", save_all=True, append_images=frames[1:], duration=10 * max(round(100.0 / fps), 1),
                       loop=0, optimize=False, disposal=1)
    return Path(path)


def write_mp4(renderer: Renderer, path: str | Path, fps: float, progress: Progress | None = None) -> Path:
    """An H.264 MP4 (yuv420p, plays everywhere) of every renderer frame at ``fps``, encoded by ffmpeg."""
    exe = ffmpeg_path()
    w, h = renderer.size
    with atomic_path(path) as tmp:
        cmd = [exe, "-hide_banner", "-loglevel", "error", "-y",
               "-f", "rawvideo", "-pix_fmt", "rgb24", "-s", f"{w}x{h}", "-r", f"{fps:g}", "-i", "-",
               "-an", "-vf", "pad=ceil(iw/2)*2:ceil(ih/2)*2", "-c:v", "libx264", "-preset", "medium", "-crf", "20",
               "-pix_fmt", "yuv420p", "-movflags", "+faststart", "-f", "mp4", str(tmp)]
        proc = subprocess.Popen(cmd, stdin=subprocess.PIPE, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
        assert proc.stdin is not None and proc.stderr is not None  # both piped
        try:
            for k in range(len(renderer)):
                proc.stdin.write(renderer.image(k).tobytes())
                if progress:
                    progress.advance()
            proc.stdin.close()
        except BrokenPipeError:
            pass  # ffmpeg stopped early; its exit status and message say why
        except BaseException:
            proc.kill()
            proc.wait()
            raise
        err = proc.stderr.read().decode(errors="replace").strip()
        if proc.wait() != 0:
            last = err.splitlines()[-1] if err else f"exit status {proc.returncode}"
            raise UnusableInputError(path, f"ffmpeg could not encode the video: {last}")
    return Path(path)


def render(
    figures: Sequence[Figure],
    path: str | Path,
    *,
    frame: int | None = None,
    start: float | None = None,
    end: float | None = None,
    strip: int | None = None,
    fps: float | None = None,
    size: tuple[int, int] | None = None,
    camera: Camera = Camera(),
    overlay: bool = False,
    title: str = "",
    style: Style = Style(),
    progress: bool | None = None,
) -> Path:
    """Render ``figures`` to ``path`` (.png, .gif or .mp4) and return the path.

    A PNG is one still (``frame``, else ``start``, else the first frame) or, with ``strip=N``, a
    filmstrip of N frames evenly spread over ``start``..``end`` (``size`` is then one tile's; the
    camera follows a figure that travels more than half its height, unless ``camera.follow`` says).
    GIF and MP4 play ``start``..``end`` (seconds; default the whole clip) at ``fps`` (default the
    first figure's rate; GIF at most 25). Figures go side by side, one panel each at one scale,
    unless ``overlay``. ``progress``: a progress bar on stderr (``None``: only on a terminal).
    """
    if not figures:
        raise UsageError("nothing to render")
    kind = check_suffix(path)
    if kind == ".mp4":
        ffmpeg_path()  # fail before any drawing when ffmpeg is missing
    if strip is not None and kind != ".png":
        raise UsageError("--strip makes a PNG filmstrip; use an output ending in .png")
    panels = 1 if overlay else len(figures)
    if strip is not None:
        times = select_times(figures, start=start, end=end, count=strip)
        size = size or (STRIP_TILE[0] * panels, STRIP_TILE[1])
    else:
        if kind != ".png" and fps is None:
            fps = min(figures[0].fps, GIF_MAX_FPS) if kind == ".gif" else min(figures[0].fps, 60.0)
        times = select_times(figures, frame=frame, start=start, end=end, fps=fps, still=kind == ".png")
        size = size or (max(STILL_SIZE[0], 400 * panels), STILL_SIZE[1])
    tile_title = "" if strip is not None else title
    renderer = Renderer(figures, times, overlay=overlay, camera=camera, size=size, title=tile_title, style=style,
                        follow_travel=0.5 if strip is not None else 2.0)  # small tiles: keep the figure big
    if kind == ".png" and strip is None:
        return write_png(renderer, path)
    with Progress(len(renderer), f"render {Path(path).name}", enabled=progress) as bar:
        if kind == ".png":
            return write_strip(renderer, path, title, bar)
        rate = figures[0].fps if fps is None else fps  # set above for every moving output
        if kind == ".gif":
            return write_gif(renderer, path, rate, bar)
        return write_mp4(renderer, path, rate, bar)
