"""The source of a new plugin of each kind: a small working plugin and its tests, for the author to change.

Each template is a :class:`string.Template` over ``$name`` (the plugin name), ``$package`` (the import
package), ``$distribution``, ``$ident`` (the name as a Python identifier) and ``$extension`` (``.NAME``,
for readers and writers). Every plugin module imports only ``infuse`` and its own package.
"""
from __future__ import annotations

from dataclasses import dataclass
from string import Template


@dataclass(frozen=True)
class KindTemplate:
    """What ``infuse plugin new KIND`` writes: ``modules`` (file name -> source) into the package, ``test``
    into ``tests/``, and a line of README saying what it does and how to use it."""

    group: str
    summary: str
    modules: dict[str, Template]
    test: Template
    usage: str


_JSON_FORMAT = '''A $extension file is a JSON skeleton: ``{"joints": [{"name": "hips", "parent": null, "offset": [0, 1, 0],
"rotation": [0, 0, 0, 1]}, ...]}``; ``offset`` is the joint's rest position in its parent's frame in
metres, ``rotation`` its rest local rotation (x, y, z, w; identity when left out), parents before children.'''

READER = Template('''"""The $name reader: $extension files into an infuse Asset (a skeleton).

''' + _JSON_FORMAT + '''
Replace :func:`read` with your format; keep its contract: convert into the core frame (metres, +Y
up, +Z forward, +X the character's left), honour ``units`` and ``up_axis``, and raise
:class:`infuse.InputError` naming the file, the place and the problem for malformed input.
"""
import json
import math
from pathlib import Path

import numpy as np

import infuse
from infuse import hookimpl
from infuse.conventions import UNIT_SCALES
from infuse.errors import InputError
from infuse.plugin_types import Reader
from infuse.skeleton import Skeleton

EXTENSION = "$extension"
#: A Z-up file's (x, y, z) in the core frame: (x, z, -y).
Z_UP_TO_Y_UP = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])


def _numbers(path, place, value, count):
    if not (isinstance(value, list) and len(value) == count
            and all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in value)):
        raise InputError(path, place, f"expected {count} finite numbers")
    return [float(v) for v in value]


def read(path, units=None, up_axis=None, **options) -> infuse.Asset:
    """The skeleton of a $extension file (see the module doc)."""
    path = Path(path)
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise InputError(path, None, f"not a JSON skeleton: {exc}") from None
    joints = doc.get("joints") if isinstance(doc, dict) else None
    if not isinstance(joints, list) or not joints:
        raise InputError(path, "joints", "expected a non-empty list")
    index, parents, offsets, rotations = {}, [], [], []
    for k, joint in enumerate(joints):
        where = f"joints[{k}]"
        name = joint.get("name") if isinstance(joint, dict) else None
        if not isinstance(name, str) or not name or name in index:
            raise InputError(path, f"{where}.name", "expected a new non-empty joint name")
        parent = joint.get("parent")
        if (parent is None) != (k == 0):
            raise InputError(path, f"{where}.parent", "the first joint is the root, every other has an earlier parent")
        if parent is not None and parent not in index:
            raise InputError(path, f"{where}.parent", f"{parent!r} is not an earlier joint")
        index[name] = k
        parents.append(-1 if parent is None else index[parent])
        offsets.append(_numbers(path, f"{where}.offset", joint.get("offset"), 3))
        rotations.append(_numbers(path, f"{where}.rotation", joint.get("rotation", [0, 0, 0, 1]), 4))
    if units is not None and units not in UNIT_SCALES:
        raise InputError(path, None, f"unknown unit {units!r}; known: {', '.join(UNIT_SCALES)}")
    offsets = np.array(offsets) * UNIT_SCALES[units or "m"]
    rotations = np.array(rotations)
    if np.any(np.abs(np.linalg.norm(rotations, axis=1) - 1.0) > 1e-3):
        raise InputError(path, "joints", "a rotation is not a unit quaternion")
    if (up_axis or "Y").upper() == "Z":
        offsets = offsets @ Z_UP_TO_Y_UP.T
        rotations[:, :3] = rotations[:, :3] @ Z_UP_TO_Y_UP.T
    skeleton = Skeleton(tuple(index), np.array(parents), offsets, rotations)
    return infuse.Asset(path, "$name", skeleton, source_units=units or "m", source_up_axis=(up_axis or "Y").upper())


@hookimpl
def infuse_readers():
    return [Reader("$name", (EXTENSION,), read, "JSON skeletons ($extension)")]
''')

READER_TEST = Template('''"""The $name reader: installed, reads a skeleton, names the place of a mistake."""
import json

import numpy as np
import pytest

import infuse
from infuse.errors import InputError
from infuse.registry import readers

JOINTS = [{"name": "hips", "parent": None, "offset": [0.0, 1.0, 0.0]},
          {"name": "spine", "parent": "hips", "offset": [0.0, 0.2, 0.0]},
          {"name": "head", "parent": "spine", "offset": [0.0, 0.4, 0.05]}]


def test_installed():
    assert "$extension" in readers()["$name"].extensions


def test_reads_a_skeleton(tmp_path):
    path = tmp_path / "three$extension"
    path.write_text(json.dumps({"joints": JOINTS}))
    skeleton = infuse.load(path).skeleton
    assert skeleton.names == ("hips", "spine", "head") and list(skeleton.parents) == [-1, 0, 1]
    assert np.allclose(skeleton.rest_global_positions[2], [0.0, 1.6, 0.05])
    in_cm = infuse.load(path, units="cm").skeleton
    assert np.allclose(in_cm.rest_global_positions[2], [0.0, 0.016, 0.0005])


def test_a_mistake_is_named(tmp_path):
    path = tmp_path / "bad$extension"
    path.write_text(json.dumps({"joints": [JOINTS[0], {**JOINTS[1], "parent": "nobody"}]}))
    with pytest.raises(InputError, match=r"joints\\[1\\]\\.parent"):
        infuse.load(path)
''')

WRITER = Template('''"""The $name writer: an infuse Asset's skeleton into a $extension file.

''' + _JSON_FORMAT + '''
Replace :func:`write` with your format. infuse hands it a temporary path and renames the file when
it returns, so a failed write never leaves half a file.
"""
import json
from pathlib import Path

from infuse import hookimpl
from infuse.plugin_types import Writer

EXTENSION = "$extension"


def write(asset, path, **options) -> None:
    """Write ``asset.skeleton`` (its rest pose, in metres, +Y up) to ``path``; motions are not written."""
    sk = asset.skeleton
    joints = [{"name": name, "parent": None if parent < 0 else sk.names[parent],
               "offset": [round(float(v), 6) for v in offset], "rotation": [round(float(v), 8) for v in rotation]}
              for name, parent, offset, rotation in zip(sk.names, sk.parents, sk.rest_translations, sk.rest_rotations)]
    Path(path).write_text(json.dumps({"joints": joints}, indent=1) + "\\n", encoding="utf-8")


@hookimpl
def infuse_writers():
    return [Writer("$name", (EXTENSION,), write, "JSON skeletons ($extension)")]
''')

WRITER_TEST = Template('''"""The $name writer: installed, writes every joint of the canonical skeleton."""
import json

import numpy as np

import infuse
from infuse.canonical import canonical_skeleton
from infuse.registry import writers


def test_installed():
    assert "$extension" in writers()["$name"].extensions


def test_writes_the_canonical_skeleton(tmp_path):
    skeleton = canonical_skeleton()
    path = tmp_path / "canonical$extension"
    infuse.save(infuse.Asset(None, "canonical", skeleton), path)
    joints = json.loads(path.read_text())["joints"]
    assert [j["name"] for j in joints] == list(skeleton.names)
    assert [j["parent"] for j in joints[1:]] == [skeleton.names[p] for p in skeleton.parents[1:]]
    assert np.allclose([j["offset"] for j in joints], skeleton.rest_translations, atol=1e-6)
''')

MAPPER = Template('''"""The $name mapper: joints named ``<PREFIX><canonical name>`` (a studio's own convention) are
mapped by their names; every other canonical name is left to the default mapper.

Replace :func:`map_names` with your convention. A mapper returns a :class:`infuse.mapping.Mapping`
(canonical name -> joint name or None, with confidences and reasons) and refuses a skeleton that is
not a humanoid with :class:`infuse.NotHumanoidError`.
"""
from infuse import hookimpl
from infuse.canonical import ALL_NAMES
from infuse.errors import NotHumanoidError
from infuse.mapping import DEFAULT_MAPPER, Mapping, get_mapper
from infuse.plugin_types import Mapper

PREFIX = "c_"


def map_names(skeleton, fixed=None, **options) -> Mapping:
    """Canonical names from the prefix; ``fixed`` entries (set by hand) win; the rest by the default mapper."""
    found = {name[len(PREFIX):]: name for name in skeleton.names
             if name.startswith(PREFIX) and name[len(PREFIX):] in ALL_NAMES}
    found.update(fixed or {})
    try:
        rest = get_mapper(DEFAULT_MAPPER).map(skeleton, fixed=found, **options)
    except NotHumanoidError:
        if not found:
            raise
        rest = Mapping.build(skeleton, {})
    joints = {**rest.joints, **found}
    confidence = {**rest.confidence, **{k: 1.0 for k in found}}
    reasons = {**rest.reasons, **{k: f"named {v!r}" for k, v in found.items() if v is not None}}
    return Mapping.build(skeleton, joints, confidence, reasons, mapper="$name")


@hookimpl
def infuse_mappers():
    return [Mapper("$name", map_names, f"joints named {PREFIX}<canonical name>, the rest by the default mapper")]
''')

MAPPER_TEST = Template('''"""The $name mapper: installed, maps a skeleton named by the convention."""
from infuse.canonical import canonical_skeleton
from infuse.mapping import map_skeleton
from infuse.registry import mappers
from infuse.skeleton import Skeleton

from $package.plugin import PREFIX


def test_installed():
    assert "$name" in mappers()


def test_maps_every_joint_named_by_the_convention():
    sk = canonical_skeleton()
    renamed = Skeleton(tuple(PREFIX + n for n in sk.names), sk.parents, sk.rest_translations, sk.rest_rotations)
    mapping = map_skeleton(renamed, mapper="$name")
    assert mapping.mapper == "$name"
    assert all(mapping.joints[n] == PREFIX + n and mapping.confidence[n] == 1.0 for n in sk.names)
''')

RETARGETER = Template('''"""The $name retargeter: each mapped joint turns away from its rest as the source's does, and the
root travels as the source's, scaled by the ratio of the pelvis heights.

A starting point that suits skeletons whose rest poses match (both in a T-pose, with the same joint
axes); replace :func:`retarget` with your method. Arrays: local rotations (F, J, 4), scalar-last
quaternions; root translations (F, 3) in metres.
"""
import numpy as np

import infuse
from infuse import hookimpl
from infuse import quaternions as quat
from infuse.errors import UnusableInputError
from infuse.plugin_types import Retargeter


def retarget(motion, source_mapping, target_skeleton, target_mapping, **options) -> infuse.Motion:
    """``motion`` on ``target_skeleton``; joints the mappings do not share keep their rest rotation."""
    source = motion.skeleton
    pairs = [(source.index[s], target_skeleton.index[t]) for c, t in target_mapping.joints.items()
             if t is not None and (s := source_mapping.joints.get(c)) is not None]
    if not pairs or source_mapping.joints.get("base") is None or target_mapping.joints.get("base") is None:
        raise UnusableInputError(None, "the two mappings share no pelvis ('base') and joints to carry the motion")
    s, t = np.array(pairs).T
    frames = motion.num_frames
    rotations = np.broadcast_to(target_skeleton.rest_rotations, (frames, len(target_skeleton.names), 4)).copy()
    away_from_rest = quat.multiply(quat.conjugate(source.rest_rotations[s]), motion.local_rotations[:, s])
    rotations[:, t] = quat.multiply(target_skeleton.rest_rotations[t], away_from_rest)
    height = (target_skeleton.rest_global_positions[target_skeleton.index[target_mapping.joints["base"]], 1]
              / source.rest_global_positions[source.index[source_mapping.joints["base"]], 1])
    root = target_skeleton.rest_translations[0] + height * (motion.root_translations - source.rest_translations[0])
    return infuse.Motion(target_skeleton, motion.fps, rotations, root, name=motion.name)


@hookimpl
def infuse_retargeters():
    return [Retargeter("$name", retarget, "rest-relative joint rotations, root travel scaled by pelvis height")]
''')

RETARGETER_TEST = Template('''"""The $name retargeter: installed; onto a half-size copy of a skeleton every joint lands at half the height."""
import numpy as np

import infuse
from infuse import quaternions as quat
from infuse.canonical import canonical_skeleton
from infuse.kinematics import motion_fk
from infuse.mapping import map_skeleton
from infuse.registry import retargeters
from infuse.skeleton import Skeleton


def _swaying(sk, frames=30):
    """The skeleton's spine joints bending forward and back, the root walking forward (1 m/s at 30 fps)."""
    t = np.arange(frames) / 30.0
    rotations = quat.identity((frames, len(sk.names)))
    bend = quat.from_axis_angle(np.array([1.0, 0.0, 0.0]), 0.3 * np.sin(2 * np.pi * t))
    for name in ("spine1", "spine2", "spine3"):
        rotations[:, sk.index[name]] = quat.multiply(sk.rest_rotations[sk.index[name]], bend)
    root = sk.rest_translations[0] + np.outer(t, [0.0, 0.0, 1.0])
    return infuse.Motion(sk, 30.0, rotations, root, name="sway")


def test_installed():
    assert "$name" in retargeters()


def test_a_half_size_copy_moves_at_half_the_size():
    big = canonical_skeleton()
    small = Skeleton(tuple("s_" + n for n in big.names), big.parents, 0.5 * big.rest_translations, big.rest_rotations)
    motion = _swaying(big)
    out = retargeters()["$name"].retarget(motion, map_skeleton(big), small, map_skeleton(small))
    assert out.skeleton is small and out.num_frames == motion.num_frames
    assert np.allclose(motion_fk(out)[1], 0.5 * motion_fk(motion)[1], atol=1e-9)
''')

CONTROLLER = Template('''"""The $name controller: the head tips forward by ``angle_deg`` and back, a half cosine up and down
over ``duration_s`` seconds, on top of whatever the character is doing.

Replace :meth:`evaluate_one` with your behaviour. A controller binds once per character through
canonical joint names (``rig.joint``) and computes whole blocks of frames with numpy; angles in the
joints' aligned frames (:mod:`infuse.runtime.swing`) mean the same on every skeleton. What ``bind``
works out per character is a frozen dataclass, its fields named and their shapes stated.
"""
from dataclasses import dataclass

import numpy as np

from infuse import hookimpl
from infuse.errors import MissingJointsError, UsageError
from infuse.plugin_types import ControllerFactory
from infuse.runtime import Controller, Layer, Mode
from infuse.runtime.swing import local_offsets, swing


def tip_curve(t, duration_s: float) -> np.ndarray:
    """(F,) tip in [0, 1] at ``t`` seconds from the start: 0 -> 1 -> 0 over ``duration_s``, 0 outside."""
    x = np.asarray(t, dtype=np.float64) / duration_s
    return np.where((x >= 0.0) & (x <= 1.0), 0.5 - 0.5 * np.cos(2.0 * np.pi * np.clip(x, 0.0, 1.0)), 0.0)


@dataclass(frozen=True, eq=False)
class ${ident}Binding:
    """The $name controller bound to one character: the head ``joints`` (1,) and their ``aligned`` frames (1, 4)."""

    joints: np.ndarray
    aligned: np.ndarray


class $ident(Controller):
    """Tip the head forward by ``angle_deg`` (degrees, default 20) and back over ``duration_s`` (default 1 s)."""

    kind = "$name"
    layer = Layer.HEAD
    mode = Mode.ADDITIVE
    blend_in_s = 0.0  # the curve itself starts and ends at rest
    blend_out_s = 0.0

    def __init__(self, angle_deg: float = 20.0, duration_s: float = 1.0):
        if not (np.isfinite(angle_deg) and abs(angle_deg) <= 90.0):
            raise UsageError(f"$name angle must lie in [-90, 90] degrees, got {angle_deg}")
        if not (np.isfinite(duration_s) and duration_s > 0.05):
            raise UsageError(f"$name duration must be over 0.05 s, got {duration_s}")
        self.angle_deg, self.duration_s = float(angle_deg), float(duration_s)

    def bind(self, rig, report) -> ${ident}Binding:
        """Per character: the head joint and its aligned frame."""
        head = rig.joint("skullbase")
        if head is None:
            raise MissingJointsError(rig.name, "no head ('skullbase') is mapped")
        return ${ident}Binding(joints=np.array([head]), aligned=rig.aligned[[head]])

    def evaluate_one(self, job, block) -> None:
        """Vectorized over the block's frames: one pitch per frame."""
        b: ${ident}Binding = job.binding
        pitch = -np.radians(self.angle_deg) * tip_curve(job.local_times, self.duration_s)  # (F,) negative: down
        offsets = local_offsets(b.aligned, swing(0.0, pitch[:, None], 0.0))
        job.pose.set_rotations(b.joints, offsets, job.weight, job.mode)


@hookimpl
def infuse_controllers():
    return [ControllerFactory("$name", $ident, "tip the head forward and back")]
''')

CONTROLLER_TEST = Template('''"""The $name controller: installed, and the head turns by the angle asked at the middle of the movement."""
import numpy as np

import infuse
from infuse import quaternions as quat
from infuse.canonical import canonical_skeleton
from infuse.runtime import Runtime, controller, controller_components

FPS = 30


def test_installed():
    assert "$name" in controller_components()


def test_the_head_turns_by_the_angle_and_back():
    rt = Runtime(fps=FPS)
    name = rt.add_character(infuse.Character("c", infuse.Asset(None, "canonical", canonical_skeleton())))
    rt.activate(name, controller("$name", angle_deg=20.0, duration_s=1.0), 0.5)
    rt.run(2.0)
    motion = rt.motion(name)
    head = motion.skeleton.index["skullbase"]
    angle = np.degrees(quat.angle_between(motion.local_rotations[:, head], motion.skeleton.rest_rotations[head]))
    assert angle[int(1.0 * FPS)] == np.clip(angle, 0, None).max()
    assert abs(angle[int(1.0 * FPS)] - 20.0) < 0.5
    assert angle[: int(0.5 * FPS)].max() < 1e-6 and angle[int(1.6 * FPS):].max() < 1e-6
''')

BML = Template('''"""The $name BML behaviour: ``<x:$name>`` in the namespace ``urn:infuse:$name`` nods the head twice,
realized by the installed ``head`` controller.

Replace :func:`plan` with your behaviour: from the parsed element it returns the timing model (the
sync points and their natural times, seconds from the start) and the controller that realizes it
with its parameters; a value it cannot use raises :class:`infuse.bml.BehaviourError` (the scheduler
warns and runs the rest of the block).
"""
import math

from infuse import hookimpl
from infuse.bml import BehaviourError, BehaviourPlan, TimingModel
from infuse.plugin_types import BMLBehaviour

NAMESPACE = "urn:infuse:$name"
ELEMENT = "{" + NAMESPACE + "}$name"
ATTRIBUTES = frozenset({"amount"})
#: Two nods at 1.5 Hz: sync point -> seconds from the start.
TIMING = {"start": 0.0, "ready": 0.13, "stroke": 0.5, "relax": 1.17, "end": 1.33}
NOD_DEG = 30.0


def plan(behaviour, context) -> BehaviourPlan:
    """The timing and the head controller's parameters for ``<x:$name amount="0..1"/>``."""
    text = behaviour.attributes.get("amount", "0.5")
    try:
        amount = float(text)
    except ValueError:
        raise BehaviourError(f"amount={text!r} is not a number") from None
    if not (math.isfinite(amount) and 0.0 <= amount <= 1.0):
        raise BehaviourError(f"amount={text!r} must lie in [0, 1]")
    parameters = {"lexeme": "NOD", "amount": amount, "repeats": 2.0, "velocity_hz": 1.5,
                  "peak_angle_deg": amount * NOD_DEG, "direction": None}
    return BehaviourPlan(TimingModel.from_points(TIMING), "head", parameters)


@hookimpl
def infuse_bml_behaviours():
    return [BMLBehaviour("$name", plan, "nod twice", (ELEMENT,), ATTRIBUTES)]
''')

BML_TEST = Template('''"""The $name BML behaviour: installed, scheduled, refused when wrong, and realized on a character."""
import numpy as np

import infuse
from infuse import quaternions as quat
from infuse.bml import Scheduler
from infuse.canonical import canonical_skeleton
from infuse.registry import table
from infuse.runtime import Runtime

from $package.plugin import ELEMENT, NAMESPACE, TIMING

FPS = 30


def _schedule(attributes: str):
    scheduler = Scheduler()
    warnings = []
    scheduler.feedback.subscribe(warnings.append, kinds=["warningFeedback"])
    (block,) = scheduler.submit(f'<bml xmlns="http://www.bml-initiative.org/bml/bml-1.0" xmlns:x="{NAMESPACE}" id="b1" '
                                f'characterId="bob"><x:$name id="a1" {attributes}/></bml>', at=0.0)
    return block.activations, warnings


def test_installed():
    assert ELEMENT in table("bml-behaviour")["$name"].elements


def test_scheduled_at_its_natural_timing():
    (activation,), warnings = _schedule('amount="0.8" start="1"')
    assert warnings == [] and activation.controller == "head" and activation.parameters["amount"] == 0.8
    assert all(abs(activation.sync_times[k] - (1.0 + v)) < 1e-9 for k, v in TIMING.items())


def test_a_bad_amount_is_a_warning():
    activations, warnings = _schedule('amount="lots"')
    assert len(activations) == 0 and len(warnings) == 1


def test_realized_the_head_moves_between_start_and_end():
    (activation,), _ = _schedule('amount="0.8"')
    rt = Runtime(fps=FPS)
    name = rt.add_character(infuse.Character("bob", infuse.Asset(None, "canonical", canonical_skeleton())))
    rt.realize(activation, name)
    rt.run(2.0)
    motion = rt.motion(name)
    head = motion.skeleton.index["skullbase"]
    angle = np.degrees(quat.angle_between(motion.local_rotations[:, head], motion.skeleton.rest_rotations[head]))
    assert angle[: int(TIMING["end"] * FPS)].max() > 5.0 and angle[int((TIMING["end"] + 0.2) * FPS):].max() < 1e-3
''')

GENERATOR = Template('''"""The $name BML generator: ``infuse:$name="true"`` on a ``<bml>`` block (namespace
``urn:infuse:bml``) adds a nod at the end of each of its speeches, before the block is scheduled.

Replace :func:`generate` with your generator: it gets the parsed block and an
:class:`infuse.bml.GeneratorContext` (the character, the scene's characters and objects, a seed, what
was said before, the ``infuse:`` settings it declares) and returns an :class:`infuse.bml.Generation`:
the block with what it added, blocks for other characters, and the added BML as text (reported as
``generatedBml`` feedback). :class:`infuse.bml.GenerationError` leaves the block as it was, with a warning.
"""
import math
from dataclasses import replace
from xml.sax.saxutils import quoteattr

from infuse import hookimpl
from infuse.bml import Generation, GenerationError, parse_bml
from infuse.plugin_types import BMLGenerator

BML_NS = "http://www.bml-initiative.org/bml/bml-1.0"
#: The ``infuse:`` block setting it reads: how deep the nods are (0 to 1).
AMOUNT = "$name-amount"


def generate(block, context) -> Generation:
    """``block`` with a nod whose stroke is on the end of each speech."""
    text = context.settings.get(AMOUNT, "0.4")
    try:
        amount = float(text)
    except ValueError:
        amount = math.nan
    if not 0.0 <= amount <= 1.0:
        raise GenerationError(f"infuse:{AMOUNT}={text!r} is not a number from 0 to 1")
    taken = {b.id for b in block.behaviours}
    nods = []
    for speech in (b for b in block.behaviours if b.element == "speech"):
        behaviour_id = next(f"nod{k}" for k in range(1, len(taken) + 2) if f"nod{k}" not in taken)
        taken.add(behaviour_id)
        nods.append(f'<head id={quoteattr(behaviour_id)} lexeme="NOD" amount="{amount:g}" '
                    f'stroke={quoteattr(speech.id + ":end")}/>')
    if not nods:
        return Generation(block)
    document = f'<bml xmlns="{BML_NS}" id={quoteattr(block.id)}>{"".join(nods)}</bml>'
    (added,) = parse_bml(document).blocks
    return Generation(replace(block, behaviours=block.behaviours + added.behaviours), bml=document)


@hookimpl
def infuse_bml_generators():
    return [BMLGenerator("$name", generate, "a nod at the end of each speech", frozenset({AMOUNT}))]
''')

GENERATOR_TEST = Template('''"""The $name BML generator: installed, off unless a block turns it on, a nod on each speech's end, a bad
setting warned."""
from infuse.bml import Scheduler
from infuse.registry import table

from $package.plugin import AMOUNT


def _schedule(flags: str):
    scheduler = Scheduler()
    (record,) = scheduler.submit('<bml xmlns="http://www.bml-initiative.org/bml/bml-1.0" xmlns:infuse="urn:infuse:bml" '
                                 f'id="b1" characterId="bob" {flags}><speech id="s1"><text>Hello there.</text></speech></bml>',
                                 at=0.0)
    return record, scheduler.feedback.log


def test_installed():
    assert "$name" in table("bml-generator")


def test_a_nod_on_the_end_of_the_speech():
    record, log = _schedule(f'infuse:$name="true" infuse:{AMOUNT}="0.6"')
    (nod,) = [a for a in record.activations if a.controller == "head"]
    assert abs(nod.time("stroke") - record.activation("s1").end) < 1e-9 and nod.parameters["amount"] == 0.6
    assert [e.generator for e in log if e.kind == "generatedBml"] == ["$name"]


def test_off_by_default_and_a_bad_amount_warns():
    record, _ = _schedule("")
    assert [a.controller for a in record.activations] == ["speech"]
    record, log = _schedule(f'infuse:$name="true" infuse:{AMOUNT}="lots"')
    assert [a.controller for a in record.activations] == ["speech"]
    assert any("'lots' is not a number" in e.description for e in log if e.kind == "warningFeedback")
''')

COMMAND = Template('''"""The $name command: ``infuse $name FILE`` prints the joints of a file's skeleton and its clips.

Replace :func:`run` with your command. ``add_arguments(parser)`` declares an ``argparse`` sub-command
and ``run(args)`` returns the exit code; raise :class:`infuse.InputError` or :class:`infuse.UsageError`
(exit code 2) or :class:`infuse.UnusableInputError` (exit code 3) and the command line prints one line.
"""
import infuse
from infuse import hookimpl
from infuse.plugin_types import Command


def add_arguments(parser) -> None:
    parser.add_argument("file", help="a character or motion file infuse reads")


def run(args) -> int:
    asset = infuse.load(args.file)
    print(f"{args.file}: {len(asset.skeleton.names)} joints, {len(asset.motions)} clips")
    for name, motion in asset.motions.items():
        print(f"  {name}: {motion.num_frames} frames at {motion.fps:g} fps ({(motion.num_frames - 1) / motion.fps:.2f} s)")
    return 0


@hookimpl
def infuse_commands():
    return [Command("$name", "print the joints and clips of a file", add_arguments, run)]
''')

COMMAND_TEST = Template('''"""The $name command: installed, prints a file's clips, and exits 2 with one line on a missing file."""
import subprocess
import sys
from pathlib import Path

import numpy as np

import infuse
from infuse import quaternions as quat
from infuse.canonical import canonical_skeleton
from infuse.registry import commands

INFUSE = Path(sys.executable).with_name("infuse")


def infuse_command(*args):
    return subprocess.run([str(INFUSE), *map(str, args)], capture_output=True, text=True, timeout=60)


def test_installed():
    assert "$name" in commands()


def test_prints_the_clips(tmp_path):
    sk = canonical_skeleton()
    motion = infuse.Motion(sk, 30.0, quat.identity((31, len(sk.names))), np.tile(sk.rest_translations[0], (31, 1)), name="still")
    path = tmp_path / "still.bvh"
    infuse.save(infuse.Asset(None, "bvh", sk, {"still": motion}), path)
    proc = infuse_command("$name", path)
    assert proc.returncode == 0, proc.stderr
    assert f"{len(sk.names)} joints, 1 clips" in proc.stdout and "31 frames at 30 fps (1.00 s)" in proc.stdout


def test_a_missing_file_exits_2(tmp_path):
    proc = infuse_command("$name", tmp_path / "nothing.bvh")
    assert proc.returncode == 2 and "nothing.bvh" in proc.stderr and "Traceback" not in proc.stderr
''')

KINDS: dict[str, KindTemplate] = {
    "reader": KindTemplate("infuse.readers", "reads $extension files (a JSON skeleton)", {"plugin.py": READER}, READER_TEST,
                           "infuse info file$extension"),
    "writer": KindTemplate("infuse.writers", "writes $extension files (a JSON skeleton)", {"plugin.py": WRITER}, WRITER_TEST,
                           "infuse convert character.glb out$extension"),
    "mapper": KindTemplate("infuse.mappers", "maps joints named c_<canonical name>, the rest by the default mapper",
                           {"plugin.py": MAPPER}, MAPPER_TEST, "infuse map character.glb --mapper $name"),
    "retargeter": KindTemplate("infuse.retargeters", "rest-relative rotations, root travel scaled by pelvis height",
                               {"plugin.py": RETARGETER}, RETARGETER_TEST,
                               "python -c \"import infuse.registry as r; print(r.retargeters()['$name'])\""),
    "controller": KindTemplate("infuse.controllers", "tips the head forward and back", {"plugin.py": CONTROLLER},
                               CONTROLLER_TEST, "python -c \"from infuse.runtime import controller; print(controller('$name'))\""),
    "bml-behaviour": KindTemplate("infuse.bml_behaviours", "<x:$name> (namespace urn:infuse:$name) nods twice",
                                  {"plugin.py": BML}, BML_TEST, "infuse run scene.toml -o out/   # a scene whose BML uses <x:$name>"),
    "bml-generator": KindTemplate("infuse.bml_generators", "infuse:$name=\"true\" on a <bml> block adds a nod at the end "
                                   "of each speech", {"plugin.py": GENERATOR}, GENERATOR_TEST,
                                   "infuse run scene.toml -o out/   # a scene whose blocks say infuse:$name=\"true\""),
    "command": KindTemplate("infuse.commands", "infuse $name FILE prints a file's joints and clips", {"plugin.py": COMMAND},
                            COMMAND_TEST, "infuse $name character.glb"),
}
