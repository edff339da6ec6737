"""Registers the ``nonverbal`` BML generator: ``infuse:nonverbal="true"`` on a ``<bml>`` block (or
``Scene(generators=("nonverbal",))``) adds gestures, nods, brow raises, gaze and listener backchannel for
its speech (:mod:`infuse_nvbg.generate`, rules in ``rules.toml``)."""
from __future__ import annotations

import infuse
from infuse.plugin_types import BMLGenerator

#: The ``infuse:`` block attributes the generator reads: who listens, a seed of the block's own, and how
#: expressive the speaker is (a factor on the rules' probabilities).
SETTINGS = frozenset({"listener", "seed", "expressiveness"})


def _generate(block, context):
    from .generate import generate

    return generate(block, context)


@infuse.hookimpl
def infuse_bml_generators():
    return [BMLGenerator("nonverbal", _generate, "gestures, nods, brow raises, gaze and listener backchannel from speech",
                         SETTINGS)]
