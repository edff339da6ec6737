"""A pack's clips in an order set by what they hold, so no result depends on names or file order.

Steps that see the clips together (the tessellation's Delaunay, the retargeter reading one joined
batch, the blend's running sums) give slightly different floating-point results when the clips
come in another order. The manifest's order follows the file names, so those steps take the clips
in :func:`content_order` instead: by a digest of each clip's frame rate and arrays, the same in
every process, for any pack name, clip names or folder listing.
"""
from __future__ import annotations

import hashlib
from typing import TypeVar

import numpy as np

from ..motion import Motion

Key = TypeVar("Key")


def content_digest(motion: Motion) -> str:
    """A SHA-256 of ``motion``'s frame rate, local rotations (F, J, 4), root translations (F, 3) and
    joint translations (F, J, 3) when it has them, as float64 bytes; its name and skeleton are left out."""
    h = hashlib.sha256(np.float64(motion.fps).tobytes())
    arrays = (motion.local_rotations, motion.root_translations, motion.joint_translations)
    for arr in arrays:
        h.update(b"-" if arr is None else np.ascontiguousarray(arr, dtype=np.float64).tobytes())
    return h.hexdigest()


def content_order(motions: dict[Key, Motion]) -> list[Key]:
    """The keys of ``motions`` sorted by :func:`content_digest` (equal clips as given: they give equal results)."""
    digests = {k: content_digest(m) for k, m in motions.items()}
    return sorted(motions, key=digests.__getitem__)
