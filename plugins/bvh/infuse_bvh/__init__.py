"""BVH (Biovision Hierarchy) reader and writer for infuse.

:mod:`.parse` reads the text into the file's own numbers, :mod:`.reader` converts them into the
core frame (metres, +Y up, quaternions x,y,z,w), :mod:`.writer` writes an asset back as BVH and
:mod:`.plugin` registers both through the ``infuse.readers`` and ``infuse.writers`` entry points.
"""
from .parse import BvhDocument, parse
from .reader import read

__all__ = ["BvhDocument", "parse", "read"]
