"""The viewer page: one HTML template, served with URLs or written as one offline file.

Served, the page's import map points at ``/vendor/...`` and the data lists URLs the server answers
(``/entries/<i>/info.json``, ``/entries/<i>/model.glb``, ``/entries/<i>/audio/<k>.wav``).
Offline, every module, model and sound is inlined as base64; a small classic script turns the
modules into blob URLs and installs the import map before the viewer module runs, so the file
works from ``file://`` with no network.
"""
from __future__ import annotations

import base64
import html
import json
import re
from importlib import resources

from .content import Prepared, Source
from infuse.three import Vendor

VIEWER_SPECIFIER = "infuse-viewer"
BASE64_TYPE = "application/x-infuse-base64"

# Builds blob URLs for the inlined modules, then the import map, then loads the viewer module.
_OFFLINE_LOADER = """<script>
(function () {
  var imports = {};
  document.querySelectorAll('script[data-module]').forEach(function (el) {
    var text = el.textContent.trim(), bytes;
    if (Uint8Array.fromBase64) bytes = Uint8Array.fromBase64(text);
    else {
      var binary = atob(text);
      bytes = new Uint8Array(binary.length);
      for (var i = 0; i < binary.length; i++) bytes[i] = binary.charCodeAt(i);
    }
    imports[el.dataset.module] = URL.createObjectURL(new Blob([bytes], {type: 'text/javascript'}));
  });
  var map = document.createElement('script');
  map.type = 'importmap';
  map.textContent = JSON.stringify({imports: imports});
  document.body.appendChild(map);
  var main = document.createElement('script');
  main.type = 'module';
  main.textContent = 'import "%s";';
  document.body.appendChild(main);
})();
</script>""" % VIEWER_SPECIFIER


def static_text(name: str) -> str:
    return resources.files("infuse_viewer").joinpath("static", name).read_text(encoding="utf-8")


def _json_for_script(value) -> str:
    """JSON that can sit inside a <script> element (no ``</`` closes it early)."""
    return json.dumps(value, ensure_ascii=False, separators=(",", ":")).replace("</", "<\\/")


def _fill(title: str, data: dict, blobs: str, loader: str) -> str:
    parts = {"TITLE": html.escape(title), "STYLE": static_text("viewer.css"), "DATA": _json_for_script(data),
             "BLOBS": blobs, "LOADER": loader}
    return re.sub(r"\{\{([A-Z]+)\}\}", lambda m: parts[m[1]], static_text("page.html"))  # one pass: values are not rescanned


def _blob(element_id: str | None, data: bytes, mime: str, module: str | None = None) -> str:
    attrs = f' id="{element_id}"' if element_id else ""
    attrs += f' data-module="{html.escape(module)}"' if module else ""
    encoded = base64.b64encode(data).decode("ascii")
    return f'<script type="{BASE64_TYPE}"{attrs} data-type="{mime}">{encoded}</script>'


def served_page(title: str, vendor: Vendor, sources: list[Source]) -> str:
    """The page the local server answers at ``/``."""
    imports = {spec: f"/vendor/{rel}" for spec, rel in vendor.modules.items()}
    imports[VIEWER_SPECIFIER] = "/static/viewer.js"
    entries = [{"name": s.name, "info_url": f"/entries/{i}/info.json", "glb_url": f"/entries/{i}/model.glb"}
               for i, s in enumerate(sources)]
    loader = (f'<script type="importmap">{_json_for_script({"imports": imports})}</script>\n'
              f'<script type="module">import "{VIEWER_SPECIFIER}";</script>')
    return _fill(title, {"mode": "served", "entries": entries}, "", loader)


def served_info(prepared: Prepared, index: int) -> dict:
    """``info`` with the audio keys turned into server URLs."""
    audio = {key: f"/entries/{index}/audio/{k}.wav" for k, (key, _) in enumerate(prepared.audio)}
    return dict(prepared.info, audio=audio)


def offline_page(title: str, vendor: Vendor, prepared: list[Prepared]) -> str:
    """The whole viewer in one HTML file: three.js, the viewer, every model and sound inlined."""
    blobs, entries = [], []
    for spec in vendor.modules:
        blobs.append(_blob(None, vendor.source(spec), "text/javascript", module=spec))
    blobs.append(_blob(None, static_text("viewer.js").encode("utf-8"), "text/javascript", module=VIEWER_SPECIFIER))
    for i, p in enumerate(prepared):
        blobs.append(_blob(f"glb-{i}", p.glb, "model/gltf-binary"))
        audio = {}
        for k, (key, wav) in enumerate(p.audio):
            audio[key] = f"audio-{i}-{k}"
            blobs.append(_blob(audio[key], wav.read_bytes(), "audio/wav"))
        entries.append({"name": p.info["name"], "info": dict(p.info, audio=audio), "glb": f"glb-{i}"})
    return _fill(title, {"mode": "offline", "entries": entries}, "\n".join(blobs), _OFFLINE_LOADER)
