"""Painting primitives on a Pillow canvas: colours, capsules, dashed lines and labels that avoid each other.

Coordinates are pixels (x right, y down) of the canvas being drawn, which is usually the
supersampled one (see :mod:`infuse.render.renderer`).
"""
from __future__ import annotations

from functools import lru_cache

import numpy as np
from PIL import ImageDraw, ImageFont

RGB = tuple[int, int, int]


def mix(color: RGB, other: RGB, amount: float) -> RGB:
    """``color`` moved ``amount`` (0..1) of the way to ``other``."""
    a = min(max(float(amount), 0.0), 1.0)
    return (round(color[0] + (other[0] - color[0]) * a), round(color[1] + (other[1] - color[1]) * a),
            round(color[2] + (other[2] - color[2]) * a))


@lru_cache(maxsize=32)
def font(size: int) -> ImageFont.FreeTypeFont | ImageFont.ImageFont:
    """Pillow's bundled scalable font at ``size`` pixels (no system fonts needed)."""
    return ImageFont.load_default(size=max(int(size), 6))


def capsule(draw: ImageDraw.ImageDraw, a, b, width: float, fill: RGB, outline: RGB, edge: float) -> None:
    """A bone from ``a`` to ``b``: a line with round ends, ``width`` pixels wide inside an ``edge`` pixel outline."""
    passes = ((width + 2 * edge, outline), (width, fill)) if edge > 0 else ((width, fill),)
    for w, colour in passes:
        r = w / 2.0
        draw.line((a[0], a[1], b[0], b[1]), fill=colour, width=max(int(round(w)), 1))
        for x, y in (a, b):
            draw.ellipse((x - r, y - r, x + r, y + r), fill=colour)


def disc(draw: ImageDraw.ImageDraw, centre, radius: float, fill: RGB | None, outline: RGB | None = None, width: float = 1) -> None:
    x, y = centre
    draw.ellipse((x - radius, y - radius, x + radius, y + radius), fill=fill, outline=outline,
                 width=max(int(round(width)), 1))


def dashed_line(draw: ImageDraw.ImageDraw, a, b, fill: RGB, width: float, dash: float) -> None:
    """A line from ``a`` to ``b`` made of ``dash``-pixel dashes separated by equal gaps."""
    a, b = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    length = float(np.linalg.norm(b - a))
    if length < 1e-6:
        return
    starts = np.arange(0.0, length, 2 * dash)
    ends = np.minimum(starts + dash, length)
    unit = (b - a) / length
    for s, e in zip(a + starts[:, None] * unit, a + ends[:, None] * unit):
        draw.line((s[0], s[1], e[0], e[1]), fill=fill, width=max(int(round(width)), 1))


class LabelPlacer:
    """Draws short texts near anchor points, trying a few spots around each so labels do not overlap.

    Labels are placed in the order given, so earlier ones win the free spots.
    """

    def __init__(self, draw: ImageDraw.ImageDraw, bounds: tuple[float, float, float, float]):
        self.draw = draw
        self.bounds = bounds
        self.boxes: list[tuple[float, float, float, float]] = []

    def _free(self, box) -> bool:
        x0, y0, x1, y1 = box
        bx0, by0, bx1, by1 = self.bounds
        if x0 < bx0 or y0 < by0 or x1 > bx1 or y1 > by1:
            return False
        return all(x1 <= o[0] or x0 >= o[2] or y1 <= o[1] or y0 >= o[3] for o in self.boxes)

    def place(self, anchor, text: str, fnt, fill: RGB, halo: RGB, gap: float) -> bool:
        """Put ``text`` beside ``anchor`` (right, left, above, below, then diagonals, then further out).

        Returns False, drawing nothing, when every spot overlaps a placed label or leaves the
        bounds: in a crowd (finger joints) overlapping names would be unreadable anyway.
        """
        left, top, right, bottom = self.draw.textbbox((0, 0), text, font=fnt)
        w, h = right - left, bottom - top
        x, y = anchor
        spots = []
        for reach in (1.0, 2.2):
            g = gap * reach
            spots += [(x + g, y - h / 2), (x - g - w, y - h / 2), (x - w / 2, y - g - h), (x - w / 2, y + g),
                      (x + g, y - g - h), (x - g - w, y - g - h), (x + g, y + g), (x - g - w, y + g)]
        for sx, sy in spots:
            if self._free((sx, sy, sx + w, sy + h)):
                self.boxes.append((sx, sy, sx + w, sy + h))
                stroke = max(1, int(round(fnt.size / 7)))
                self.draw.text((sx - left, sy - top), text, font=fnt, fill=fill, stroke_width=stroke, stroke_fill=halo)
                return True
        return False
