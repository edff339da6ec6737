"""infuse-anim-locomotion: parameterized, phase-synchronized locomotion from behaviour packs.

::

    from infuse_locomotion import Locomotion
    rt.activate(character, Locomotion("locomotion-female", path=[(0, 0), (3, 2), (6, 0)], speed=1.3), 0.0)
"""
from __future__ import annotations

from .controller import Locomotion

__all__ = ["Locomotion"]
