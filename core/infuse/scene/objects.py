"""Where a scene's objects are at every evaluated frame.

Objects move when characters move them: a picked-up object follows the hand from the stroke of the
hand's movement, a put-down one stays where it was left from the stroke on (the controller moving it
swaps the object's runtime target when the stroke falls in the frames it evaluates). Two controllers that change no pose keep the
record: :class:`ObjectsBefore` runs first in every block and notes each object's runtime target;
:class:`ObjectRecorder` runs last, when every pose is final, and samples the targets over the block's
frames, the old target before a swap and the new one from it (the scene says when: :meth:`switch`, and
ends a block before each swap, :meth:`ObjectRecorder.frames_ahead`, so no block holds two).
"""
from __future__ import annotations

import math

import numpy as np

from ..runtime import Controller, Layer


class ObjectsBefore(Controller):
    """Notes the objects' runtime targets before anything in a block can swap them."""

    kind = "object-recorder"
    layer = Layer.BASE
    priority = -1_000_000  # before everything else
    blend_in_s = 0.0
    blend_out_s = 0.0

    def __init__(self, recorder: "ObjectRecorder"):
        self.recorder = recorder

    def evaluate_one(self, job, block) -> None:
        self.recorder.before = {name: block.runtime.target(name) for name in self.recorder.scene.objects}


class ObjectRecorder(Controller):
    """Records the positions (metres) of ``scene``'s objects, block by block (see the module doc)."""

    kind = "object-recorder"
    layer = Layer.FACE
    priority = 1_000_000  # after everything else
    blend_in_s = 0.0
    blend_out_s = 0.0

    def __init__(self, scene):
        self.scene = scene
        self.before: dict = {}
        self.tracks: dict[str, list[np.ndarray]] = {}
        self.switches: dict[str, list[float]] = {}

    def describe(self) -> str:
        return "object recorder"

    def switch(self, name: str, at_s: float) -> None:
        """Object ``name``'s target is swapped at ``at_s`` seconds (picked up or put down)."""
        self.switches.setdefault(name, []).append(float(at_s))

    def frames_ahead(self, frame: int, most: int) -> int:
        """How many frames (1..``most``) the block starting at ``frame`` may hold: it ends before the next
        swap after its first frame, so a block swaps each object's target at most once, on its first frame."""
        fps = self.scene.fps
        later = [f - frame for times in self.switches.values() for f in (math.ceil(t * fps - 1e-6) for t in times)
                 if frame < f < frame + most]
        return min(later, default=most)

    def evaluate_one(self, job, block) -> None:
        runtime = block.runtime
        for name in self.scene.objects:
            after = runtime.target(name)
            positions = np.array(after.positions(block.times, block), dtype=np.float64)
            before = self.before.get(name, after)
            if before is not after:
                swaps = [t for t in self.switches.get(name, ()) if block.times[0] - 1e-9 <= t <= block.times[-1] + 1e-9]
                at = min(swaps) if swaps else block.times[0]
                earlier = block.times < at - 1e-9
                positions[earlier] = before.positions(block.times, block)[earlier]
            self.tracks.setdefault(name, []).append(positions)

    def track(self, name: str, frames: int) -> np.ndarray:
        """(frames, 3) positions of object ``name`` from frame 0 (its first position before it was recorded)."""
        recorded = self.tracks.get(name)
        start = np.asarray(self.scene.objects[name].position, dtype=np.float64)
        out = np.concatenate(recorded) if recorded else np.zeros((0, 3))
        if len(out) < frames:
            out = np.concatenate([np.broadcast_to(start, (frames - len(out), 3)), out])
        return out[len(out) - frames:]
