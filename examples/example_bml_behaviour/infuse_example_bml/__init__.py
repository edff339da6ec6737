"""Example third-party BML behaviour for infuse: ``<ex:shrug xmlns:ex="urn:infuse:example"/>``."""
from .shrug import NAMESPACE, plan_shrug

__all__ = ["NAMESPACE", "plan_shrug"]
