"""A PNG of the viewer page, taken in headless Chromium through Playwright (``infuse view --screenshot``).

The browser is the system's Chromium (``$INFUSE_CHROMIUM``, else ``chromium`` on the PATH); Playwright
drives it and never downloads one. Each run uses a fresh, temporary browser profile.
"""
from __future__ import annotations

import os
import shutil
import tempfile
from pathlib import Path

from infuse.atomic import atomic_path
from infuse.errors import MissingFeatureError, UsageError

CHROMIUM_ARGS = ("--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                 "--disable-background-networking", "--disable-component-update", "--disable-sync")
ENV_CHROMIUM = "INFUSE_CHROMIUM"


def chromium_path() -> Path:
    """The Chromium executable, or :class:`MissingFeatureError` saying how to install it."""
    found = os.environ.get(ENV_CHROMIUM) or shutil.which("chromium") or shutil.which("chromium-browser")
    if not found or not Path(found).is_file():
        raise MissingFeatureError(None, f"screenshots need Chromium: run `make setup` (Debian package chromium) "
                                        f"or set {ENV_CHROMIUM} to a Chromium executable")
    return Path(found)


def take(url: str, out: str | Path, width: int = 1000, height: int = 640, time: float | None = None,
         clip: str | None = None, timeout_s: float = 120.0) -> Path:
    """Open ``url`` (a viewer page), show ``clip`` (default: the first) at ``time`` seconds (default:
    the first frame), paused, and write a PNG of the page to ``out`` atomically."""
    try:
        from playwright.sync_api import Error as PlaywrightError
        from playwright.sync_api import sync_playwright
    except ImportError:
        raise MissingFeatureError(None, "screenshots need Playwright for Python: run `make setup`") from None
    executable = chromium_path()
    profile = tempfile.mkdtemp(prefix="infuse-chromium-")
    try:
        with sync_playwright() as p:
            context = p.chromium.launch_persistent_context(
                profile, executable_path=str(executable), args=list(CHROMIUM_ARGS), headless=True,
                viewport={"width": width, "height": height})
            try:
                page = context.new_page()
                page.goto(url, timeout=timeout_s * 1000)
                page.wait_for_function("window.infuseViewer && (window.infuseViewer.ready || window.infuseViewer.error)",
                                       timeout=timeout_s * 1000)
                error = page.evaluate("window.infuseViewer.error")
                if error:
                    raise UsageError(f"the page could not show the file: {error}")
                if clip is not None:
                    clips = page.evaluate("window.infuseViewer.state().clips")
                    if clip not in clips:
                        raise UsageError(f"no clip named {clip!r}; the file has: {', '.join(clips) or 'none'}")
                    page.evaluate("name => window.infuseViewer.selectClip(name)", clip)
                page.evaluate("async t => { window.infuseViewer.pause(); window.infuseViewer.setTime(t); "
                              "await window.infuseViewer.nextFrame(); }", time or 0.0)
                with atomic_path(out) as tmp:
                    page.screenshot(path=str(tmp), type="png")
            finally:
                context.close()
    except PlaywrightError as exc:
        raise MissingFeatureError(None, f"headless Chromium failed: {str(exc).splitlines()[0]}") from None
    finally:
        shutil.rmtree(profile, ignore_errors=True)
    return Path(out)
