"""Preview renders of a scene: its characters where they stand (their meshes, with the morph targets the
controllers moved, else stick figures), its objects as spheres where they are (carried ones move with the
hand), and
each character's line of sight as a dashed ray from its eyes (or head) along where they point, ending at what it
looks at (a character's face or an object within 15 degrees of the ray) or 1.2 m ahead."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from .. import quaternions as quat
from ..kinematics import motion_fk
from ..render import PALETTE, Camera, Figure, Marker, drawable_meshes, render, sides_from_mapping

#: How far off the ray a character's face or an object may be and still end it, degrees.
LOOK_AT_CONE_DEG = 15.0
#: Length of a ray that ends at nothing, metres.
FREE_RAY_M = 1.2
OBJECT_COLOR = (230, 150, 20)
#: The automatic view: this many degrees around from square to the line between the first two characters,
#: and this high.
AUTO_VIEW_TURN_DEG, AUTO_VIEW_ELEVATION_DEG = -20.0, 12.0
#: Filmstrip tiles of several characters, pixels: wide, since a scene spreads along the ground.
STRIP_TILE = (420, 320)


def look_joints(rig) -> list[int]:
    """The joints a character looks from: both eyes, else the head (skullbase, else the top of the neck)."""
    eyes = [rig.joint("eyeball_left"), rig.joint("eyeball_right")]
    if None not in eyes:
        return eyes
    head = next((rig.joint(n) for n in ("skullbase", "spine5", "spine4") if rig.joint(n) is not None), None)
    return [] if head is None else [head]


def sight_rays(rig, g_rot: np.ndarray, g_pos: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """(origins (F, 3), unit directions (F, 3)) of where a character looks, from its global joint rotations
    (F, J, 4) and positions (F, J, 3); None without eyes or head."""
    joints = look_joints(rig)
    if not joints:
        return None
    forward_body = quat.rotate(rig.body, np.array([0.0, 0.0, 1.0]))
    forward_local = quat.rotate(quat.conjugate(rig.reference_rotations[joints]), forward_body)  # (K, 3)
    direction = quat.rotate(g_rot[:, joints], np.broadcast_to(forward_local, g_rot[:, joints].shape[:-1] + (3,)))
    direction = direction.mean(axis=1)
    direction /= np.maximum(np.linalg.norm(direction, axis=1, keepdims=True), 1e-12)
    return g_pos[:, joints].mean(axis=1), direction


def scene_figures(scene, style: str = "auto") -> list[Figure]:
    """One figure per character of ``scene`` (every frame so far), with its line of sight, drawn as ``style``
    (see :data:`infuse.render.STYLES`); the objects go with the first figure."""
    names = list(scene.characters)
    if not names or scene.runtime.frame == 0:
        return []
    motions = {n: scene.motion(n) for n in names}
    poses = {n: motion_fk(m) for n, m in motions.items()}
    rays = {n: sight_rays(scene.runtime.rig(n), *poses[n]) for n in names}
    faces = {n: r[0] for n, r in rays.items() if r is not None}
    objects = {o: scene.object_track(o) for o in scene.objects}
    figures = []
    for k, name in enumerate(names):
        rig = scene.runtime.rig(name)
        markers = []
        if rays[name] is not None:
            origin, direction = rays[name]
            candidates = [p for other, p in faces.items() if other != name] + list(objects.values())
            length = _ray_lengths(origin, direction, candidates)
            joint = rig.skeleton.names[look_joints(rig)[0]]
            markers.append(Marker(origin + direction * length[:, None], "", color=PALETTE[k % len(PALETTE)],
                                  style="cross", size=0.04, ray_from=joint))
        if k == 0:
            markers += [Marker(objects[o.name], o.name, color=OBJECT_COLOR, style="sphere", size=o.size / 2)
                        for o in scene.objects.values()]
        asset = rig.character.asset
        meshes = drawable_meshes(asset, motions[name].skeleton, style)
        figures.append(Figure.from_motion(motions[name], meshes=meshes, label=name,
                                          color=PALETTE[k % len(PALETTE)],
                                          sides=sides_from_mapping(rig.skeleton, rig.mapping), markers=markers))
    return figures


def _ray_lengths(origin: np.ndarray, direction: np.ndarray, candidates: list[np.ndarray]) -> np.ndarray:
    """(F,) distance to the candidate point (each (F, 3)) nearest the ray within the cone, else :data:`FREE_RAY_M`."""
    length = np.full(len(origin), FREE_RAY_M)
    best = np.full(len(origin), np.radians(LOOK_AT_CONE_DEG))
    for points in candidates:
        to = points - origin
        distance = np.linalg.norm(to, axis=1)
        cosine = np.einsum("fi,fi->f", to, direction) / np.maximum(distance, 1e-9)
        angle = np.arccos(np.clip(cosine, -1.0, 1.0))
        closer = (angle < best) & (distance > 1e-3)
        best = np.where(closer, angle, best)
        length = np.where(closer, distance, length)
    return length


def auto_view(scene) -> tuple[float, float] | str:
    """A view across the line between the first two characters (the first on the left), a little from the
    first one's side and above; three-quarter for one character."""
    names = list(scene.characters)
    if len(names) < 2:
        return "three-quarter"
    a, b = (scene.runtime.rig(n).position for n in names[:2])
    d = b - a
    if np.hypot(d[0], d[2]) < 1e-6:
        return "three-quarter"
    return float(np.degrees(np.arctan2(d[0], d[2])) - 90.0 + AUTO_VIEW_TURN_DEG), AUTO_VIEW_ELEVATION_DEG


def render_scene(scene, path, *, strip: int | None = None, overlay: bool = True, start: float | None = None,
                 end: float | None = None, fps: float | None = None, size: tuple[int, int] | None = None,
                 view: str | tuple[float, float] | None = None, title: str | None = None,
                 progress: bool | None = None, style: str = "auto") -> Path:
    """Render the scene so far to ``path`` (.png still or filmstrip with ``strip=N``, .gif, .mp4): every
    character in one panel (``overlay``, default) or side by side, objects as spheres, lines of sight. ``view``:
    a named view or (azimuth, elevation) degrees (default :func:`auto_view`); ``style``: each character as its
    mesh, a stick figure, or ``auto`` (the mesh where it has one)."""
    from ..errors import UsageError

    figures = scene_figures(scene, style)
    if not figures:
        raise UsageError("nothing to render: the scene has no character or no frame evaluated yet (run it first)")
    if title is None:
        title = " · ".join(scene.characters)
    camera = Camera(view=auto_view(scene) if view is None else view, follow=False)
    if size is None and strip is not None and len(figures) > 1:
        size = (STRIP_TILE[0] * (1 if overlay else len(figures)), STRIP_TILE[1])
    return render(figures, path, strip=strip, overlay=overlay, start=start, end=end, fps=fps, size=size,
                  camera=camera, title=title, progress=progress)
