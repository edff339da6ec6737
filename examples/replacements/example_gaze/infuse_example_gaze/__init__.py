"""Example replacement of the gaze controller: BML ``<gaze>`` turns the head alone toward its target."""
from .controller import HeadGaze

__all__ = ["HeadGaze"]
