"""Cameras and framing: from core-frame points (metres, +Y up, +Z forward) to image pixels.

A view is an azimuth and an elevation (degrees). Azimuth 0 looks at the character's front (the
camera stands on +Z looking towards -Z, so the character's left, +X, is on the image's right);
azimuth -90 stands on the character's right (-X), so forward (+Z) runs to the image's right;
elevation 90 looks straight down. The named top view (azimuth 180) reads like a map: forward is
up the image and the character's left is on the image's left. Projection is vectorized over all
frames and points at once.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: Named views: (azimuth_deg, elevation_deg).
VIEWS: dict[str, tuple[float, float]] = {
    "front": (0.0, 0.0),
    "side": (-90.0, 0.0),
    "top": (180.0, 90.0),
    "three-quarter": (-35.0, 15.0),
}

PROJECTIONS = ("orthographic", "perspective")


@dataclass(frozen=True)
class Camera:
    """How to look at the scene.

    - ``view``: a name of :data:`VIEWS` or ``(azimuth_deg, elevation_deg)``.
    - ``projection``: ``"orthographic"`` or ``"perspective"``.
    - ``fov_deg``: perspective field of view (the camera backs off until the content fits it).
    - ``follow``: ``True`` keeps the root centred (long walks), ``False`` frames every rendered
      frame at once with a still camera, ``None`` follows when the root travels more than twice
      the figure's height.
    """

    view: str | tuple[float, float] = "three-quarter"
    projection: str = "orthographic"
    fov_deg: float = 30.0
    follow: bool | None = None

    def __post_init__(self):
        if isinstance(self.view, str) and self.view not in VIEWS:
            raise ValueError(f"unknown view {self.view!r}; known: {', '.join(VIEWS)}")
        if self.projection not in PROJECTIONS:
            raise ValueError(f"unknown projection {self.projection!r}; known: {', '.join(PROJECTIONS)}")
        if not 1.0 <= self.fov_deg <= 150.0:
            raise ValueError("fov_deg must lie in [1, 150]")

    def basis(self) -> np.ndarray:
        """(3, 3) rows: image right, image up, and the direction towards the camera (unit vectors)."""
        az, el = VIEWS[self.view] if isinstance(self.view, str) else self.view
        az, el = np.radians(az), np.radians(el)
        toward = np.array([np.sin(az) * np.cos(el), np.sin(el), np.cos(az) * np.cos(el)])
        right = np.array([np.cos(az), 0.0, -np.sin(az)])
        up = np.cross(toward, right)
        return np.stack((right, up, toward))


@dataclass
class PanelView:
    """A framed camera for one panel and every rendered frame.

    ``target`` (T, 3) is the point the camera centres on at each rendered frame; ``distance`` is
    the perspective camera's distance from it (``None`` for orthographic); ``scale`` maps view
    units to pixels; ``view_centre`` (2,) is the view-space point drawn at ``pixel_centre`` (2,).
    """

    basis: np.ndarray
    target: np.ndarray
    distance: float | None
    scale: float
    view_centre: np.ndarray
    pixel_centre: np.ndarray

    def camera_space(self, points: np.ndarray, t: int | None = None) -> np.ndarray:
        """(..., 3) camera-space coordinates (right, up, nearness) relative to the target.

        ``points`` is (T, N, 3) for every rendered frame, or (N, 3) for rendered frame ``t``.
        """
        target = self.target[:, None] if t is None else self.target[t]
        return (np.asarray(points) - target) @ self.basis.T

    def project(self, points: np.ndarray, t: int | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Pixels (..., 2) (x right, y down) and nearness (...,) in metres (larger is nearer)."""
        cam = self.camera_space(points, t)
        return self.to_pixels(cam), cam[..., 2]

    def to_pixels(self, cam: np.ndarray) -> np.ndarray:
        """Camera-space (..., 3) -> pixels (..., 2)."""
        xy = cam[..., :2]
        if self.distance is not None:
            xy = xy / np.maximum(self.distance - cam[..., 2:3], 1e-6)
        out = (xy - self.view_centre) * self.scale
        out[..., 1] *= -1.0
        return out + self.pixel_centre

    def clip_segments(self, a: np.ndarray, b: np.ndarray, t: int) -> tuple[np.ndarray, np.ndarray]:
        """World segments (S, 3) -> pixel segments (S', 2), (S', 2) in front of the camera at frame ``t``.

        Orthographic views keep every segment; perspective views cut segments at a near plane.
        """
        ca, cb = self.camera_space(a, t), self.camera_space(b, t)
        if self.distance is not None:
            limit = self.distance * 0.95  # nearness beyond which a point is too close to (or behind) the eye
            za, zb = ca[:, 2], cb[:, 2]
            keep = (za < limit) | (zb < limit)
            ca, cb, za, zb = ca[keep], cb[keep], za[keep], zb[keep]
            s = np.clip((limit - za) / np.where(zb != za, zb - za, 1.0), 0.0, 1.0)[:, None]
            cut = ca + (cb - ca) * s
            ca = np.where((za >= limit)[:, None], cut, ca)
            cb = np.where((zb >= limit)[:, None], cut, cb)
        return self.to_pixels(ca), self.to_pixels(cb)


def _view_coords(camera: Camera, rel: np.ndarray, basis: np.ndarray) -> tuple[np.ndarray, float | None]:
    """View-space 2D coordinates of target-relative points and the perspective distance."""
    cam = rel @ basis.T
    if camera.projection == "orthographic":
        return cam[..., :2], None
    radius = max(float(np.max(np.linalg.norm(rel, axis=-1))), 0.1)
    distance = radius / np.sin(np.radians(camera.fov_deg) / 2.0)
    return cam[..., :2] / (distance - cam[..., 2:3]), distance


def frame_panels(
    camera: Camera,
    contents: list[np.ndarray],
    targets: list[np.ndarray | None],
    rects: list[tuple[float, float, float, float]],
) -> list[PanelView]:
    """Frame each panel on what it must show, with one pixel scale shared by all panels.

    - ``contents[k]``: (T, N, 3) points (metres) panel ``k`` must keep in view at each rendered frame.
    - ``targets[k]``: (T, 3) point to follow per frame, or ``None`` to frame all frames at once.
    - ``rects[k]``: (x, y, width, height) pixels of the area the content may occupy.

    Sharing the scale keeps sizes comparable across side-by-side panels.
    """
    basis = camera.basis()
    prepared = []
    for points, target, rect in zip(contents, targets, rects):
        flat = points.reshape(-1, 3)
        if target is None:
            centre = (flat.min(axis=0) + flat.max(axis=0)) / 2.0
            target = np.broadcast_to(centre, (len(points), 3))
        target = np.asarray(target, dtype=np.float64)
        xy, distance = _view_coords(camera, points - target[:, None], basis)
        lo, hi = xy.reshape(-1, 2).min(axis=0), xy.reshape(-1, 2).max(axis=0)
        floor = 0.2 if distance is None else 0.2 / distance  # a lone point still gets a sensible zoom
        extent = np.maximum(hi - lo, floor)
        scale = min(rect[2] / extent[0], rect[3] / extent[1])
        prepared.append((target, distance, scale, (lo + hi) / 2.0, rect))
    shared = min(p[2] for p in prepared)
    return [
        PanelView(basis, target, distance, shared, centre, np.array([rect[0] + rect[2] / 2.0, rect[1] + rect[3] / 2.0]))
        for target, distance, _, centre, rect in prepared
    ]
