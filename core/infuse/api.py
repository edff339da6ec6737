"""The public plugin API: the modules of infuse a plugin may import, and what each offers it.

A plugin (any distribution found through the entry points of :data:`infuse.registry.KINDS`) imports
infuse only from these modules, and imports no other plugin; every other module of infuse is internal
and may change without notice. ``tests/test_plugin_api.py`` checks the plugins, examples and packs of
this repository against this list.

Array layouts, stated once: what crosses this API is frame-major, ``(F, J, ...)`` for F frames of
J joints (rotations ``(F, J, 4)`` as (x, y, z, w) quaternions, translations and positions
``(F, J, 3)`` in metres), morph weights ``(F, M)``, in the core frame (+Y up, +Z the character's
forward, +X its left): ``Motion``, ``Asset``, the pose block controllers write, the descriptors'
arguments. Some hot paths work component-major inside (forward kinematics ``(J, 4, F)``, clip
tables ``(4, ...)``, the retargeter's ``(3, F)`` positions: one component of every frame contiguous);
their docstrings say so, and such arrays do not cross this API.
"""
from __future__ import annotations

#: Module -> what a plugin finds there.
PUBLIC_MODULES: dict[str, str] = {
    # the contract
    "infuse": "load, save, Asset, Character, Skeleton, Motion, the errors, hookimpl, forward kinematics",
    "infuse.hookspecs": "the hooks a plugin implements",
    "infuse.plugin_types": "the descriptors the hooks return",
    "infuse.registry": "other installed plugins by kind and name: table(kind), get(kind, name=None)",
    "infuse.errors": "typed errors naming the input, the place and the problem",
    # the data model and its maths
    "infuse.asset": "Asset and Character: a skeleton, its clips, mesh, morph targets and humanoid map",
    "infuse.skeleton": "Skeleton: joint names, parents, rest pose",
    "infuse.motion": "Motion: one clip's tracks: joint rotations, root motion, morph weights, animated joints",
    "infuse.mesh": "skinned meshes and morph targets",
    "infuse.texture": "texture sampling shared by the mesh readers",
    "infuse.canonical": "the canonical humanoid joint table",
    "infuse.conventions": "units, up axes and the core frame",
    "infuse.quaternions": "vectorized quaternion maths (x, y, z, w)",
    "infuse.transforms": "affine transforms",
    "infuse.kinematics": "forward kinematics over frames",
    "infuse.contacts": "foot contacts: when the heel and the ball of each foot are down",
    "infuse.footing": "planted feet: plant positions and the pinning goals the leg IK enforces",
    "infuse.grounding": "the height of a character's feet at rest, clips lifted onto the ground",
    "infuse.mapping": "Mapping and map_skeleton: canonical joint names of a skeleton",
    "infuse.metrics": "motion quality measures",
    "infuse.speech": "utterances, phonemes and visemes for TTS engines and lip sync",
    # files and progress
    "infuse.fileio": "load and save through the installed readers and writers",
    "infuse.atomic": "writing a file whole or not at all",
    "infuse.limits": "bounds on what an input file may ask for, checked by readers before allocating",
    "infuse.references": "where a file's references to other files may lead",
    "infuse.progress": "progress bars on stderr",
    # controllers and behaviours
    "infuse.runtime": "Runtime, Controller, Layer, Mode, controller(kind)",
    "infuse.runtime.controller": "the controller base class and its jobs and blocks",
    "infuse.runtime.layers": "layers, blending modes and blend curves",
    "infuse.runtime.pose": "the pose block controllers write",
    "infuse.runtime.rig": "a character as the runtime binds it: joints by canonical name, aligned frames",
    "infuse.runtime.swing": "rotations in aligned frames (heading, pitch, roll)",
    "infuse.runtime.targets": "what a controller looks or reaches at",
    "infuse.runtime.tracks": "keyed curves of joint rotations and morph weights",
    "infuse.runtime.clip": "clip sampling and loop tables",
    "infuse.runtime.limb_ik": "two-bone limb inverse kinematics",
    "infuse.bml": "BML behaviour plans, timing models, generations (BML added before scheduling) and errors",
    "infuse.bml.model": "BML documents and the warningFeedback types",
    "infuse.stage": "Stage, Stagehand and Held: what a scene offers the controller realizing a BML behaviour",
    "infuse.packs": "behaviour packs: load_pack, Pack, space_on (a pack infused on a runtime character)",
    "infuse.packs.analysis": "what the pack builder measures in clips (steps, strokes)",
    "infuse.packs.manifest": "pack manifests",
    "infuse.scene": "scenes: characters, objects and timed BML",
    "infuse.scene.scenefile": "reading scene files",
    "infuse.scene.command": "build_scene: a Scene from a scene file's document, as `infuse run` builds it",
    "infuse.scene.speech": "utterance_samples: an utterance's audio as the scene mixes it",
    "infuse.live": "running a scene live",
    # drawing and the command line
    "infuse.render": "Camera, Figure, Marker, render",
    "infuse.render.camera": "camera views",
    "infuse.three": "three.js modules for pages served to a browser (import-map specifiers and files)",
    "infuse.render.command": "parse_size: the --size option shared by commands that draw",
    "infuse.cli.builtin": "options shared by commands that read a file: add_read_options, read_options",
    "infuse.cli.map_command": "options shared by commands that map: add_mapping_options, mapping_from_args",
}


def is_public(module: str) -> bool:
    """Whether a plugin may import ``module`` (a dotted name)."""
    return module in PUBLIC_MODULES
