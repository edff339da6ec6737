"""Standing a character on the ground: how high its feet are at rest, and clips lifted by it.

The ground is y = 0 (core frame, metres, +Y up). A character's feet are the ankles and everything
below them (:func:`infuse.contacts.feet`); their lowest point at rest is the lowest vertex of the
mesh they carry (the sole), else, for a character without a mesh, the lowest of their joints and
end sites. A file whose rig puts the hips at the origin (SmartBody's Brad) has its feet a metre
below the ground; lifting every written clip's root by that height stands it on the ground.
"""
from __future__ import annotations

import numpy as np

from .asset import Asset
from .contacts import feet, lowest_points
from .kinematics import forward_kinematics
from .motion import Motion


def rest_foot_height(asset: Asset, mapping) -> float:
    """Height (m) of the lowest point of the character's feet in its rest pose (see the module doc).

    ``mapping``: the character's canonical mapping (:class:`~infuse.mapping.Mapping` or a dict).
    Raises :class:`~infuse.errors.UnusableInputError` when a leg is not mapped.
    """
    sk = asset.skeleton
    pair = feet(sk, mapping, file=asset.path)
    rest = np.broadcast_to(sk.rest_rotations, (1,) + sk.rest_rotations.shape)
    g, p = forward_kinematics(sk, rest, sk.rest_translations[None, 0])
    lowest = float(lowest_points(sk, pair, g, p).min())
    foot_joints = np.zeros(sk.num_joints, dtype=bool)
    foot_joints[[j for foot in pair for j in foot.joints]] = True
    soles = []
    for mesh in asset.meshes:
        # a vertex belongs to the foot that moves it most
        strongest = mesh.bind_joints[mesh.joints[np.arange(mesh.num_vertices), np.argmax(mesh.weights, axis=1)]]
        on_feet = np.nonzero(foot_joints[strongest])[0]
        if len(on_feet):
            soles.append(float(mesh.skin(g, p, vertices=on_feet)[0][0, :, 1].min()))
    return min(soles) if soles else lowest


def grounded(motion: Motion, height: float) -> Motion:
    """``motion`` with its root (joint 0) lowered by ``height`` metres (a negative height lifts it):
    a character whose feet rest at ``height`` stands on y = 0."""
    roots = motion.root_translations.copy()
    roots[:, 1] -= height
    jt = motion.joint_translations
    if jt is not None:
        jt = jt.copy()
        jt[:, 0, 1] -= height
    return motion.replace(root_translations=roots, joint_translations=jt)
