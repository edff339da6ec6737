"""The ``heuristic`` mapper: canonical joint names for any humanoid skeleton."""
from .mapper import heuristic_map

__all__ = ["heuristic_map"]
