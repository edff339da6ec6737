"""A scene with the default idle (blinks, breathing) exports every kind of character: the clip it
made is the file's first animation, the character stands on the ground, and the idle drove only
channels the file can carry."""
from __future__ import annotations

import numpy as np
import pytest

import infuse
from infuse.grounding import foot_height
from infuse.mapping import map_skeleton
from infuse.scene import Scene
from infuse_gltf.container import parse_file

from corpus_data import corpus_file, require_corpus

CHARACTERS = {
    "vrm": "vrm-specification/samples/VRMC_vrm_expressions_isBinary_Overrides/vrm/VRMC_vrm_expressions_isBinary_Overrides.vrm",
    "gltf": "runxaway-models/Xbot.glb",
    "ready-player-me": "talkinghead/avatars/brunette-t.glb",
    "smartbody": "smartbody/mesh/brad/Brad.dae",
    "fbx": "ue4-mannequin/SK_Mannequin.FBX",
}


@pytest.mark.parametrize("kind", CHARACTERS)
def test_default_idle_exports_on_the_ground(kind, tmp_path):
    require_corpus()
    scene = Scene(quiet=True, seed=3)
    name = scene.add_character(corpus_file(CHARACTERS[kind]))
    scene.run(3.0)
    out = tmp_path / f"{kind}.glb"
    scene.export(name, out)
    assert [a["name"] for a in parse_file(out).json["animations"]][0] == "scene"
    back = infuse.load(out)
    motion = back.motions["scene"]
    assert motion.num_frames == 90
    assert abs(foot_height(back, map_skeleton(back), motion)) < 1e-4  # SmartBody's Brad was a metre down
    tracks = dict(zip(motion.morph_names, motion.morph_weights.T))
    assert set(tracks) <= set(back.morph_targets)
    if kind == "ready-player-me":  # it has eyelid morph targets: it blinks
        assert np.max(tracks["eyeBlinkLeft"]) > 0.8
