"""``infuse retarget MOTION --to CHARACTER -o OUT``: put a clip onto another character.

Both skeletons are mapped to the canonical names (``--mapper``, or saved maps ``--map`` for the
motion and ``--target-map`` for the character; a partial map is completed by the mapper). BVH
output carries the character's joint names and rest offsets; glTF/GLB output is a copy of the
character, mesh and all, with the new clip as its first (and, unless ``--keep-clips``, only)
animation. Each written clip stands on the ground, its feet's lowest point (soles included) at
y = 0, unless ``--no-ground``. Nothing is written unless everything succeeds.
"""
from __future__ import annotations

import dataclasses
from pathlib import Path

from infuse import fileio, registry
from infuse.cli.builtin import add_read_options, read_options
from infuse.cli.map_command import add_mapping_options
from infuse.errors import InputError, UnusableInputError, UsageError
from infuse.grounding import foot_height, grounded
from infuse.mapping import map_skeleton, sample_poses
from infuse.motion import carry_morph_weights
from infuse.plugin_types import normalized_extension

from .retarget import IK_MODES, retarget_clip
from .transfer import RetargetPlan


def add_arguments(p) -> None:
    p.add_argument("motion", metavar="MOTION", help="the clip to retarget (BVH, SmartBody .skm, glTF, ...)")
    p.add_argument("--to", dest="character", required=True, metavar="CHARACTER", help="the character that receives it")
    p.add_argument("-o", "--output", required=True, metavar="OUT", help="output file: .bvh, or .glb/.gltf (the character with the new clip)")
    add_mapping_options(p)
    p.add_argument("--target-map", metavar="MAP.json", help="saved joint map for the character (completed by the mapper)")
    p.add_argument("--clip", help="which clip of MOTION (default: its first)")
    p.add_argument("--name", help="name of the new clip (default: the source clip's)")
    p.add_argument("--ik", choices=IK_MODES, default="contacts",
                   help="foot constraints: contacts (pinned planted feet, default), paper (warped trajectories), none")
    p.add_argument("--no-ik", dest="ik", action="store_const", const="none", help="the plain transfer (same as --ik none)")
    p.add_argument("--limb-scaling", action="store_true", help="scale reaching hands by arm length as the arm extends")
    p.add_argument("--keep-clips", action="store_true",
                   help="glTF output: keep the character's own clips after the new one (default: the new clip only)")
    p.add_argument("--no-ground", dest="ground", action="store_false",
                   help="keep the clips' heights (default: each lifted or lowered so its lowest foot touches y = 0)")
    add_read_options(p)


def _meshes_if_readable(character) -> tuple:
    """The character's meshes (soles of feet without a ball joint), or none when they cannot be decoded: a
    skeleton-only output (``.bvh``) never needed them, and a ``.glb`` output reports them when it writes."""
    try:
        return character.meshes
    except (InputError, UnusableInputError):  # malformed, or compressed with a codec not installed
        return ()


def _clip(asset, name, path):
    if not asset.motions:
        raise UnusableInputError(path, "has no motion clip to retarget")
    if name is None:
        return next(iter(asset.motions.values()))
    if name not in asset.motions:
        known = ", ".join(repr(n) for n in asset.motions)
        raise InputError(path, f"clip {name!r}", f"no such clip; clips: {known}")
    return asset.motions[name]


def source_mapping(asset, mapper: str | None, saved_map):
    """The motion file's canonical mapping, over its whole skeleton.

    A motion file may animate only some joints (``Motion.animated_joints``), but every joint has a
    global orientation, so the mapping is not restricted to the animated ones: a SmartBody reach
    that turns ``l_sternoclavicular`` moves the unanimated clavicle joint below it.
    """
    return map_skeleton(asset.skeleton, mapper=mapper, saved_map=saved_map, pose=sample_poses(asset),
                        meta=asset.meta, humanoid=asset.humanoid, file=asset.path)


def run(args) -> int:
    out = Path(args.output)
    ext = normalized_extension(out)
    if not any(ext in w.extensions for w in registry.writers().values()):
        raise UsageError(f"{out}: no installed writer handles {ext or 'files without extension'!r} (use .bvh or .glb)")
    motion_path = Path(args.motion)
    asset = fileio.load(motion_path, format=getattr(args, "read_format", None), **read_options(args))
    clip = _clip(asset, args.clip, motion_path)
    mapper = args.mapper  # None: the default mapper
    src_map = source_mapping(asset, mapper, args.map_file)
    character = fileio.load(args.character)
    tgt_map = map_skeleton(character, mapper=mapper, saved_map=args.target_map)
    target_clip = next(iter(character.motions.values()), None)
    plan = RetargetPlan(clip.skeleton, src_map, character.skeleton, tgt_map, source_motion=clip,
                        target_motion=target_clip, source_file=motion_path, target_file=args.character,
                        target_meshes=_meshes_if_readable(character))
    result = retarget_clip(plan, clip, ik=args.ik, limb_scaling=args.limb_scaling)
    name = args.name or clip.name or motion_path.stem
    motion = carry_morph_weights(result.motion.replace(name=name), clip, character.morph_targets)
    kept = dict(character.motions) if args.keep_clips and ext != ".bvh" else {}
    while name in kept:
        name += "_retargeted"
    # The new clip first: Blender makes the first animation the active action and three.js code
    # plays animations[0]; the character's own clips follow only when asked for.
    motions = {name: motion.replace(name=name), **kept}
    if args.ground:
        motions = {k: grounded(m, foot_height(character, tgt_map, m)) for k, m in motions.items()}
    fileio.save(dataclasses.replace(character, motions=motions), out)
    unmet = [k for k, r in result.residual.items() if (r[result.reachable[k]] > 1e-3).any()]
    print(f"wrote {out}: clip {name!r}, {motion.num_frames} frames at {motion.fps:g} fps, "
          f"leg scale {result.scale:.3f}, feet: {args.ik}"
          + (f"; goals missed by > 1 mm on {', '.join(unmet)}" if unmet else ""))
    return 0
