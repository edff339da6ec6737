"""The ``names`` mapper: canonical joint names from dictionaries of well-known rig conventions."""
from .mapper import names_map, normalize

__all__ = ["names_map", "normalize"]
