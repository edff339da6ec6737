"""BML 1.0 ``<faceShift>`` on the Ready Player Me avatar's ARKit shapes: the expression comes in over the
shift (start to end), stays after it, and gives way to the next face shift as that one comes in."""
from __future__ import annotations

import pytest

from infuse.bml import Scheduler
from infuse.scene import Scene

from corpus_data import require_corpus
from runtime_characters import corpus_character

pytest.importorskip("infuse_lipsync")

FPS = 30.0
BML = '<bml xmlns="http://www.bml-initiative.org/bml/bml-1.0" id="{id}">{body}</bml>'


def test_a_face_shift_is_scheduled_as_a_lasting_change():
    (block,) = Scheduler().submit(BML.format(id="b1", body='<faceShift id="f" lexeme="SMILE" end="0.8"/>'))
    (activation,) = block.activations
    assert activation.controller == "face" and activation.persistent and activation.end == pytest.approx(0.8)


def test_face_shifts_last_until_the_next():
    require_corpus()
    scene = Scene(fps=FPS, tts=None, quiet=True, idle=False)
    warnings = []
    scene.on("warningFeedback", warnings.append)
    scene.add_character(corpus_character("rpm"), "ann")
    scene.bml("ann", BML.format(id="smile", body='<faceShift id="f" lexeme="SMILE" amount="1"/>'), at=0.5)
    scene.bml("ann", BML.format(id="frown", body='<faceShift id="f" lexeme="FROWN" amount="1" end="0.5"/>'), at=3.0)
    scene.run(5.0)
    assert not warnings, [w.description for w in warnings]
    names = scene.runtime.rig("ann").morph_targets
    weights = scene.runtime.morph_weights("ann")
    smile, brow = weights[:, names.index("mouthSmileLeft")], weights[:, names.index("browDownLeft")]
    at = lambda t: int(round(t * FPS))  # noqa: E731
    assert smile[at(0.4)] == 0.0 and smile[at(0.75)] < smile[at(1.0)]  # comes in over the shift
    assert smile[at(1.0):at(3.0)].min() > 0.5  # and stays, long after its end
    assert brow[at(2.9)] == 0.0 and brow[at(3.5):].min() > 0.5  # the next one comes in...
    assert smile[at(3.5):].max() < 1e-9  # ...as the first goes, and lasts to the end
