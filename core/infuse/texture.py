"""Textures sampled at mesh vertices: readers colour :class:`~infuse.mesh.SkinnedMesh` vertices with them.

Pixels are linear RGBA in 0..1, an (H, W, 4) array whose row 0 is the image's top. Images are reduced to
at most :data:`TEXTURE_SIZE` pixels a side (colours are kept per vertex, so finer detail would not show).
sRGB is decoded with the exact piecewise curve. Texture coordinates are given as fractions of the image,
``u`` to the right and ``v`` down from the top left corner; each format's own convention (origin,
wrapping) is applied by its reader.
"""
from __future__ import annotations

import io
from pathlib import Path

import numpy as np

from . import limits

#: Largest side (pixels) a texture is reduced to before sampling at the vertices.
TEXTURE_SIZE = 256


def srgb_to_linear(c: np.ndarray) -> np.ndarray:
    """sRGB-encoded values in 0..1 -> linear (the exact piecewise curve)."""
    c = np.asarray(c, dtype=np.float64)
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def decode_image(source: bytes | str | Path, size: int = TEXTURE_SIZE) -> np.ndarray:
    """Linear RGBA pixels (H, W, 4) of an encoded image (bytes) or image file, at most ``size`` a side.

    Raises ``ImportError`` without Pillow, ``OSError``/``ValueError`` when the image is unreadable or
    declares more than :data:`infuse.limits.MAX_IMAGE_PIXELS` pixels (checked before decoding).
    """
    from PIL import Image

    try:
        opened = Image.open(io.BytesIO(source) if isinstance(source, (bytes, bytearray)) else source)
    except Image.DecompressionBombError as exc:
        raise ValueError(str(exc)) from None
    with opened as img:
        width, height = img.size
        if width * height > limits.MAX_IMAGE_PIXELS:
            raise ValueError(f"an image of {width} x {height} pixels is over the limit of {limits.MAX_IMAGE_PIXELS:,} "
                             "(infuse.limits.MAX_IMAGE_PIXELS)")
        img.draft("RGB", (size, size))  # JPEG decodes straight at a reduced scale
        converted = img.convert("RGBA")
        converted.thumbnail((size, size))
        rgba = np.asarray(converted, dtype=np.float64) / 255.0
    rgba[..., :3] = srgb_to_linear(rgba[..., :3])
    return rgba


def bilinear(pixels: np.ndarray, u: np.ndarray, v: np.ndarray, wrap_edges: bool = False) -> np.ndarray:
    """(N, 4) bilinear samples of ``pixels`` (H, W, 4) at image fractions ``u``, ``v`` (N,), in 0..1 from
    the top left corner. Between the outermost pixel centres and the edge, ``wrap_edges`` blends with the
    opposite edge (a repeating texture); otherwise the edge pixels are held."""
    h, w = pixels.shape[:2]
    x, y = np.asarray(u) * w - 0.5, np.asarray(v) * h - 0.5
    x0, y0 = np.floor(x), np.floor(y)
    fx, fy = (x - x0)[:, None], (y - y0)[:, None]
    x0, y0 = x0.astype(np.int64), y0.astype(np.int64)
    if wrap_edges:
        x0, y0 = x0 % w, y0 % h
        x1, y1 = (x0 + 1) % w, (y0 + 1) % h
    else:
        x1, y1 = np.clip(x0 + 1, 0, w - 1), np.clip(y0 + 1, 0, h - 1)
        x0, y0 = np.clip(x0, 0, w - 1), np.clip(y0, 0, h - 1)
    top = pixels[y0, x0] * (1 - fx) + pixels[y0, x1] * fx
    bottom = pixels[y1, x0] * (1 - fx) + pixels[y1, x1] * fx
    return top * (1 - fy) + bottom * fy
