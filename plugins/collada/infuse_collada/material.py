"""What colour a COLLADA surface has: ``<bind_material>`` → ``<material>`` → ``<effect>`` diffuse.

A primitive names a material symbol; the instance's ``<instance_material>`` binds it to a
``<material>`` (a material with that id when nothing binds it), whose ``<instance_effect>``
holds a ``profile_COMMON`` technique. Its ``<diffuse>`` (``<emission>`` for ``<constant>``) is a
colour, or a texture: a ``<sampler2D>`` → ``<surface>`` → ``<image>`` chain (COLLADA 1.4) or an
``<instance_image>`` (1.5). A texture is used when its image file is found beside the document
(by its relative path, else by its file name) and Pillow can read it: its texels are the colour;
otherwise the surface gets :data:`DEFAULT_COLOR`. Colours are taken as linear RGBA; ``<transparent>``/``<transparency>``
give the alpha (``A_ONE`` or ``RGB_ZERO`` modes).
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from urllib.parse import unquote, urlparse

import numpy as np

from infuse.texture import TEXTURE_SIZE, bilinear, decode_image

from .document import Document

#: Linear RGBA of a surface whose colour is a texture that is not found, or that has no material.
DEFAULT_COLOR = (0.8, 0.8, 0.8, 1.0)
_SHADERS = ("lambert", "phong", "blinn", "constant")


@dataclass
class Look:
    """A surface's linear RGBA ``color``; its diffuse texture ``image`` (a file beside the document,
    or ``None``) with the ``TEXCOORD`` set it reads (``None``: the primitive's first) and, when
    the texture was named but not found, the file name it names (``missing``)."""

    color: np.ndarray
    image: Path | None = None
    texcoord_set: int | None = None
    missing: str | None = None


def look(doc: Document, instance, symbol: str | None) -> Look:
    """The look of the primitives naming material ``symbol`` under ``instance`` (an
    ``<instance_controller>`` or ``<instance_geometry>``)."""
    material, binding = _material(doc, instance, symbol)
    effect_ref = material.find("instance_effect") if material is not None else None
    effect = doc.ids.get((effect_ref.get("url") or "").lstrip("#")) if effect_ref is not None else None
    technique = None if effect is None else next(
        (t for t in effect.iterfind("profile_COMMON/technique/*") if t.tag in _SHADERS), None)
    if technique is None:
        return Look(np.array(DEFAULT_COLOR))
    channel = technique.find("emission" if technique.tag == "constant" else "diffuse")
    color = np.array(DEFAULT_COLOR)
    image, texcoord_set, missing = None, None, None
    if channel is not None and channel.find("color") is not None:
        color = _color(doc, channel.find("color"))
    elif channel is not None and channel.find("texture") is not None:
        texture = channel.find("texture")
        name = _image_file(doc, effect, texture.get("texture"))
        if name is not None:
            image = _beside(doc.path, name)
            missing = None if image is not None else Path(name.replace("\\", "/")).name
        texcoord_set = _texcoord_set(binding, texture.get("texcoord"))
    color[3] = _alpha(doc, technique)
    return Look(color, image, texcoord_set, missing)


def _material(doc: Document, instance, symbol: str | None):
    """The ``<material>`` bound to ``symbol`` and the ``<instance_material>`` binding it."""
    if symbol is None:
        return None, None
    for binding in instance.iterfind("bind_material/technique_common/instance_material"):
        if binding.get("symbol") == symbol:
            target = doc.ids.get((binding.get("target") or "").lstrip("#"))
            return (target if target is not None and target.tag == "material" else None), binding
    target = doc.ids.get(symbol)
    return (target if target is not None and target.tag == "material" else None), None


def _color(doc: Document, element) -> np.ndarray:
    values = doc.floats(element)
    if values.size not in (3, 4):
        raise doc.error(element, f"a colour has {values.size} values, expected 3 or 4")
    return np.clip(np.append(values, 1.0)[:4], 0.0, 1.0)


def _alpha(doc: Document, technique) -> float:
    """Opacity from a ``<transparent>`` colour (a transparency texture counts as opaque)."""
    transparent = technique.find("transparent")
    if transparent is None or transparent.find("color") is None:
        return 1.0
    amount = technique.find("transparency/float")
    factor = float(doc.floats(amount, 1)[0]) if amount is not None else 1.0
    rgba = _color(doc, transparent.find("color"))
    if transparent.get("opaque", "A_ONE") == "RGB_ZERO":
        luminance = float(rgba[:3] @ [0.212671, 0.715160, 0.072169])
        return float(np.clip(1.0 - luminance * factor, 0.0, 1.0))
    return float(np.clip(rgba[3] * factor, 0.0, 1.0))


def _image_file(doc: Document, effect, sampler_sid: str | None) -> str | None:
    """The file an effect's texture reads (the image's ``init_from``), through its newparams."""
    if not sampler_sid:
        return None
    params = {p.get("sid"): p for p in effect.iter("newparam")}
    image = None
    sampler = params.get(sampler_sid)
    if sampler is not None:
        instance = sampler.find("sampler2D/instance_image")  # COLLADA 1.5
        if instance is not None:
            image = doc.ids.get((instance.get("url") or "").lstrip("#"))
        else:
            surface = params.get((sampler.findtext("sampler2D/source") or "").strip())
            init = surface.findtext("surface/init_from") if surface is not None else None
            image = doc.ids.get((init or "").strip())
    else:
        image = doc.ids.get(sampler_sid)  # some exporters name the image directly
    if image is None or image.tag != "image":
        return None
    text = image.findtext("init_from/ref") or image.findtext("init_from")  # 1.5 wraps the URI in <ref>
    return text.strip() if text and text.strip() else None


def _beside(document: Path, uri: str) -> Path | None:
    """The image file ``uri`` names, looked for only in the document's folder (and below it)."""
    parsed = urlparse(uri)
    path = unquote(parsed.path if parsed.scheme in ("file", "") else "").replace("\\", "/")
    if not path:
        return None
    folder = document.resolve().parent
    candidates = [folder / Path(path).name]
    if parsed.scheme == "" and not Path(path).is_absolute() and ":" not in path:
        candidates.insert(0, folder / path)
    for candidate in candidates:
        try:
            resolved = candidate.resolve()
        except OSError:
            continue
        if resolved.is_file() and resolved.is_relative_to(folder):
            return resolved
    return None


def _texcoord_set(binding, texcoord: str | None) -> int | None:
    if binding is None or texcoord is None:
        return None
    for b in binding.iterfind("bind_vertex_input"):
        if b.get("semantic") == texcoord and (b.get("input_semantic") or "TEXCOORD") == "TEXCOORD":
            raw = b.get("input_set")
            return int(raw) if raw and raw.isdigit() else None
    return None
def read_image(path: Path) -> np.ndarray:
    """Linear RGBA pixels (H, W, 4) of an image file, reduced to at most :data:`TEXTURE_SIZE` a side.

    Raises ``ImportError`` without Pillow, ``OSError``/``ValueError`` when the file is unreadable.
    """
    return decode_image(path, TEXTURE_SIZE)


def sample(pixels: np.ndarray, uv: np.ndarray) -> np.ndarray:
    """(N, 4) bilinear samples of ``pixels`` (H, W, 4) at COLLADA texture coordinates ``uv`` (N, 2):
    origin at the image's bottom left, repeated outside 0..1."""
    return bilinear(pixels, np.mod(uv[:, 0], 1.0), 1.0 - np.mod(uv[:, 1], 1.0), wrap_edges=True)
