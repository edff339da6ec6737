"""Breathing for infuse: the chest lifts and the clavicles rise with each breath."""
from .controller import Breathing, breath_curve

__all__ = ["Breathing", "breath_curve"]
