"""What the HTTP side of ``infuse serve`` answers to GET: the live viewer page, its scripts and models.

The page (``static/live.html`` and ``static/live.js`` beside this module) loads three.js from ``/vendor/...``, each
character's model from ``/characters/<name>.glb`` (the character as the scene holds it, at rest, written
once on first request), then connects to the WebSocket and plays the pose stream and the speech audio.
"""
from __future__ import annotations

import json
import tempfile
import threading
from dataclasses import replace
from importlib import resources
from pathlib import Path

import infuse
from infuse.three import Vendor

LIVE_SPECIFIER = "infuse-live"


def static_text(name: str) -> str:
    """A file of the live page (``static/`` beside this module)."""
    return resources.files("infuse_live").joinpath("static", name).read_text(encoding="utf-8")


class LiveSite:
    """GET answers for the live page: ``answer(path) -> (body, mime) | None``."""

    def __init__(self, scene, vendor: Vendor, title: str):
        self.scene = scene
        self.vendor = vendor
        self.vendor_files = {rel: spec for spec, rel in vendor.modules.items()}
        imports = {spec: f"/vendor/{rel}" for spec, rel in vendor.modules.items()}
        imports[LIVE_SPECIFIER] = "/static/live.js"
        page = static_text("live.html").replace("{{TITLE}}", title.replace("<", "&lt;"))
        self.page = page.replace("{{IMPORTS}}", json.dumps({"imports": imports}).replace("</", "<\\/")).encode("utf-8")
        self.script = static_text("live.js").encode("utf-8")
        self._models: dict[str, bytes] = {}
        self._lock = threading.Lock()

    def answer(self, path: str) -> tuple[bytes, str] | None:
        if path in ("/", "/index.html"):
            return self.page, "text/html; charset=utf-8"
        if path == "/static/live.js":
            return self.script, "text/javascript; charset=utf-8"
        if path.startswith("/vendor/") and path[len("/vendor/"):] in self.vendor_files:
            return self.vendor.path(self.vendor_files[path[len("/vendor/"):]]).read_bytes(), "text/javascript; charset=utf-8"
        if path.startswith("/characters/") and path.endswith(".glb"):
            name = path[len("/characters/"):-len(".glb")]
            if name in self.scene.characters:
                return self.model(name), "model/gltf-binary"
        return None

    def model(self, name: str) -> bytes:
        """The character ``name`` as a GLB: its mesh and skeleton at rest, no clips."""
        with self._lock:
            if name not in self._models:
                asset = self.scene.characters[name].character.asset
                with tempfile.TemporaryDirectory(prefix="infuse-serve-") as tmp:
                    out = Path(tmp) / f"{name}.glb"
                    infuse.save(replace(asset, motions={}), out)
                    self._models[name] = out.read_bytes()
            return self._models[name]
