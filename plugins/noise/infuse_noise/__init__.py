"""Noise for infuse: smooth random turns of named joints, as SmartBody's ``<sbm:noise>``."""
from .controller import Noise, gradient_noise

__all__ = ["Noise", "gradient_noise"]
