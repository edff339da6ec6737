"""Example third-party controller for infuse: ``shrug`` raises both shoulders and lets them fall."""
from .controller import Shrug, shrug_curve

__all__ = ["Shrug", "shrug_curve"]
