"""Standing a character on the ground: how low its feet go in a clip, and the clip lifted by it.

The ground is y = 0 (core frame, metres, +Y up). A character's feet are the ankles and everything
below them (:func:`infuse.contacts.feet`). Their lowest point is that of their joints and end sites,
lowered by how far the mesh they carry (the sole) reaches below those at rest. A file whose rig
puts the hips at the origin (SmartBody's Brad) stands a metre below the ground in every clip that
does not move its root; lifting each written clip by its feet's lowest point stands it on the ground.
"""
from __future__ import annotations

import numpy as np

from .asset import Asset
from .contacts import SIDES, Foot, feet, joint_index, lowest_points
from .kinematics import forward_kinematics, motion_fk
from .motion import Motion


def sole_depth(asset: Asset, pair: tuple[Foot, Foot]) -> float:
    """How far (m) the mesh on the feet reaches below their lowest joint or end site at rest; 0 for a
    character without a mesh on its feet. A vertex belongs to the joint that moves it most."""
    sk = asset.skeleton
    g, p = forward_kinematics(sk, sk.rest_rotations[None], sk.rest_translations[None, 0])
    lowest = float(lowest_points(sk, pair, g, p).min())
    on_feet = np.zeros(sk.num_joints, dtype=bool)
    on_feet[[j for foot in pair for j in foot.joints]] = True
    sole = lowest
    for mesh in asset.meshes:
        strongest = mesh.bind_joints[mesh.joints[np.arange(mesh.num_vertices), np.argmax(mesh.weights, axis=1)]]
        vertices = np.nonzero(on_feet[strongest])[0]
        if len(vertices):
            sole = min(sole, float(mesh.skin(g, p, vertices=vertices)[0][0, :, 1].min()))
    return lowest - sole


def foot_height(asset: Asset, mapping, motion: Motion | None = None, sole: float | None = None) -> float:
    """Height (m) of the lowest point of the character's feet: in its rest pose, or (``motion``) the
    lowest over the clip's frames, soles included (``sole``: the :func:`sole_depth`, measured here
    unless given, for many clips of one character).

    ``mapping``: the character's canonical mapping (:class:`~infuse.mapping.Mapping` or a dict).
    Raises :class:`~infuse.errors.UnusableInputError` when a leg is not mapped.
    """
    sk = asset.skeleton
    pair = feet(sk, mapping, file=asset.path)
    if motion is None:
        g, p = forward_kinematics(sk, sk.rest_rotations[None], sk.rest_translations[None, 0])
    else:
        g, p = motion_fk(motion)
    return float(lowest_points(sk, pair, g, p).min()) - (sole_depth(asset, pair) if sole is None else sole)


def grounded(motion: Motion, height: float) -> Motion:
    """``motion`` with its roots lowered by ``height`` metres (a negative height lifts it): a clip
    whose feet go down to ``height`` then stands on y = 0. Every root moves (a skeleton whose body
    hangs from another root than joint 0 gets per-frame joint translations for it)."""
    root = motion.root_translations.copy()
    root[:, 1] -= height
    roots = motion.skeleton.roots
    jt = motion.joint_translations
    if jt is not None or len(roots) > 1:
        jt = motion.local_translations()
        jt[:, roots, 1] -= height
    return motion.replace(root_translations=root, joint_translations=jt)


def on_ground(asset: Asset, mapping, motion: Motion, level: float = 0.0) -> Motion:
    """``motion`` moved up or down so that its feet's lowest point (:func:`foot_height`) is at
    ``level`` metres; unchanged for a character without both legs mapped (nothing to stand on)."""
    index = joint_index(asset.skeleton, mapping)
    if not all(prefix + j in index for _, prefix in SIDES for j in ("hip", "knee", "ankle")):
        return motion
    return grounded(motion, foot_height(asset, mapping, motion) - level)
