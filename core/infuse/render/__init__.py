"""Preview renders of skeletons and motions: PNG stills and filmstrips, GIF and MP4.

Inputs are :class:`Figure` objects (a skeleton and its global joint positions per frame, in the
core frame: metres, +Y up, +Z forward, +X the character's left) with optional :class:`Marker`
targets. Quick use::

    from infuse.render import Figure, render
    render([Figure.from_motion(motion)], "walk.gif")

Figures are drawn side by side at one scale (or overlaid), as depth-sorted stick figures with the
left side lighter and the right side darker than the figure's colour, over a ground grid with
shadows and the root's trail.
"""
from __future__ import annotations

from .camera import PROJECTIONS, VIEWS, Camera
from .output import SUFFIXES, check_suffix, ffmpeg_path, filmstrip, render, select_times, write_gif, write_mp4, write_png, write_strip
from ..progress import Progress
from .renderer import Renderer, Style
from .scene import LEFT, PALETTE, RIGHT, STYLES, Figure, Marker, default_sides, drawable_meshes, sides_from_mapping

__all__ = [
    "PROJECTIONS", "VIEWS", "Camera", "SUFFIXES", "check_suffix", "ffmpeg_path", "filmstrip", "render", "select_times",
    "write_gif", "write_mp4", "write_png", "write_strip", "Progress", "Renderer", "Style", "LEFT", "PALETTE", "RIGHT",
    "STYLES", "Figure", "Marker", "default_sides", "drawable_meshes", "sides_from_mapping",
]
