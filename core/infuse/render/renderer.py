"""Turn figures into images, one rendered frame at a time.

A :class:`Renderer` is built for a list of output times (seconds). It gathers every figure's
joint positions at those times, frames the camera once for all of them (vectorized), and then
draws any frame on request: ground grid, root trail, shadows, bones sorted far to near (or, for a
figure with a mesh, its skinned surfaces through a z-buffer), markers, rays, contacts, highlights,
names, a title and a time/frame counter. It draws at ``supersample`` times the output size and
downsamples, which antialiases lines, text and mesh edges.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np
from PIL import Image, ImageDraw

from .camera import Camera, PanelView, frame_panels
from .draw import RGB, LabelPlacer, capsule, dashed_line, disc, font, mix
from .meshes import shade
from .raster import coverage, rasterize
from .scene import LEFT, PALETTE, RIGHT, Figure, to_rgb

WHITE: RGB = (255, 255, 255)
BLACK: RGB = (0, 0, 0)

#: Direction the light travels (core frame): from above, a little from the character's front-right,
#: so shadows fall behind and to the left, visible from every named view.
LIGHT = np.array([0.25, -1.0, -0.3]) / np.linalg.norm([0.25, -1.0, -0.3])


#: Output frames posed at once when a mesh figure is drawn frame after frame.
POSE_CHUNK = 8


def on_ground(points: np.ndarray, ground: float) -> np.ndarray:
    """Shadows (..., 3) of ``points`` cast along :data:`LIGHT` onto the plane y = ``ground``."""
    drop = (points[..., 1:2] - ground) / -LIGHT[1]
    return points + drop * LIGHT


@dataclass(frozen=True)
class Style:
    """Colours (r, g, b) and what to draw besides the figures."""

    background: RGB = (247, 246, 242)
    grid: RGB = (218, 216, 209)
    shadow: RGB = (212, 209, 201)
    text: RGB = (35, 35, 40)
    highlight: RGB = (225, 20, 140)
    contact: RGB = (20, 175, 70)
    show_grid: bool = True
    show_shadow: bool = True
    show_trail: bool = True


def default_times(figures: Sequence[Figure], fps: float | None = None) -> np.ndarray:
    """Output times covering the longest figure, at ``fps`` (default: the first figure's rate)."""
    rate = fps or figures[0].fps
    duration = max(f.duration for f in figures)
    return np.arange(int(np.floor(duration * rate + 1e-9)) + 1) / rate


def nice_spacing(length: float) -> float:
    """A round grid spacing (…, 0.25, 0.5, 1, 2.5, 5 …, metres) near a third of ``length``."""
    target = max(length / 3.0, 1e-3)
    base = 10.0 ** np.floor(np.log10(target))
    for step in (1.0, 2.5, 5.0, 10.0):
        if base * step >= target * 0.7:
            return float(base * step)
    return float(base * 10.0)


class _Panel:
    """One panel: which figures it shows, its framed view and the ground under them."""

    def __init__(self, members: list[int], rect: tuple[float, float, float, float]):
        self.members = members
        self.rect = rect  # (x, y, w, h) integer pixels of the whole panel on the (supersampled) canvas
        self._view: PanelView | None = None
        self.ground = 0.0
        self.height = 1.0  # a figure height (metres), for sizes in the scene
        self.near_range = (0.0, 1.0)
        self.grid: tuple[np.ndarray, np.ndarray] | None = None
        self.labels: list[tuple[int, float, float, str]] = []  # (figure, x, y, text) of the names at the top
        self.label_height = 0.0

    @property
    def view(self) -> PanelView:
        """The panel's framed view (set as the renderer frames its panels)."""
        if self._view is None:
            raise RuntimeError("the panel is drawn before it is framed")
        return self._view

    @view.setter
    def view(self, view: PanelView) -> None:
        self._view = view


class Renderer:
    """Draws ``figures`` at ``times`` (seconds).

    - ``overlay``: all figures in one panel; otherwise one panel each, side by side, at one scale.
    - ``camera``: view, projection and follow mode (:class:`~infuse.render.camera.Camera`).
    - ``size``: (width, height) of each output image in pixels.
    - ``title``: text at the top; ``counter``: draw "frame i/F  t s" at the bottom.
    - ``follow_travel``: with ``camera.follow=None``, follow the root when it travels more than
      this many figure heights over the rendered frames.
    """

    def __init__(
        self,
        figures: Sequence[Figure],
        times: np.ndarray | None = None,
        *,
        overlay: bool = False,
        camera: Camera = Camera(),
        size: tuple[int, int] = (640, 480),
        title: str = "",
        counter: bool = True,
        style: Style = Style(),
        supersample: int = 2,
        follow_travel: float = 2.0,
    ):
        if not figures:
            raise ValueError("nothing to render: no figures")
        self.figures = list(figures)
        self.times = default_times(self.figures) if times is None else np.atleast_1d(np.asarray(times, dtype=np.float64))
        self.camera, self.style, self.title, self.counter = camera, style, title, counter
        self.follow_travel = follow_travel
        self.size = (int(size[0]), int(size[1]))
        if min(self.size) < 16:
            raise ValueError(f"image size {self.size} is too small (at least 16x16)")
        self.ss = int(supersample)
        self.colors = [to_rgb(f.color) if f.color is not None else PALETTE[i % len(PALETTE)] for i, f in enumerate(self.figures)]
        self.frames = [f.frames_at(self.times) for f in self.figures]  # (T,) frame of each figure per output frame
        w, h = self.size[0] * self.ss, self.size[1] * self.ss
        self.font_px = max(10, round(min(self.size[1] / 34, self.size[0] / 30))) * self.ss
        self.unit = min(w / (1 if overlay else len(self.figures)), h) / 100.0  # sizes of strokes, in pixels
        self.header = round(self.font_px * 1.7) if title else 0
        self.footer = round(self.font_px * 1.6) if counter else round(self.font_px * 0.5)
        groups = [list(range(len(self.figures)))] if overlay else [[i] for i in range(len(self.figures))]
        edges = [round(k * w / len(groups)) for k in range(len(groups) + 1)]
        # panels span the full height (the title and counter are drawn over them) and tile the width exactly
        self.panels = [_Panel(g, (edges[k], 0, edges[k + 1] - edges[k], h)) for k, g in enumerate(groups)]
        self._blanks: dict[tuple[int, int], Image.Image] = {}
        self._points = [f.points()[fr] for f, fr in zip(self.figures, self.frames)]  # (T, N, 3) each
        # a spread of mesh vertices per output frame: surfaces reach past the joints (head top, soles)
        self._mesh_points = {i: f.mesh.sample_points(fr) for i, (f, fr) in enumerate(zip(self.figures, self.frames))
                             if f.mesh is not None}
        self._posed: dict[int, tuple[int, np.ndarray, np.ndarray]] = {}  # figure -> (first output frame, positions, normals)
        self._last_posed: dict[int, int] = {}
        self._frame_views()
        self._project()

    # -- preparation (vectorized over all output frames) ------------------------------------------
    def _marker_points(self, i: int) -> np.ndarray:
        fig = self.figures[i]
        if not fig.markers:
            return np.zeros((len(self.times), 0, 3))
        return np.stack([m.at(self.frames[i]) for m in fig.markers], axis=1)

    def _follow(self) -> bool:
        if self.camera.follow is not None:
            return self.camera.follow
        fig, frames = self.figures[0], self.frames[0]
        root = fig.positions[frames[0]:frames[-1] + 1, fig.root][:, [0, 2]]
        travel = float(np.max(np.ptp(root, axis=0))) if len(root) > 1 else 0.0
        return travel > self.follow_travel * max(fig.skeleton.height(), 0.1)

    def _follow_target(self, i: int) -> np.ndarray:
        """(T, 3) the figure's root, smoothed over about a second so the camera does not shake."""
        fig = self.figures[i]
        root = fig.positions[:, fig.root]
        k = max(int(round(fig.fps)) | 1, 1)
        # odd reflection at the ends keeps a steady walk exactly centred (edge padding would lag)
        padded = np.pad(root, ((k // 2, k // 2), (0, 0)), mode="reflect", reflect_type="odd") if len(root) > k // 2 \
            else np.pad(root, ((k // 2, k // 2), (0, 0)), mode="edge")
        smooth = np.stack([np.convolve(padded[:, a], np.ones(k) / k, mode="valid") for a in range(3)], axis=1)
        out = smooth[self.frames[i]]
        out[:, 1] = root[:, 1].mean()
        return out

    def _frame_views(self) -> None:
        follow = self._follow()
        contents, targets, rects = [], [], []
        pad = self.unit * 3
        for panel in self.panels:
            self._layout_labels(panel)
            pts = np.concatenate([self._points[i][:, self.figures[i].visible] for i in panel.members]
                                 + [self._mesh_points[i] for i in panel.members if i in self._mesh_points], axis=1)
            heights = [self.figures[i].skeleton.height() for i in panel.members]
            panel.height = max(max(heights), 0.1)
            lowest = float(pts[..., 1].min())
            panel.ground = 0.0 if abs(lowest) < 0.1 * panel.height else lowest
            markers = np.concatenate([self._marker_points(i) for i in panel.members], axis=1)
            target = self._follow_target(panel.members[0]) if follow else None
            if target is not None:  # a following camera frames the markers near the figure, not far-away ones
                near = np.linalg.norm(markers - target[:, None], axis=-1) <= 1.5 * panel.height
                markers = np.where(near[..., None], markers, target[:, None])
            contents.append(np.concatenate([pts, on_ground(pts, panel.ground), markers], axis=1))
            targets.append(target)
            _, _, w, h = panel.rect
            top = self.header + panel.label_height + pad
            rects.append((pad, top, w - 2 * pad, h - top - self.footer - pad))
        views = frame_panels(self.camera, contents, targets, rects)
        for panel, view, content in zip(self.panels, views, contents):
            panel.view = view
            self._make_grid(panel, content)

    def _make_grid(self, panel: _Panel, content: np.ndarray) -> None:
        """Grid lines on the ground (y = ground) covering the content's footprint and what the panel shows around it."""
        step = nice_spacing(panel.height)
        view = panel.view
        seen = max(panel.rect[2], panel.rect[3]) / view.scale * (view.distance or 1.0)  # metres across the panel
        margin = min(max(step, seen), 20.0 * panel.height)
        flat = content.reshape(-1, 3)
        lo = np.floor((flat[:, [0, 2]].min(axis=0) - margin) / step) * step
        hi = np.ceil((flat[:, [0, 2]].max(axis=0) + margin) / step) * step
        xs = np.arange(lo[0], hi[0] + step / 2, step)
        zs = np.arange(lo[1], hi[1] + step / 2, step)
        g = panel.ground
        a = np.concatenate([np.stack([xs, np.full_like(xs, g), np.full_like(xs, lo[1])], 1),
                            np.stack([np.full_like(zs, lo[0]), np.full_like(zs, g), zs], 1)])
        b = np.concatenate([np.stack([xs, np.full_like(xs, g), np.full_like(xs, hi[1])], 1),
                            np.stack([np.full_like(zs, hi[0]), np.full_like(zs, g), zs], 1)])
        panel.grid = (a, b)

    def _project(self) -> None:
        """Pixels and nearness of every figure point, its ground shadow and markers, all frames at once.

        Each table maps a figure index to (T, N, 2) pixels or (T, N) nearness on its panel's image.
        """
        self._pix, self._near, self._shadow, self._marker_pix, self._marker_near = {}, {}, {}, {}, {}
        for panel in self.panels:
            for i in panel.members:
                self._pix[i], self._near[i] = panel.view.project(self._points[i])
                self._shadow[i] = panel.view.project(on_ground(self._points[i], panel.ground))[0]
                self._marker_pix[i], self._marker_near[i] = panel.view.project(self._marker_points(i))
            near = np.concatenate([self._near[i][:, self.figures[i].visible].reshape(-1) for i in panel.members])
            panel.near_range = (float(near.min()), float(near.max()))

    # -- drawing ----------------------------------------------------------------------------------
    def __len__(self) -> int:
        return len(self.times)

    def joint_pixels(self, figure: int, t: int) -> np.ndarray:
        """(J + E, 2) where figure ``figure``'s joints then end sites land in output frame ``t``, in
        output-image pixels (x right, y down)."""
        panel = next(p for p in self.panels if figure in p.members)
        return (self._pix[figure][t] + np.array(panel.rect[:2])) / self.ss

    def image(self, t: int, labels: bool = True) -> Image.Image:
        """The RGB image of output frame ``t`` (0 <= t < len(self)); ``labels``: name the figures."""
        w, h = self.size
        if len(self.panels) == 1:
            canvas = self._blank(w * self.ss, h * self.ss)
            self._draw_panel(canvas, self.panels[0], t, labels)
        else:  # each panel on its own image, so nothing spills into its neighbour
            canvas = Image.new("RGB", (w * self.ss, h * self.ss))
            for panel in self.panels:
                x, y, pw, ph = panel.rect
                sub = self._blank(pw, ph)
                self._draw_panel(sub, panel, t, labels)
                canvas.paste(sub, (x, y))
        draw = ImageDraw.Draw(canvas)
        for panel in self.panels[1:]:  # a rule between side-by-side panels
            x = panel.rect[0]
            draw.line((x, self.header + self.unit * 2, x, panel.rect[3] - self.footer - self.unit * 2),
                      fill=self.style.grid, width=max(int(round(0.3 * self.unit)), 1))
        self._draw_chrome(draw, t)
        return canvas.reduce(self.ss) if self.ss > 1 else canvas

    def _halo(self, fnt) -> dict:
        """Text options for a background-coloured outline, so text stays readable over grid lines."""
        return {"stroke_width": max(1, round(fnt.size / 8)), "stroke_fill": self.style.background}

    def _blank(self, width: int, height: int) -> Image.Image:
        """A background-coloured image (copied from a cached one: filling is slower than copying)."""
        key = (width, height)
        if key not in self._blanks:
            self._blanks[key] = Image.new("RGB", key, self.style.background)
        return self._blanks[key].copy()

    def _fog(self, panel: _Panel, color: RGB, near: float) -> RGB:
        """Far things fade a little towards the background: a depth cue."""
        lo, hi = panel.near_range
        far = 1.0 - (near - lo) / (hi - lo) if hi - lo > 1e-9 else 0.0
        return mix(color, self.style.background, 0.35 * far)

    def _side_colors(self, i: int) -> dict[int, RGB]:
        base = self.colors[i]
        return {LEFT: mix(base, WHITE, 0.42), RIGHT: mix(base, BLACK, 0.3), 0: base}

    def _draw_panel(self, canvas: Image.Image, panel: _Panel, t: int, labels: bool) -> None:
        draw = ImageDraw.Draw(canvas)
        st, view, u = self.style, panel.view, self.unit
        bone_w = max(1.6 * u, 2.0 * self.ss)
        edge = max(0.28 * u, self.ss * 0.6)
        if st.show_grid and panel.grid is not None:
            a, b = view.clip_segments(*panel.grid, t)
            for p, q in zip(a, b):
                draw.line((p[0], p[1], q[0], q[1]), fill=st.grid, width=max(int(round(0.25 * u)), 1))
        for i in panel.members:
            fig, frame = self.figures[i], self.frames[i][t]
            if st.show_trail and frame > 0:
                root = fig.positions[: frame + 1, fig.root].copy()
                root = root[np.unique(np.linspace(0, len(root) - 1, min(len(root), 400)).astype(int))]
                root[:, 1] = panel.ground
                pix = view.project(root, t)[0]
                draw.line([tuple(p) for p in pix], fill=mix(self.colors[i], st.background, 0.55),
                          width=max(int(round(0.5 * u)), 1), joint="curve")
            if st.show_shadow and view.basis[2, 1] < 0.85 and fig.mesh is None:  # from nearly above, a shadow only clutters
                sh = self._shadow[i][t]
                for pa, ch in fig.bones:
                    capsule(draw, sh[pa], sh[ch], bone_w, st.shadow, st.shadow, 0)
            for j, flags in fig.contacts.items():
                if flags[frame]:
                    self._contact_ring(draw, view, t, fig.positions[frame, j], panel, 0.08 * panel.height)
        if any(self.figures[i].mesh is not None for i in panel.members):
            self._draw_meshes(canvas, panel, t)
        self._draw_figures(draw, panel, t, bone_w, edge)
        if labels:
            self._draw_panel_label(draw, panel)

    def _pose(self, i: int, t: int) -> tuple[np.ndarray, np.ndarray]:
        """Posed vertex positions and normals (V, 3) of figure ``i`` at output frame ``t``.

        Frames drawn one after another (a GIF, a video) are skinned :data:`POSE_CHUNK` at a time.
        """
        cached = self._posed.get(i)
        if cached is None or not cached[0] <= t < cached[0] + len(cached[1]):
            count = POSE_CHUNK if self._last_posed.get(i) == t - 1 else 1
            positions, normals = self.figures[i].mesh.pose(self.frames[i][t:t + count])
            cached = self._posed[i] = (t, positions, normals)
        self._last_posed[i] = t
        return cached[1][t - cached[0]], cached[2][t - cached[0]]

    def _draw_meshes(self, canvas: Image.Image, panel: _Panel, t: int) -> None:
        """The panel's mesh figures at output frame ``t``: their ground shadow, then their surfaces
        lit and z-buffered together, composited onto ``canvas`` (the panel's image)."""
        view, st = panel.view, self.style
        posed, triangles, colors, offset = [], [], [], 0
        for i in panel.members:
            mesh = self.figures[i].mesh
            if mesh is not None:
                posed.append(self._pose(i, t))
                triangles.append(mesh.triangles + offset)
                colors.append(mesh.colors)
                offset += mesh.num_vertices
        positions = np.concatenate([p for p, _ in posed]).astype(np.float64)
        normals = np.concatenate([n for _, n in posed])
        triangles, colors = np.concatenate(triangles), np.concatenate(colors)
        width, height = canvas.size
        image = np.array(canvas)
        if st.show_shadow and view.basis[2, 1] < 0.85:
            # the surfaces' silhouette cast on the ground, at output resolution: a flat patch needs no more
            low = (-(-width // self.ss), -(-height // self.ss))
            cast = view.project(on_ground(positions, panel.ground), t)[0] / self.ss
            mask = coverage(cast, triangles, low).repeat(self.ss, axis=0).repeat(self.ss, axis=1)[:height, :width]
            darker = np.array(st.shadow, dtype=np.float32) / np.maximum(np.array(st.background, dtype=np.float32), 1.0)
            image[mask] = np.clip(image[mask] * darker, 0, 255).astype(np.uint8)
        cam = view.camera_space(positions, t)
        pixels = view.to_pixels(cam)
        depth = cam[:, 2]
        if view.distance is not None:  # perspective: 1/distance is what varies linearly across the screen
            behind = cam[:, 2] > 0.95 * view.distance
            triangles = triangles[~behind[triangles].any(axis=1)]
            depth = 1.0 / np.maximum(view.distance - cam[:, 2], 1e-6)
        fragments = rasterize(pixels, depth, triangles, (width, height))
        corner = pixels[triangles]
        e1, e2 = corner[:, 1] - corner[:, 0], corner[:, 2] - corner[:, 0]
        facing = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0] < 0  # counter-clockwise on screen (y runs down)
        rgb = shade(fragments, triangles, normals, colors, facing, -LIGHT, view.basis[2])
        image.reshape(-1, 3)[fragments.index] = rgb
        canvas.paste(Image.fromarray(image))

    def _contact_ring(self, draw, view: PanelView, t: int, where: np.ndarray, panel: _Panel, radius: float) -> None:
        angles = np.linspace(0.0, 2.0 * np.pi, 25)
        ring = np.stack([where[0] + radius * np.cos(angles), np.full_like(angles, panel.ground),
                         where[2] + radius * np.sin(angles)], axis=1)
        pix = view.project(ring, t)[0]
        draw.polygon([tuple(p) for p in pix], fill=mix(self.style.contact, self.style.background, 0.6),
                     outline=self.style.contact, width=max(int(round(0.3 * self.unit)), 1))

    def _draw_figures(self, draw: ImageDraw.ImageDraw, panel: _Panel, t: int, bone_w: float, edge: float) -> None:
        """Bones, joints, markers and rays of the panel's figures, sorted far to near; then overlays."""
        st, u = self.style, self.unit
        items = []  # (nearness, order, painter): drawn far to near
        rings, labels = [], []  # drawn on top of everything
        for i in panel.members:
            fig, frame = self.figures[i], self.frames[i][t]
            pix, near = self._pix[i][t], self._near[i][t]
            colors = self._side_colors(i)
            contact = {j for j, flags in fig.contacts.items() if flags[frame]}
            nj = fig.skeleton.num_joints
            for pa, ch in fig.bones if fig.mesh is None else ():
                side = fig.sides[ch] if ch < nj else fig.sides[pa]
                color = st.contact if pa in contact else colors[int(side)]
                z = (near[pa] + near[ch]) / 2.0
                fill = self._fog(panel, color, z)
                outline = mix(fill, BLACK, 0.45)
                items.append((z, 0, lambda a=pix[pa], b=pix[ch], f=fill, o=outline: capsule(draw, a, b, bone_w, f, o, edge)))
            for j in np.nonzero(fig.visible[:nj] & (fig.mesh is None))[0]:
                big = j in contact
                r = bone_w * (0.85 if big else 0.32)
                fill = st.contact if big else mix(self._fog(panel, colors[int(fig.sides[j])], near[j]), BLACK, 0.5)
                items.append((near[j] + 1e-6, 1, lambda c=pix[j], r=r, f=fill: disc(draw, c, r, f)))
            mpix, mnear = self._marker_pix[i][t], self._marker_near[i][t]
            for k, marker in enumerate(fig.markers):
                centre, z = mpix[k], mnear[k]
                if marker.ray_from is not None:
                    src = fig.skeleton.index[marker.ray_from]
                    items.append(((z + near[src]) / 2.0, 2, lambda a=pix[src], b=centre, c=marker.color:
                                  dashed_line(draw, a, b, c, max(0.45 * u, self.ss), 1.6 * u)))
                items.append((z, 3, lambda m=marker, c=centre, i=i: self._draw_marker(draw, panel, t, m, c, i)))
                if marker.label:
                    labels.append((centre, marker.label, marker.color))
            rings += [pix[j] for j in np.nonzero(fig.highlight & fig.visible[:nj])[0]]
            # joints nearer the root first: they win the free spots over crowded fingers
            named = sorted((j for j in fig.names if fig.visible[j]), key=lambda j: fig.skeleton.depths[j])
            labels += [(pix[j], fig.names[j], st.text) for j in named]
        items.sort(key=lambda it: (it[0], it[1]))
        for _, _, paint in items:
            paint()
        placer = LabelPlacer(draw, (0, 0, panel.rect[2], panel.rect[3]))
        small = font(round(self.font_px * 0.78))
        for centre in rings:
            disc(draw, centre, bone_w * 1.7, None, st.highlight, max(0.45 * u, self.ss))
        for centre, text, color in labels:
            placer.place(centre, text, small, color, st.background, bone_w * 1.2)

    def _draw_marker(self, draw, panel: _Panel, t: int, marker, centre, i: int) -> None:
        u, view = self.unit, panel.view
        fill = marker.color
        if marker.style == "sphere":
            pos = marker.at(self.frames[i][t:t + 1])[0]
            edge_pt = pos + view.basis[0] * marker.size
            radius = max(float(np.linalg.norm(view.project(edge_pt[None], t)[0][0] - centre)), 1.5 * u)
            disc(draw, centre, radius, fill, mix(fill, BLACK, 0.45), max(0.3 * u, 1))
            disc(draw, (centre[0] - radius * 0.3, centre[1] - radius * 0.3), radius * 0.3, mix(fill, WHITE, 0.55))
            return
        pos = marker.at(self.frames[i][t:t + 1])[0]
        ends = pos + np.concatenate([np.eye(3), -np.eye(3)]) * marker.size
        pix = view.project(ends, t)[0]
        for colour, width in ((mix(fill, BLACK, 0.45), 0.8 * u + 2 * self.ss), (fill, 0.8 * u)):  # outlines under fills
            for k in range(3):
                draw.line((pix[k][0], pix[k][1], pix[k + 3][0], pix[k + 3][1]), fill=colour, width=max(int(round(width)), 1))

    def _layout_labels(self, panel: _Panel) -> None:
        """Place each figure's name and left/right legend (stick figures only) in rows at the top of the panel."""
        fnt, small = font(self.font_px), font(round(self.font_px * 0.8))
        r = self.font_px * 0.32
        sides = sum(2.6 * r + small.getlength(t) + self.font_px * 0.4 for t in "LR")
        left = self.unit * 3
        room = panel.rect[2] - 2 * left
        x, y, row = left, self.header + self.font_px * 0.25, self.font_px * 1.4
        panel.labels = []
        for i in panel.members:
            legend = sides if self.figures[i].mesh is None else 0.0
            label = self.figures[i].label or f"figure {i + 1}"
            fit = room - legend - self.font_px * 0.6
            if fnt.getlength(label) > fit:
                while len(label) > 1 and fnt.getlength(label + "…") > fit:
                    label = label[:-1]
                label += "…"
            width = fnt.getlength(label) + self.font_px * 0.6 + legend
            if x > left and x + width > left + room:
                x, y = left, y + row
            panel.labels.append((i, x, y, label))
            x += width + self.font_px * 0.8
        panel.label_height = y + row - self.header

    def _draw_panel_label(self, draw: ImageDraw.ImageDraw, panel: _Panel) -> None:
        """Each figure's name in its colour, with the left/right shades a stick figure uses."""
        fnt, small = font(self.font_px), font(round(self.font_px * 0.8))
        r = self.font_px * 0.32
        for i, x, y, label in panel.labels:
            draw.text((x, y), label, font=fnt, fill=mix(self.colors[i], BLACK, 0.2), **self._halo(fnt))
            if self.figures[i].mesh is not None:
                continue  # a mesh shows its own colours, not the left/right shades
            x += draw.textlength(label, font=fnt) + self.font_px * 0.6
            colors = self._side_colors(i)
            for text, side in (("L", LEFT), ("R", RIGHT)):
                disc(draw, (x + r, y + self.font_px * 0.6), r, colors[side], mix(colors[side], BLACK, 0.45), self.ss)
                draw.text((x + 2.6 * r, y + self.font_px * 0.12), text, font=small, fill=self.style.text, **self._halo(small))
                x += 2.6 * r + draw.textlength(text, font=small) + self.font_px * 0.4

    def _draw_chrome(self, draw: ImageDraw.ImageDraw, t: int) -> None:
        """Title at the top, frame and time counter at the bottom right."""
        w, h = self.size[0] * self.ss, self.size[1] * self.ss
        if self.title:
            fnt = font(round(self.font_px * 1.15))
            draw.text((self.font_px * 0.6, self.font_px * 0.3), self.title, font=fnt, fill=self.style.text, **self._halo(fnt))
        if self.counter:
            fig = self.figures[0]
            text = f"frame {self.frames[0][t] + 1}/{fig.num_frames}   {self.times[t]:6.2f} s"
            fnt = font(round(self.font_px * 0.85))
            tw = draw.textlength(text, font=fnt)
            draw.text((w - tw - self.font_px * 0.6, h - self.font_px * 1.25), text, font=fnt,
                      fill=mix(self.style.text, self.style.background, 0.25), **self._halo(fnt))
