"""FBX material colours: the diffuse colour, and the diffuse texture when its image can be had.

A ``Material`` gives ``DiffuseColor`` (or the older ``Diffuse``) times ``DiffuseFactor``, taken as
linear RGB, and ``Opacity`` (else ``1 - TransparencyFactor``) as alpha. A ``Texture`` connected to
the material's ``DiffuseColor`` property replaces the colour; its image comes from the ``Video``
under it: the bytes embedded in ``Content``, else a file of that name beside the ``.fbx`` (in its
folder, the folder its relative name gives, or the exporter's ``<name>.fbm`` media folder; never
outside the ``.fbx``'s folder). Images are decoded by Pillow, reduced to :data:`TEXTURE_SIZE`
pixels a side and converted from sRGB to linear. Texture coordinates have their origin at the
image's bottom left corner and repeat (``WrapModeU/V`` 1 clamps).
"""
from __future__ import annotations

import base64
import binascii
from dataclasses import dataclass
from pathlib import Path, PureWindowsPath

import numpy as np

from infuse.texture import TEXTURE_SIZE, bilinear, decode_image

from .document import Document, FbxObject

#: Largest image file read beside the .fbx (bytes).
MAX_IMAGE_BYTES = 64 << 20

DEFAULT_COLOR = (0.8, 0.8, 0.8, 1.0)


@dataclass
class Texture:
    pixels: np.ndarray  # (H, W, 4) linear RGBA, row 0 at the top of the image
    clamp_u: bool
    clamp_v: bool


def _numbers(obj: FbxObject, name: str) -> list[float] | None:
    values = obj.props.get(name)
    if not values or not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in values):
        return None
    out = [float(v) for v in values]
    return out if all(np.isfinite(out)) else None


def base_color(material: FbxObject | None) -> np.ndarray:
    """(4,) linear RGBA of a material (:data:`DEFAULT_COLOR` without one)."""
    if material is None:
        return np.array(DEFAULT_COLOR)
    rgb = _numbers(material, "DiffuseColor") or _numbers(material, "Diffuse")
    rgb = rgb[:3] if rgb is not None and len(rgb) >= 3 else DEFAULT_COLOR[:3]
    factor = _numbers(material, "DiffuseFactor")
    out = np.array(rgb) * (factor[0] if factor else 1.0)
    opacity = _numbers(material, "Opacity")
    transparency = _numbers(material, "TransparencyFactor")
    alpha = opacity[0] if opacity else 1.0 - (transparency[0] if transparency else 0.0)
    return np.clip(np.append(out, alpha), 0.0, 1.0)


class Textures:
    """The diffuse textures of a document's materials, decoded once each; reasons for any not used go to ``warnings``."""

    def __init__(self, doc: Document, warnings: list[str]):
        self.doc = doc
        self.folder = Path(doc.path).resolve().parent
        self.warnings = warnings
        self._cache: dict[int, Texture | None] = {}

    def diffuse(self, material: FbxObject | None) -> Texture | None:
        if material is None:
            return None
        textures = [t for t, _ in self.doc.children_of(material.id, "Texture", "DiffuseColor")]
        if not textures:
            return None
        tex = textures[0]
        if tex.id not in self._cache:
            self._cache[tex.id] = self._load(tex)
        return self._cache[tex.id]

    def _load(self, tex: FbxObject) -> Texture | None:
        videos = [v for v, _ in self.doc.children_of(tex.id, "Video")]
        data = _content(videos[0]) if videos else None
        names = [_record_text(o, key) for o in [tex] + videos[:1]
                 for key in ("RelativeFilename", "FileName", "Filename")]
        if data is None:
            path = self._beside([n for n in names if n])
            if path is None:
                shown = next((n for n in names if n), "")
                self.warnings.append(f"texture {tex.name!r} ({PureWindowsPath(shown).name or 'no file name'}) "
                                     "is neither embedded nor beside the file: its material's colour is used")
                return None
        from PIL import Image  # only files with textures pay for importing Pillow

        try:
            pixels = decode_image(data if data is not None else path.read_bytes(), TEXTURE_SIZE)
        except (OSError, ValueError, SyntaxError, Image.DecompressionBombError) as exc:  # what Pillow raises for images it cannot read
            self.warnings.append(f"texture {tex.name!r} is not used: its image cannot be decoded ({exc})")
            return None
        wrap_u, wrap_v = tex.props.get("WrapModeU", [0]), tex.props.get("WrapModeV", [0])
        return Texture(pixels, bool(wrap_u and wrap_u[0] == 1), bool(wrap_v and wrap_v[0] == 1))

    def _beside(self, names: list[str]) -> Path | None:
        """An existing image file the texture names, inside the .fbx's folder."""
        stem = Path(self.doc.path).stem
        for name in names:
            pure = PureWindowsPath(name.replace("/", "\\"))
            if not pure.name:
                continue
            candidates = [self.folder / pure.name, self.folder / f"{stem}.fbm" / pure.name]
            if not pure.anchor:
                candidates.insert(0, self.folder.joinpath(*pure.parts))
            for path in candidates:
                try:
                    resolved = path.resolve()
                except OSError:
                    continue
                if resolved.is_relative_to(self.folder) and resolved.is_file() and resolved.stat().st_size <= MAX_IMAGE_BYTES:
                    return resolved
        return None


def _record_text(obj: FbxObject, name: str) -> str:
    rec = obj.node.find(name)
    value = rec.props[0] if rec is not None and rec.props else None
    return value if isinstance(value, str) else ""


def _content(video: FbxObject) -> bytes | None:
    """The image bytes embedded in a Video (binary: raw bytes; ASCII: base64 text), or ``None``."""
    rec = video.node.find("Content")
    if rec is None:
        return None
    raw = [p for p in rec.props if isinstance(p, (bytes, str)) and p]
    if not raw:
        return None
    if isinstance(raw[0], bytes):
        return raw[0]
    try:
        return base64.b64decode("".join(p for p in raw if isinstance(p, str)), validate=False) or None
    except (binascii.Error, ValueError):
        return None


def sample(texture: Texture, uv: np.ndarray) -> np.ndarray:
    """(N, 4) bilinear samples of ``texture`` at FBX texture coordinates ``uv`` (N, 2), origin bottom left."""
    u = np.clip(uv[:, 0], 0.0, 1.0) if texture.clamp_u else np.mod(uv[:, 0], 1.0)
    v = np.clip(uv[:, 1], 0.0, 1.0) if texture.clamp_v else np.mod(uv[:, 1], 1.0)
    return bilinear(texture.pixels, u, 1.0 - v)
