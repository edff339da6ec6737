"""Characters for the runtime and controller tests: a synthetic one built from the canonical skeleton,
and the four corpus characters of the gaze checks (Xbot, the SmartBody utah skeleton, the Ready
Player Me avatar and a Bandai BVH), mapped by the heuristic mapper."""
from __future__ import annotations

from functools import lru_cache

import numpy as np

import infuse
from infuse import Asset, Character, quaternions as quat
from infuse.canonical import canonical_skeleton
from infuse.mapping import Mapping, map_skeleton

from corpus_data import corpus_file

CORPUS_CHARACTERS = {
    "xbot": "runxaway-models/Xbot.glb",
    "utah": "smartbody/behaviorsets/MaleLocomotion/skeletons/test_utah.sk",
    "rpm": "talkinghead/avatars/brunette-t.glb",
    "bandai": "bandai/Bandai-Namco-Research-Motiondataset-1/data/dataset-1_walk_normal_001.bvh",
}


def synthetic_character(name: str = "synthetic", drop: tuple[str, ...] = (), morphs: tuple[str, ...] = ()) -> Character:
    """The canonical skeleton as a character (identity rest rotations), without the joints ``drop``
    (their children hang from the nearest kept ancestor), with morph target names ``morphs``."""
    full = canonical_skeleton()
    keep = [i for i, n in enumerate(full.names) if n not in drop]
    index = {old: new for new, old in enumerate(keep)}
    parents, offsets = [], []
    positions = full.rest_global_positions
    for i in keep:
        p = full.parents[i]
        while p >= 0 and p not in index:
            p = full.parents[p]
        parents.append(index[p] if p >= 0 else -1)
        offsets.append(positions[i] - (positions[p] if p >= 0 else 0.0))
    sk = infuse.Skeleton(tuple(full.names[i] for i in keep), np.array(parents), np.array(offsets), quat.identity((len(keep),)))
    asset = Asset(None, "synthetic", sk, morph_targets=list(morphs))
    mapping = Mapping.build(sk, {n: n for n in sk.names}, mapper="identity")
    return Character(name, asset, mapping=mapping)


@lru_cache(maxsize=None)
def corpus_character(key: str) -> Character:
    """A corpus character mapped by the default (heuristic) mapper."""
    asset = infuse.load(corpus_file(CORPUS_CHARACTERS[key]))
    return Character(key, asset, mapping=map_skeleton(asset))


def first_frame(motion) -> infuse.Motion:
    """A one-frame clip of ``motion``'s first frame (to hold a pose)."""
    jt = None if motion.joint_translations is None else motion.joint_translations[:1]
    return motion.replace(local_rotations=motion.local_rotations[:1], root_translations=motion.root_translations[:1],
                          joint_translations=jt)


def reference_frame(character: Character) -> tuple[np.ndarray, np.ndarray, bool]:
    """Global rotations (J, 4) and positions (J, 3) of the pose a test reads the character's axes from:
    the rest pose when its head is above its hips, else the first frame of its clip; and whether that
    is the clip's frame (the test must then hold that pose under the controllers)."""
    sk = character.skeleton
    m = character.mapping
    up = sk.rest_global_positions[sk.index[m["skullbase"]]] - sk.rest_global_positions[sk.index[m["base"]]]
    if up[1] > 0.5 * np.linalg.norm(up):
        return sk.rest_global_rotations, sk.rest_global_positions, False
    clip = next(iter(character.asset.motions.values()))
    g_rot, g_pos = infuse.motion_fk(first_frame(clip))
    return g_rot[0], g_pos[0], True


def body_axes(character: Character) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(left, up, forward) unit vectors of the character in its reference pose, by the rule the runtime
    documents: up from the pelvis to the head, left from the right hip to the left hip, forward = left x up."""
    _, pos, _ = reference_frame(character)
    idx = character.mapping.indices(character.skeleton)
    up = pos[idx["skullbase"]] - pos[idx["base"]]
    up /= np.linalg.norm(up)
    left = pos[idx["l_hip"]] - pos[idx["r_hip"]]
    left -= np.dot(left, up) * up
    left /= np.linalg.norm(left)
    return left, up, np.cross(left, up)
