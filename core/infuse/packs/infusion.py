"""Infusing a character with behaviour packs: map it, retarget every clip, build its blend spaces, cache.

::

    from infuse.packs import infuse_character
    infusion = infuse_character("Xbot.glb", ["locomotion-female", "reaching"], cache="~/.cache/infuse")
    space = infusion.spaces["locomotion-female"]      # a BlendSpace on the character's skeleton

Each clip of each pack is retargeted onto the character (all clips of a pack as one batch through the
installed retargeter), its parameters are measured again on the character (a shorter character walks
slower at the same cadence), and the parameter spaces are tessellated anew. The result is cached as an
``.npz`` (clip arrays) and a ``.json`` (everything else) keyed by the character's file, its mapping,
the packs' fingerprints and versions and infuse's version, so the next load skips all of it.
"""
from __future__ import annotations

import hashlib
import json
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .. import __version__, fileio, registry
from ..asset import Asset, Character
from ..atomic import atomic_path
from ..contacts import contact_phases, feet, foot_contacts, leg_length, lowest_points
from ..errors import MissingFeatureError, MissingJointsError, UsageError
from ..kinematics import forward_kinematics
from ..mapping import Mapping, map_skeleton
from ..motion import Motion
from ..runtime.limb_ik import hangs_below, is_carried
from ..skeleton import Skeleton
from .balls import balls_above, depths, planted_heights
from .analysis import body_frame_point, coordinates_of, headings, locomotion_parameters, resolution_of, transition_parameters
from .compatible import CompatibleBlend
from .coverage import SpeedLimit
from .cycles import STRAIGHTEN_DEG_S, alignment, straighten
from .order import content_order
from .pack import Pack, file_digest, load_pack
from .tessellation import Tessellation

CACHE_FORMAT = 6
#: Transitions a locomotion controller plays whole, with their own root motion.
PLAYED_TRANSITIONS = ("start", "stop", "turn")
#: Options for the retargeter. The runtime controllers pin the feet and place the hands themselves, so
#: infusing needs only the transfer (rotations through the canonical frame, root scaled by leg length).
RETARGET_OPTIONS = {"ik": "none"}


@dataclass
class BlendClip:
    """One example of a blend space on the character.

    ``motion``: the clip's cycle (locomotion), or the whole clip (a reach, or a locomotion
    ``transition``: ``"start"``, ``"stop"`` or ``"turn"`` on the spot), retargeted; ``keys``: (3,) seconds
    from the motion's start of left strike, right strike and next left strike (may pass the end of a
    loop: they wrap); ``contacts``: (F, 2) planted flags, left and right; ``parameters``: measured on
    the character; ``stroke``: seconds (reach).
    """

    name: str
    role: str
    hand: str | None
    loop: bool
    motion: Motion
    keys: np.ndarray
    contacts: np.ndarray
    parameters: dict
    stroke: float = 0.0
    phases: np.ndarray | None = None
    transition: str | None = None
    #: (F, 3) a transition's pelvis positions (metres, in the clip's frame): it is placed by its pelvis.
    pelvis: np.ndarray | None = None

    def __post_init__(self):
        if self.phases is None:
            self.phases = np.stack((self.contacts, np.zeros_like(self.contacts)), axis=-1)

    @property
    def duration(self) -> float:
        return self.motion.duration


@dataclass
class BlendSpace:
    """A pack's clips on one character, and the tessellations that blend them (one per group:
    ``"locomotion"``, or ``"left"``/``"right"`` hands for reaches)."""

    pack: str
    version: str
    kind: str
    clips: dict[str, BlendClip]
    tessellations: dict[str, Tessellation]

    @property
    def coordinates(self) -> tuple[str, ...]:
        return coordinates_of(self.kind)

    def group(self, name: str) -> list[BlendClip]:
        return [self.clips[n] for n in self.tessellations[name].labels]

    def weights(self, group: str, query) -> tuple[np.ndarray, np.ndarray]:
        """Blend weights (Q, N) over :meth:`group` ``group``'s clips for (Q, D) parameter points, and (Q,)
        flags of the points inside its tessellation; a locomotion request is blended from the examples
        that do not travel against it wherever they reach it (:mod:`.compatible`)."""
        w, inside = self.tessellations[group].weights(query)
        if self.kind == "locomotion":
            w = self._compatible(group).weights(query, w)
        return w, inside

    def locomotion_weights(self, query) -> tuple[np.ndarray, np.ndarray]:
        """Blend weights (Q, N) of (Q, 3) locomotion requests (forward speed, lateral speed, turn rate) and (Q,)
        flags of the requests inside the tessellation, as :meth:`weights` gives them, but a request outside
        weighed at the turn rate nearest its own that the tessellation holds at its velocity (the rest is spun
        at the root; :meth:`~.coverage.Hull.nearest_turns`), where it holds one. Each request is weighed once:
        the turned ones located again, alone."""
        t = self.tessellations["locomotion"]
        query = np.atleast_2d(np.asarray(query, dtype=np.float64))
        at = t.locate(query)
        inside = at.inside
        if not np.logical_and.reduce(inside):
            out = np.nonzero(~inside)[0]
            turns, ok = self.speed_limit().hull.nearest_turns(query[out, :2], query[out, 2])
            if np.logical_or.reduce(ok):  # the others keep the weights of the full request's nearest point
                cut = out[ok]
                query = query.copy()
                query[cut, 2] = turns[ok]
                at = at.replaced(cut, t.locate(query[cut]))
        return self._compatible("locomotion").weights(query, t.weights(query, at)[0]), inside

    def slowest(self, direction) -> np.ndarray:
        """(Q,) the slowest speed (m/s) at which the locomotion examples not travelling against each of (Q,)
        ``direction`` radians (+ left of the facing) reach it; NaN where they do not."""
        return self._compatible("locomotion").slowest(direction)

    def _compatible(self, group: str) -> CompatibleBlend:
        cached = self.__dict__.setdefault("_compatible_blends", {})
        t = self.tessellations[group]
        blend = cached.get(group)
        if blend is None or blend.t is not t:
            blend = cached[group] = CompatibleBlend(t, resolution_of(self.kind))
        return blend

    def contains(self, group: str, query) -> np.ndarray:
        """(Q,) flags of (Q, D) parameter points inside ``group``'s tessellation."""
        return self.tessellations[group].contains(query)

    def speed_limit(self):
        """The locomotion group's :class:`~infuse.packs.coverage.SpeedLimit` (top speed by travel
        direction), made once."""
        cached = self.__dict__.get("_speed_limit")
        if cached is None or cached[0] is not self.tessellations["locomotion"]:
            cached = self.__dict__["_speed_limit"] = (self.tessellations["locomotion"], SpeedLimit(self.tessellations["locomotion"]))
        return cached[1]

    def range(self, coordinate: str, group: str | None = None) -> tuple[float, float]:
        """Smallest and largest value of a coordinate over a group's examples."""
        t = self.tessellations[group or next(iter(self.tessellations))]
        col = t.points[:, t.coordinates.index(coordinate)]
        return float(col.min()), float(col.max())


@dataclass
class Infusion:
    """A character infused with packs: ``spaces`` pack name -> :class:`BlendSpace`; ``seconds`` it took;
    ``cached``: loaded from the cache."""

    character: Character
    mapping: Mapping
    spaces: dict[str, BlendSpace]
    seconds: float = 0.0
    cached: bool = False
    cache_file: Path | None = None
    notes: list[str] = field(default_factory=list)


def as_character(source) -> Character:
    if isinstance(source, Character):
        return source
    if isinstance(source, Asset):
        return Character(source.path.stem if source.path else "character", source)
    path = Path(source)
    return Character(path.stem, fileio.load(path))


def _signature(pack: Pack) -> str:
    """Packs with equal signatures share a skeleton and a mapping, so they retarget as one batch."""
    sk = pack.skeleton
    h = hashlib.sha256("|".join(sk.names).encode())
    for arr in (sk.parents, sk.rest_translations, sk.rest_rotations):
        h.update(np.ascontiguousarray(arr).tobytes())
    h.update(json.dumps(pack.mapping.mapped(), sort_keys=True).encode())
    return h.hexdigest()


def retarget_packs(packs: list[Pack], character: Character, mapping: Mapping, retargeter: str | None = None,
                   **options) -> dict[str, tuple[Motion, np.ndarray, list[str]]]:
    """Every clip of ``packs`` on ``character``: pack name -> (all its clips joined, (N+1,) frame bounds,
    the N clip names in the order joined).

    Packs sharing a skeleton go through the retargeter as one clip (one plan, one batch), their clips
    joined in :func:`~infuse.packs.order.content_order`: the retargeter reads the batch as a whole (its
    reference pose), so the order is set by the clips' content, not by the names of the packs and clips
    or the order they are listed in. Each pack's clips keep that order. Each clip goes in moved to start
    over the origin (:func:`_from_origin`).
    """
    if not registry.retargeters():
        raise MissingFeatureError(None, "no retargeter installed: install infuse-anim-retarget")
    chosen = registry.get("retargeter", retargeter)
    groups: dict[str, list[Pack]] = {}
    for p in packs:
        groups.setdefault(_signature(p), []).append(p)
    out = {}
    for members in groups.values():
        sk = members[0].skeleton
        every = {(p.name, n): m if m.skeleton is sk else m.replace(skeleton=sk) for p in members for n, m in p.motions.items()}
        order = content_order(every)
        motions = _from_origin([every[key] for key in order], members[0].mapping.indices(sk))
        fps = motions[0].fps
        moved = any(m.joint_translations is not None for m in motions)
        joined = Motion(sk, fps, np.concatenate([m.local_rotations for m in motions]),
                        np.concatenate([m.root_translations for m in motions]),
                        np.concatenate([m.local_translations() for m in motions]) if moved else None, name=members[0].name)
        result = chosen.retarget(joined, members[0].mapping, character.skeleton, mapping, **options)
        starts = dict(zip(order, np.cumsum([0] + [m.num_frames for m in motions[:-1]])))
        jt = result.joint_translations
        for p in members:
            names = [n for pack, n in order if pack == p.name]
            lengths = [p.motions[n].num_frames for n in names]
            frames = np.concatenate([np.arange(starts[(p.name, n)], starts[(p.name, n)] + f) for n, f in zip(names, lengths)])
            part = Motion(character.skeleton, fps, result.local_rotations[frames], result.root_translations[frames],
                          None if jt is None else jt[frames], name=p.name)
            out[p.name] = (part, np.cumsum([0] + lengths), names)
    return out


def _from_origin(motions: list[Motion], index: dict[str, int]) -> list[Motion]:
    """``motions`` each moved on the ground so that the midpoint of its hip joints starts over the origin.

    The retargeter scales a batch's travel about where its first clip starts: moved so, every clip's
    travel on the character is the same whichever clip comes first (where a clip was recorded on
    the capture floor carries no meaning)."""
    sk = motions[0].skeleton
    jt = [m.local_translations()[:1] for m in motions] if any(m.joint_translations is not None for m in motions) else None
    _, g_pos = forward_kinematics(sk, np.concatenate([m.local_rotations[:1] for m in motions]),
                                  np.concatenate([m.root_translations[:1] for m in motions]), None if jt is None else np.concatenate(jt))
    start = 0.5 * (g_pos[:, index["l_hip"]] + g_pos[:, index["r_hip"]]) * np.array([1.0, 0.0, 1.0])  # (N, 3)
    return [m.replace(root_translations=m.root_translations - s) for m, s in zip(motions, start)]


def infuse_pack(pack: Pack, character: Character, mapping: Mapping,
                retargeted: tuple[Motion, np.ndarray, list[str]]) -> BlendSpace:
    """The :class:`BlendSpace` of ``pack`` on ``character`` from its ``retargeted`` clips (see
    :func:`retarget_packs`); its clips and each tessellation's examples are in the order retargeted (by content)."""
    out, bounds, names = retargeted
    sk = character.skeleton
    index = mapping.indices(sk)
    pair = feet(sk, mapping)
    if pack.kind == "locomotion":
        out = _balls_grounded(pack, names, out, pair)
    g_rot, g_pos = forward_kinematics(sk, out.local_rotations, out.root_translations, out.joint_translations)
    heading = headings(g_pos, index)
    root = g_pos[:, index["base"]]
    starts = np.asarray(bounds[:-1], dtype=np.int64)
    ground = float(lowest_points(sk, pair, g_rot[starts], g_pos[starts]).min())  # the feet at the clips' starts, any order
    clips = {}
    for k, info in enumerate(pack.clip_info(n) for n in names):
        a, b = int(bounds[k]), int(bounds[k + 1])
        contacts = np.asarray(info["contacts"], dtype=bool).T
        phases = None  # a pack built without phases: the heel is down whenever the foot is
        if "heel_contacts" in info:
            phases = np.stack((np.asarray(info["heel_contacts"], dtype=bool).T, np.asarray(info["ball_contacts"], dtype=bool).T), axis=-1)
        fps = float(info["fps"])
        transition = info.get("transition") if pack.kind == "locomotion" and info.get("transition") in PLAYED_TRANSITIONS else None
        if transition is not None:  # played whole: measured whole
            sl = slice(a, b)
            params = transition_parameters(root[sl], heading[sl], fps)
            keys = np.asarray(info["keys"], dtype=np.float64)
            stroke = 0.0
        elif pack.kind == "locomotion":
            c0, c1 = info["cycle"]
            sl = slice(a + c0, a + c1 + 1)
            params = locomotion_parameters(root[sl], heading[sl], (0, c1 - c0), fps)
            keys = np.asarray(info["keys"], dtype=np.float64) - c0 / fps
            contacts = contacts[c0:c1 + 1]
            phases = None if phases is None else phases[c0:c1 + 1]
            stroke = 0.0
        elif pack.kind in ("gesture", "posture"):  # played by its phases (``info["sync"]``) or looped, not blended
            sl = slice(a, b)
            stroke = float(info["stroke"])
            params = {}
            keys = np.array([0.0, stroke, info["duration"]])
        else:
            sl = slice(a, b)
            stroke = float(info["stroke"])
            wrist = g_pos[a + int(info["stroke_frame"]), index[f"{info['hand'][0]}_wrist"]]
            p = body_frame_point(wrist, root[a], float(heading[a]), ground)
            params = {"x": float(p[0]), "y": float(p[1]), "z": float(p[2]), "heading_start": float(heading[a])}
            keys = np.array([0.0, stroke, info["duration"]])
        m = Motion(sk, fps, out.local_rotations[sl], out.root_translations[sl],
                   None if out.joint_translations is None else out.joint_translations[sl], name=info["name"])
        pelvis = None
        if transition is not None:  # played as it is: its feet pinned where they are down on this character
            found = foot_contacts(m, mapping, fk=(g_rot[sl], g_pos[sl]))
            contacts, phases, pelvis = found.foot_flags(), contact_phases(found, g_pos[sl]), root[sl]
        if pack.kind == "locomotion" and info.get("derived"):  # straight and aligned on this character too
            m, params = _restraightened(m, params, index)
        clips[info["name"]] = BlendClip(info["name"], info["role"], info.get("hand"), bool(info["loop"]), m, keys, contacts,
                                        params, stroke, phases, transition, pelvis)
    coords = coordinates_of(pack.kind)
    tess = {}
    rank = {n: k for k, n in enumerate(names)}
    for group, t in pack.tessellations().items():
        labels = sorted(t.labels, key=rank.__getitem__)  # by content, as the builder lists them (packs built before listed by name)
        tess[group] = Tessellation.build(coords, labels, [[clips[n].parameters[c] for c in coords] for n in labels],
                                         resolution=resolution_of(pack.kind))
    return BlendSpace(pack.name, pack.version, pack.kind, clips, tess)


#: The limbs a pack of each kind poses with IK, root to end ("{s}": each side its clips use, "l" and "r"
#: for locomotion). Each joint must be mapped and hang below the one before it, but the end may hang
#: outside its limb (carried by the end of the middle joint's bone: :func:`~infuse.runtime.limb_ik.is_carried`).
DRIVEN_LIMBS = {
    "locomotion": (("{s}_hip", "{s}_knee", "{s}_ankle"),),
    "reach": (("{s}_shoulder", "{s}_elbow", "{s}_wrist"),),
    "gesture": (("{s}_shoulder", "{s}_elbow", "{s}_wrist"),),
    "posture": (("{s}_hip", "{s}_knee", "{s}_ankle"), ("{s}_shoulder", "{s}_elbow", "{s}_wrist")),
}


def _require_joints(pack: Pack, character: Character, mapping: Mapping) -> None:
    """Refuse (exit 3) a pack whose limbs the character lacks or does not hold as chains, naming them."""
    hands = {c.hand for c in pack.manifest.clips if c.hand}
    sides = ("l", "r") if pack.kind in ("locomotion", "posture") or "both" in hands else \
        tuple(sorted({h[0] for h in hands}))
    index = {n: k for k, n in enumerate(character.skeleton.names)}
    missing, detached = [], []
    for limb in DRIVEN_LIMBS.get(pack.kind, ()):
        for s in sides:
            names = [n.format(s=s) for n in limb]
            missing += [n for n in names if mapping.get(n) is None]
            joints = [index.get(mapping.get(n) or "") for n in names]
            carried = None not in joints and is_carried(character.skeleton, joints)
            for upper, lower, name in zip(joints, joints[1:], names[1:]):
                if upper is None or lower is None or (carried and lower == joints[-1]):
                    continue
                if not hangs_below(character.skeleton, lower, upper):
                    detached.append(name)
    if missing:
        raise MissingJointsError(character.asset.path, f"pack '{pack.name}' drives {', '.join(missing)}, which "
                                 f"the character's mapping does not have (see infuse map)")
    if detached:
        raise MissingJointsError(character.asset.path, f"pack '{pack.name}' poses limbs with IK, but "
                                 f"{', '.join(detached)} {'does' if len(detached) == 1 else 'do'} not hang below the joint before it "
                                 f"in its limb (a limb's end may hang outside the limb, not from inside it)")


def _balls_grounded(pack: Pack, names: list[str], out: Motion, pair) -> Motion:
    """The retargeted clips ``out`` (joined in ``names`` order) with each foot's ball kept from going
    deeper below the height it stands at, where the pack's clips have that foot flat, than the source's
    ball goes below its own (scaled by the legs' ratio; :mod:`.balls`)."""
    infos = [pack.clip_info(n) for n in names]
    if not all("heel_contacts" in info for info in infos):
        return out
    flat = np.concatenate([(np.asarray(i["heel_contacts"], dtype=bool) & np.asarray(i["ball_contacts"], dtype=bool)).T
                           for i in infos])
    sk = pack.skeleton
    source_pair = feet(sk, pack.mapping)
    source = [pack.motions[n] for n in names]
    _, s_pos = forward_kinematics(sk, np.concatenate([m.local_rotations for m in source]),
                                  np.concatenate([m.root_translations for m in source]),
                                  np.concatenate([m.local_translations() for m in source])
                                  if any(m.joint_translations is not None for m in source) else None)
    _, g_pos = forward_kinematics(out.skeleton, out.local_rotations, out.root_translations, out.joint_translations)
    scale = leg_length(out.skeleton, pair) / leg_length(sk, source_pair)
    allowed = scale * depths(s_pos, source_pair, planted_heights(s_pos, source_pair, flat))
    return balls_above(out, pair, planted_heights(g_pos, pair, flat), allowed)[0]


def _restraightened(motion: Motion, params: dict, index: dict[str, int]) -> tuple[Motion, dict]:
    """A cycle the builder straightened (or aligned with its travel), retargeted: what is left of its turn
    taken out and its travel aligned again as measured on the character (retargeting moves the hips a
    little), then measured again. Returns the motion and its parameters."""
    turn = params["turn_rate"] if abs(np.degrees(params["turn_rate"])) < STRAIGHTEN_DEG_S else 0.0
    cycle = (0, motion.num_frames - 1)
    motion = straighten(motion, params, cycle, turn, alignment(params["direction"]))
    _, g_pos = forward_kinematics(motion.skeleton, motion.local_rotations, motion.root_translations, motion.joint_translations)
    return motion, locomotion_parameters(g_pos[:, index["base"]], headings(g_pos, index), cycle, motion.fps)


def cache_key(character: Character, mapping: Mapping, packs: list[Pack], retargeter: str | None) -> str:
    h = hashlib.sha256()
    path = character.asset.path
    if path is not None and Path(path).is_file():
        h.update(file_digest(Path(path)).encode())
    sk = character.skeleton
    for arr in (sk.parents, sk.rest_translations, sk.rest_rotations):
        h.update(np.ascontiguousarray(arr).tobytes())
    h.update(json.dumps(mapping.mapped(), sort_keys=True).encode())
    for p in packs:
        h.update(f"{p.name}|{p.version}|{p.require_built()['fingerprint']}".encode())
    h.update(f"{__version__}|{CACHE_FORMAT}|{retargeter or 'default'}".encode())
    return h.hexdigest()[:32]


def _cache_paths(cache, key: str) -> tuple[Path, Path]:
    path = Path(cache).expanduser()
    if path.suffix == ".npz":
        return path, path.with_suffix(".json")
    return path / f"{key}.npz", path / f"{key}.json"


def save_infusion(infusion: Infusion, key: str, cache) -> Path:
    """Write the infusion's clips (.npz) and metadata (.json) atomically; returns the .npz path."""
    npz, meta = _cache_paths(cache, key)
    arrays: dict[str, Any] = {}
    spaces: dict[str, dict[str, Any]] = {}
    doc = {"format": CACHE_FORMAT, "key": key, "infuse": __version__, "mapping": infusion.mapping.mapped(), "spaces": spaces}
    for name, space in infusion.spaces.items():
        names = list(space.clips)
        ms = [space.clips[n].motion for n in names]
        arrays[f"{name}/rotations"] = np.concatenate([m.local_rotations for m in ms])
        arrays[f"{name}/roots"] = np.concatenate([m.root_translations for m in ms])
        if any(m.joint_translations is not None for m in ms):
            arrays[f"{name}/joint_translations"] = np.concatenate([m.local_translations() for m in ms])
        arrays[f"{name}/bounds"] = np.cumsum([0] + [m.num_frames for m in ms])
        arrays[f"{name}/contacts"] = np.concatenate([space.clips[n].contacts for n in names]).astype(np.int8)
        arrays[f"{name}/phases"] = np.concatenate([space.clips[n].phases for n in names]).astype(np.int8)
        for k, n in enumerate(names):
            if space.clips[n].pelvis is not None:
                arrays[f"{name}/pelvis{k}"] = space.clips[n].pelvis
        spaces[name] = {
            "version": space.version, "kind": space.kind,
            "clips": [{"name": c.name, "role": c.role, "hand": c.hand, "loop": c.loop, "fps": c.motion.fps,
                       "keys": c.keys.tolist(), "parameters": c.parameters, "stroke": c.stroke,
                       "transition": c.transition} for c in (space.clips[n] for n in names)],
            "tessellations": {g: t.to_dict() for g, t in space.tessellations.items()},
        }
    with atomic_path(npz) as tmp:
        with open(tmp, "wb") as f:
            np.savez(f, **arrays)
    with atomic_path(meta) as tmp:
        Path(tmp).write_text(json.dumps(doc) + "\n", encoding="utf-8")
    return npz


def load_infusion(character: Character, mapping: Mapping, key: str, cache) -> dict[str, BlendSpace] | None:
    """The cached blend spaces for ``key``, or None when there is no matching cache."""
    npz, meta = _cache_paths(cache, key)
    if not (npz.is_file() and meta.is_file()):
        return None
    try:
        doc = json.loads(meta.read_text(encoding="utf-8"))
    except (json.JSONDecodeError, UnicodeDecodeError):
        return None
    if doc.get("key") != key or doc.get("format") != CACHE_FORMAT:
        return None
    sk: Skeleton = character.skeleton
    spaces = {}
    with np.load(npz, allow_pickle=False) as z:
        for name, s in doc["spaces"].items():
            rot, roots, bounds = z[f"{name}/rotations"], z[f"{name}/roots"], z[f"{name}/bounds"]
            jt = z[f"{name}/joint_translations"] if f"{name}/joint_translations" in z.files else None
            contacts = z[f"{name}/contacts"].astype(bool)
            phases = z[f"{name}/phases"].astype(bool)
            clips = {}
            for k, c in enumerate(s["clips"]):
                a, b = int(bounds[k]), int(bounds[k + 1])
                m = Motion(sk, c["fps"], rot[a:b], roots[a:b], None if jt is None else jt[a:b], name=c["name"])
                pelvis = z[f"{name}/pelvis{k}"] if f"{name}/pelvis{k}" in z.files else None
                clips[c["name"]] = BlendClip(c["name"], c["role"], c["hand"], c["loop"], m, np.asarray(c["keys"]),
                                             contacts[a:b], c["parameters"], c["stroke"], phases[a:b],
                                             c.get("transition"), pelvis)
            tess = {g: Tessellation.from_dict(t) for g, t in s["tessellations"].items()}
            spaces[name] = BlendSpace(name, s["version"], s["kind"], clips, tess)
    return spaces


def infuse_character(character, packs, mapping: Mapping | None = None, cache=None, retargeter: str | None = None,
                     mapper: str | None = None) -> Infusion:
    """Infuse ``character`` (a Character, Asset or file path) with ``packs`` (names, folders, manifests or
    :class:`Pack` objects): map it (unless ``mapping`` is given), retarget every clip, build the blend
    spaces. With ``cache`` (a folder, or an ``.npz`` path) the result is stored and reused."""
    start = time.perf_counter()
    character = as_character(character)
    if not packs:
        raise UsageError("name at least one behaviour pack to infuse")
    loaded = [load_pack(p) for p in packs]
    for p in loaded:
        p.require_built()
    if mapping is None:
        mapping = character.mapping if character.mapping is not None else map_skeleton(character.asset, mapper=mapper or "heuristic")
    character.mapping = mapping
    for p in loaded:
        _require_joints(p, character, mapping)
    key = cache_key(character, mapping, loaded, retargeter) if cache is not None else ""
    spaces = load_infusion(character, mapping, key, cache) if cache is not None else None
    cached = spaces is not None
    if spaces is None:
        moved = retarget_packs(loaded, character, mapping, retargeter, **RETARGET_OPTIONS)
        spaces = {p.name: infuse_pack(p, character, mapping, moved[p.name]) for p in loaded}
    infusion = Infusion(character, mapping, spaces, cached=cached)
    if cache is not None and not cached:
        infusion.cache_file = save_infusion(infusion, key, cache)
    elif cached:
        infusion.cache_file = _cache_paths(cache, key)[0]
    infusion.seconds = time.perf_counter() - start
    return infusion
