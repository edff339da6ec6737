"""The ``clip`` base controller: plays a :class:`~infuse.Motion` on a character, looping or once.

The motion must be on the character's skeleton, or share joint names with it (joints it does not
name, or does not animate (``Motion.animated_joints``), keep the pose below), or come with its own
mapping for an installed retargeter to transfer it.
Looping carries the root forward: each cycle adds the clip's horizontal root displacement, so a walk
cycle walks on. Rotations between frames are interpolated (normalized lerp on the shorter arc),
morph weights linearly; the clip's morph weights drive the character's morph targets of those names.
"""
from __future__ import annotations

import hashlib
import weakref
from collections import Counter
from dataclasses import dataclass, fields

import numpy as np

from .. import quaternions as quat
from ..errors import UsageError
from ..motion import Motion
from .controller import Block, Controller, Job, Jobs
from .layers import Layer, Mode, clamp


def sample_motion(motion: Motion, times: np.ndarray, loop: bool, joints=None):
    """Local rotations (T, J, 4), root translations (T, 3), joint translations (T, J, 3) or None, and
    completed cycles (T,) of ``motion`` at ``times`` seconds from its start; held at the ends, or
    wrapped over its duration when ``loop``. ``joints`` (K,) indices: only those joints are sampled
    (J = K in the results), the same values as the full sampling's columns."""
    return sample_positions(motion, *clip_positions(motion, times, loop), joints)


def sample_positions(motion: Motion, position: np.ndarray, cycles: np.ndarray, joints=None):
    """:func:`sample_motion` at fractional frames ``position`` (T,) in [0, F - 1] with ``cycles`` (T,)
    completed cycles (what :func:`clip_positions` gives)."""
    f = motion.num_frames
    jt = motion.joint_translations
    columns = slice(None) if joints is None else np.asarray(joints, dtype=np.int64)

    def held(idx):  # the clip's own frames, no interpolation
        frames = idx if joints is None else idx[:, None]
        return (motion.local_rotations[frames, columns], motion.root_translations[idx],
                None if jt is None else jt[frames, columns], cycles)

    if f == 1:
        return held(np.zeros(len(position), dtype=np.int64))
    nearest = np.rint(position)
    on = np.abs(position - nearest) < 1e-6
    if on.all():  # on the clip's own frames: no interpolation
        return held(nearest.astype(np.int64))
    # A time on one of the clip's frames takes that frame, whatever the other times are (each time is
    # sampled as it would be alone, to rounding: a block of frames samples as its frames one by one).
    position = np.where(on, nearest, position)
    i0 = np.minimum(np.floor(position).astype(np.int64), f - 2)
    frac = (position - i0)[:, None]
    rotations, steps = _interpolation_table(motion)
    frames = i0 if joints is None else i0[:, None]
    rot = steps[frames, columns]  # a gathered copy: the interpolation runs in place on it
    rot *= frac[:, :, None]
    rot += rotations[frames, columns]
    rot *= 1.0 / np.sqrt(np.einsum("...i,...i->...", rot, rot))[..., None]
    root = motion.root_translations[i0] + frac * (motion.root_translations[i0 + 1] - motion.root_translations[i0])
    if jt is not None:
        jt = jt[frames, columns] + frac[:, :, None] * (jt[frames + 1, columns] - jt[frames, columns])
    return rot, root, jt, cycles


def clip_positions(motion: Motion, times, loop: bool) -> tuple[np.ndarray, np.ndarray]:
    """Where ``times`` (any shape, seconds from the start) fall in ``motion``: fractional frames in
    [0, F - 1] and completed cycles (0 unless ``loop``), as :func:`sample_motion` samples them."""
    position = np.asarray(times, dtype=np.float64) * motion.fps
    cycles = np.zeros(position.shape)
    if motion.num_frames == 1:
        return np.zeros(position.shape), cycles
    span = motion.num_frames - 1  # the last frame closes the cycle: it is drawn like the first
    if loop:
        cycles = np.floor(position / span + 1e-9)
        position = position - cycles * span
    return clamp(position, 0.0, span), cycles


def on_frames(position: np.ndarray) -> np.ndarray:
    """(n,) whether every fractional frame of each row of ``position`` (n, T) (:func:`clip_positions`)
    is one of the motion's own frames, where :func:`sample_motion` takes them as they are, without
    interpolating."""
    return np.all(np.abs(position - np.rint(position)) < 1e-6, axis=-1)


def sample_morph_weights(motion: Motion, times: np.ndarray, loop: bool) -> np.ndarray:
    """(T, M) morph weights of ``motion`` at ``times`` seconds from its start, linear between frames;
    held at the ends, or wrapped over its duration when ``loop`` (as :func:`sample_motion`)."""
    f = motion.num_frames
    weights = motion.morph_weights
    position = np.asarray(times, dtype=np.float64) * motion.fps
    if f == 1:
        return np.repeat(weights, len(position), axis=0)
    span = f - 1
    if loop:
        position = position - np.floor(position / span + 1e-9) * span
    position = clamp(position, 0.0, span)
    i0 = np.minimum(np.floor(position).astype(np.int64), f - 2)
    frac = (position - i0)[:, None]
    return weights[i0] + frac * (weights[i0 + 1] - weights[i0])


class LoopTable:
    """Several looping motions of one skeleton stacked into one table, so that a blend of them is
    sampled in one gather, each joint at one of a few times (a leg at its own foot's time).

    Each motion is sampled as :func:`sample_motion` with ``loop=True`` samples it (interpolated on
    its sign-continuous rotations, held on its own frames where a time lies on one), the same values
    to rounding. The tables and the samples are component-major ((4, ...) quaternions,
    (3, ...) translations): weighting a sample frame by frame then runs over contiguous rows, where
    numpy broadcasts a weight along a last axis of 3 or 4 several times slower. Each table holds a
    frame's values and its step to the next side by side ((2C, ...): values, then steps), so one gather
    fetches both. Built once per set of motions (a blend space's binding).
    """

    def __init__(self, motions):
        motions = list(motions)
        counts = np.array([m.num_frames for m in motions], dtype=np.int64)
        self.offsets = np.concatenate(([0], np.cumsum(counts)[:-1]))  # (M,) each motion's first row
        self.last = np.maximum(counts - 2, 0)  # (M,) last frame an interpolation starts from
        self.spans = np.maximum(counts - 1, 1).astype(np.float64)  # (M,) frames in a cycle
        self.fps = np.array([m.fps for m in motions], dtype=np.float64)
        self.durations = np.array([max(m.duration, 1e-9) for m in motions])
        self.joints = motions[0].skeleton.num_joints
        self._joint_cells = np.arange(self.joints)  # (J,) each joint's cell in a frame's row
        # (3, M) each motion's duration, frame rate and cycle span; (2, M) its first row and last start.
        self._timing = np.stack((self.durations, self.fps, self.spans))
        self._rows = np.stack((self.offsets, self.last))

        ends = self.offsets + counts - 1  # each motion's last row: no step to the next motion's first

        def table(values):
            """Values (R, [J,] C) and each frame's step to the next (zero on a motion's last frame), as
            one component-major (2C, R * J) or (2C, R) table: the values' C rows, then the steps'."""
            steps = np.zeros_like(values)
            steps[:-1] = values[1:] - values[:-1]
            steps[ends] = 0.0
            return np.ascontiguousarray(np.concatenate((values, steps), axis=-1).reshape(-1, 2 * values.shape[-1]).T)

        self.rotations = table(np.concatenate([continuous_rotations(m) for m in motions]))
        self.roots = table(np.concatenate([m.root_translations for m in motions]))
        self.translations = None
        if any(m.joint_translations is not None for m in motions):
            self.translations = table(np.concatenate(
                [m.local_translations() if m.joint_translations is None else m.joint_translations for m in motions]))

    def sample(self, which: np.ndarray, times: np.ndarray, sets: np.ndarray):
        """Local rotations (4, U, F, J), root translations (3, U, F) and joint translations (3, U, F, J)
        or None of motions ``which`` (U,) at ``times`` (U, S, F) seconds (S sets of times, wrapped over
        each motion's duration), joint j at its time set ``sets[j]`` (the root at joint 0's)."""
        which = np.asarray(which, dtype=np.int64)
        duration, fps, span = self._timing.take(which, 1)[..., None, None]  # (U, 1, 1) each
        offset, last = self._rows.take(which, 1)[..., None, None]
        position = times % duration * fps
        position = position - np.floor(position / span + 1e-9) * span
        position = np.minimum(np.maximum(position, 0.0), span)  # a clip, cheaper than np.clip on few values
        nearest = np.rint(position)
        # A time on one of the motion's own frames takes that frame (each time as it would be alone).
        position = np.where(np.abs(position - nearest) < 1e-6, nearest, position)
        start = np.minimum(np.floor(position).astype(np.int64), last)
        frac = position - start
        row = offset + start  # (U, S, F)
        # Gathers by np.take on flat tables: numpy's fancy indexing costs several times more here.
        cells = np.swapaxes(row.take(sets, 1), 1, 2) * self.joints + self._joint_cells  # (U, F, J)
        joint_frac = np.swapaxes(frac.take(sets, 1), 1, 2)
        both = np.take(self.rotations, cells, axis=1)  # values (4, ...) then steps (4, ...)
        rot = both[4:] * joint_frac
        rot += both[:4]
        rot *= 1.0 / np.sqrt(np.square(rot).sum(axis=0))
        root_rows, root_frac = row[:, sets[0]], frac[:, sets[0]]
        both = np.take(self.roots, root_rows, axis=1)
        root = both[:3] + root_frac * both[3:]
        jt = None
        if self.translations is not None:
            both = np.take(self.translations, cells, axis=1)
            jt = both[:3] + joint_frac * both[3:]
        return rot, root, jt


#: Each clip's interpolation table, for as long as the clip lives: a Motion is immutable and hashed by
#: identity, so the table is the clip's own and goes with it.
_TABLES: weakref.WeakKeyDictionary[Motion, tuple[np.ndarray, np.ndarray]] = weakref.WeakKeyDictionary()


#: Each clip's :func:`content_key`, for as long as the clip lives.
_CONTENT: weakref.WeakKeyDictionary[Motion, bytes] = weakref.WeakKeyDictionary()


def content_key(motion: Motion) -> bytes:
    """A digest of what :func:`sample_motion` reads of ``motion`` (its skeleton, rate and channels), so that
    copies of one clip (characters infused from one cache each hold their own) are sampled as one."""
    key = _CONTENT.get(motion)
    if key is None:
        digest = hashlib.blake2b(digest_size=16)
        digest.update(f"{id(motion.skeleton)}:{motion.fps!r}:{motion.local_rotations.shape}".encode())
        for channel in (motion.local_rotations, motion.root_translations, motion.joint_translations):
            digest.update(b"-" if channel is None else np.ascontiguousarray(channel).tobytes())
        key = _CONTENT[motion] = digest.digest()
    return key


def continuous_rotations(motion: Motion) -> np.ndarray:
    """The clip's local rotations (F, J, 4) made sign-continuous over frames (kept with the clip)."""
    return _interpolation_table(motion)[0]


def _interpolation_table(motion: Motion) -> tuple[np.ndarray, np.ndarray]:
    """The clip's rotations (F, J, 4) made sign-continuous over frames, and each frame's step to the
    next (F - 1, J, 4); worked out once per clip (a crowd plays the same few clips)."""
    table = _TABLES.get(motion)
    if table is None:
        rotations = quat.make_continuous(motion.local_rotations, axis=0)
        table = _TABLES[motion] = (rotations, np.diff(rotations, axis=0))
    return table


@dataclass(frozen=True, eq=False)
class ClipBinding:
    """A clip bound to one character.

    - ``motion``: the clip, on a skeleton that shares joint names with the character's (retargeted
      onto it when it did not);
    - ``columns`` (K,): the clip's joints that drive the character, ``joints`` (K,): the character's
      joints they drive; ``identity_columns``: ``columns`` is 0..K-1 (the sample needs no gather);
    - ``step`` (3,) metres: how far one cycle carries the character along the ground;
    - ``mover``: the clip joint that travels (0: the root; else the first joint whose position channels
      move); ``drives_root``: the clip's root is the character's and animated;
    - ``moved_columns`` (T,), ``moved_joints`` (T,): joints whose position channels leave the
      character's rest offsets, in the clip and on the character;
    - ``morph_sources`` (M,): the clip's morph weight columns the character has, ``morph_columns``
      (M,): the character's morph targets they drive.
    """

    motion: Motion
    columns: np.ndarray
    joints: np.ndarray
    identity_columns: bool
    step: np.ndarray
    mover: int
    drives_root: bool
    moved_columns: np.ndarray
    moved_joints: np.ndarray
    morph_sources: np.ndarray
    morph_columns: np.ndarray


class Clip(Controller):
    """Play ``motion`` from the activity's start.

    - ``loop``: wrap around (the last frame meets the first); otherwise hold the last frame.
    - ``speed``: playback rate (1 = as recorded); ``offset_s``: clip time at the activity's start.
    - ``root_motion``: move the root as the clip does (else it stays at the clip's first root position).
    - ``source_mapping``: the motion's own mapping, to retarget it when it is on another skeleton.
    - ``placement``: ``(turn, shift)``, a unit quaternion (4,) (x, y, z, w) about +Y and metres (3,): the
      clip played as a copy of it whose root joint is turned by ``turn`` about the origin and moved by
      ``shift`` would be (root rotation ``turn * q``, root position ``turn(p) + shift``), with no copy
      made: characters placing one clip each their own way share its tables and play it together.
    """

    kind = "clip"
    layer = Layer.BASE
    own_characters_only = True  # clips of every priority on characters apart played in one call
    call_ms = 0.2
    # A base clip usually starts from nothing (the rest pose): no fade unless a transition asks for one.
    blend_in_s = 0.0
    blend_out_s = 0.0

    def __init__(self, motion: Motion, loop: bool = True, speed: float = 1.0, offset_s: float = 0.0,
                 root_motion: bool = True, source_mapping=None, placement=None):
        if not isinstance(motion, Motion) or motion.num_frames == 0:
            raise UsageError("a clip needs a Motion with at least one frame")
        if not (np.isfinite(speed) and speed > 0):
            raise UsageError(f"clip speed must be positive, got {speed}")
        self.motion = motion
        self.loop = bool(loop)
        self.speed = float(speed)
        self.offset_s = float(offset_s)
        self.root_motion = bool(root_motion)
        self.source_mapping = source_mapping
        self.turn: np.ndarray | None = None
        self.shift: np.ndarray | None = None
        if placement is not None:
            turn, shift = (np.array(a, dtype=np.float64) for a in placement)
            if turn.shape != (4,) or shift.shape != (3,) or not (np.isfinite(turn).all() and np.isfinite(shift).all()) \
                    or abs(float(turn @ turn) - 1.0) > 1e-6 or abs(turn[0]) > 1e-9 or abs(turn[2]) > 1e-9:
                raise UsageError("a clip's placement is (turn, shift): a unit quaternion about +Y (x, y, z, w) and "
                                 "a shift (x, y, z) in metres")
            self.turn, self.shift = turn, shift
        if not self.loop:
            self.duration_s = max(motion.duration - self.offset_s, 0.0) / self.speed

    def describe(self) -> str:
        return f"clip {self.motion.name!r}"

    def bind(self, rig, report) -> ClipBinding:
        bound = rig.state_of(_Bound)
        kept = bound.get(self.motion)
        if kept is not None and kept[0] is type(self):  # this clip bound to this character before: the same
            _, values, reported = kept  # binding, the same reports
            for message in reported:
                report(message)
            return ClipBinding(motion=self.motion, **values)
        reports: list[str] = []

        def noted(message: str) -> None:
            reports.append(message)
            report(message)

        binding = self._bind(rig, noted)
        if binding.motion is self.motion:  # not retargeted: it depends only on the clip and the character
            bound[self.motion] = (type(self), {f.name: getattr(binding, f.name) for f in fields(binding) if f.name != "motion"}, reports)
        return binding

    def _bind(self, rig, report) -> ClipBinding:
        motion = self.motion
        if motion.skeleton is not rig.skeleton and motion.skeleton.names != rig.skeleton.names:
            shared = [n for n in motion.skeleton.names if n in rig.skeleton.index]
            if len(shared) < 0.5 * motion.skeleton.num_joints:
                motion = self._retarget(rig)
        src = motion.skeleton
        if src.names == rig.skeleton.names:
            columns = np.arange(src.num_joints)
            targets = columns
        else:
            pairs = [(i, rig.skeleton.index[n]) for i, n in enumerate(src.names) if n in rig.skeleton.index]
            columns = np.array([p[0] for p in pairs], dtype=np.int64)
            targets = np.array([p[1] for p in pairs], dtype=np.int64)
            missing = rig.skeleton.num_joints - len(targets)
            if missing:
                report(f"clip {motion.name!r} does not animate {missing} of its joints; they keep the pose below")
        animated = motion.animated_mask
        if not animated.all():  # joints the clip has no data for keep the pose below too
            keep = animated[columns]
            columns, targets = columns[keep], targets[keep]
        # The joint that travels: the root, or the first joint whose position channels move (a
        # SmartBody "base" under a fixed "initial_base").
        mover, travel = 0, motion.root_translations
        if np.ptp(travel, axis=0).max() < 1e-6 and motion.joint_translations is not None:
            moving = np.nonzero(np.ptp(motion.joint_translations, axis=0).max(axis=1) > 1e-6)[0]
            if moving.size:
                mover, travel = int(moving[0]), motion.joint_translations[:, moving[0]]
        step = travel[-1] - travel[0]
        step[1] = 0.0  # a cycle carries the character along the ground, not up
        moved = []
        if motion.joint_translations is not None:  # only joints whose channels leave the character's rest offset
            rest = rig.skeleton.rest_translations
            moved = [(i, rig.skeleton.index[n]) for i, n in enumerate(src.names) if i > 0 and animated[i] and n in rig.skeleton.index
                     and np.abs(motion.joint_translations[:, i] - rest[rig.skeleton.index[n]]).max() > 1e-9]
        if motion.num_frames > 1:  # prepared now, not on the first frame that falls between two of the clip's
            _interpolation_table(motion)
        morph_sources = [k for k, n in enumerate(self.motion.morph_names) if n in rig.morph_index]
        if len(morph_sources) < len(self.motion.morph_names):
            lacking = [n for n in self.motion.morph_names if n not in rig.morph_index]
            report(f"clip {motion.name!r}: the character has no morph target {', '.join(map(repr, lacking[:8]))}; "
                   "those weights are skipped")
        return ClipBinding(
            motion=motion, columns=columns, joints=targets, identity_columns=bool(np.array_equal(columns, np.arange(len(columns)))),
            step=step, mover=mover, drives_root=src.names[0] == rig.skeleton.names[0] and bool(animated[0]),
            moved_columns=np.array([m[0] for m in moved], dtype=np.int64), moved_joints=np.array([m[1] for m in moved], dtype=np.int64),
            morph_sources=np.array(morph_sources, dtype=np.int64),
            morph_columns=np.array([rig.morph_index[self.motion.morph_names[k]] for k in morph_sources], dtype=np.int64))

    def _retarget(self, rig) -> Motion:
        from .. import registry

        table = registry.retargeters()
        if self.source_mapping is None or not table:
            raise UsageError(f"clip {self.motion.name!r} is on another skeleton: retarget it to {rig.name!r} first "
                             "(or give source_mapping= with a retargeter installed)")
        retargeter = registry.get("retargeter")
        return retargeter.retarget(self.motion, self.source_mapping, rig.skeleton, rig.mapping)

    @classmethod
    def evaluate(cls, jobs: Jobs, block: Block) -> None:
        """The characters playing one clip the same way sampled together, in one call over all their
        times, and written side by side. Clips with position channels (an inner joint that travels or
        moves), morph weights or an additive mode, and characters playing more than one clip (a
        crossfade: one after the other), play one job at a time (:meth:`evaluate_one`)."""
        if cls.evaluate_one is not Clip.evaluate_one:  # a subclass plays its own way
            return super().evaluate(jobs, block)
        together, alone = jobs.memo(_Together.of)
        for group in together:
            group.evaluate(jobs, block)
        for k in alone:
            jobs[k].controller.evaluate_one(jobs[k], block)

    def evaluate_one(self, job: Job, block: Block) -> None:
        b: ClipBinding = job.binding
        motion = b.motion
        local = self.offset_s + np.maximum(job.local_times, 0.0) * self.speed
        rot, root, moved, cycles = sample_motion(motion, local, self.loop)
        if not (b.columns.size == rot.shape[1] and b.identity_columns):
            rot = rot[:, b.columns]
        turn, shift = (self.turn, self.shift) if b.drives_root else (None, None)
        if turn is not None:  # the root joint turned (the clip's first sampled column when it drives the root)
            rot = rot.copy()
            rot[:, 0] = quat.multiply(turn, rot[:, 0])
        additive = job.mode is Mode.ADDITIVE
        if additive:  # an additive clip adds its difference from its own rest pose
            rot = quat.multiply(quat.conjugate(motion.skeleton.rest_rotations[b.columns]), rot)
        job.pose.set_rotations(b.joints, rot, job.weight, job.mode)
        first_root = motion.root_translations[0]
        first_moved = None if motion.joint_translations is None else motion.joint_translations[0]  # None with ``moved``
        if b.mover == 0:
            root = root + cycles[:, None] * b.step if self.root_motion else np.broadcast_to(first_root, root.shape)
        elif moved is not None and first_moved is not None:
            travel = moved[:, b.mover]
            moved[:, b.mover] = travel + cycles[:, None] * b.step if self.root_motion else first_moved[b.mover]
        if turn is not None:
            root, first_root = quat.rotate(turn, root) + shift, quat.rotate(turn, first_root) + shift
        if b.drives_root:
            job.pose.set_root(root - first_root if additive else root, job.weight, job.mode)
        if moved is not None and first_moved is not None and b.moved_joints.size:
            values = moved[:, b.moved_columns]
            if additive:
                values = values - first_moved[b.moved_columns]
            job.pose.set_translations(b.moved_joints, values, job.weight, job.mode)
        if b.morph_columns.size:  # from the clip as given: a retargeted copy keeps no morph weights
            weights = sample_morph_weights(self.motion, local, self.loop)[:, b.morph_sources]
            job.pose.set_morphs(b.morph_columns, weights, job.weight, job.mode)


class _Bound(weakref.WeakKeyDictionary):
    """A character's clip bindings (a state of its rig): per clip (a Motion) bound to it as it is (not
    retargeted), the class that bound it, the :class:`ClipBinding`'s values but the clip (which the entry
    then does not keep alive) and the messages binding reported. A clip played again on the character (a
    walk settling onto its pack's idle, the idle it started with) binds at the cost of a look-up."""


@dataclass(frozen=True, eq=False)
class _Together:
    """Clip jobs that sample one motion the same way (looping or not, the same joints), on characters of
    their own: ``rows`` (n,) their places among the jobs, ``offset_s`` and ``speed`` (n, 1) each clip's,
    table ``columns`` (n K,) of the joints they drive (job-major) and the sampled ``sources`` (K,)
    (``every``: all the motion's joints, in order); ``moving`` and ``held`` (among the n) those whose root the clip carries along or holds at its first
    frame, their ``characters`` in the table (``character_index``) and ``steps`` (m, 3) metres per cycle."""

    motion: Motion
    loop: bool
    rows: np.ndarray
    offset_s: np.ndarray
    speed: np.ndarray
    columns: np.ndarray
    sources: np.ndarray
    moving: np.ndarray
    moving_characters: np.ndarray
    steps: np.ndarray
    held: np.ndarray
    held_characters: np.ndarray
    every: bool
    placed: np.ndarray
    turns: np.ndarray
    shifts: np.ndarray

    @staticmethod
    def of(jobs: Jobs) -> tuple[list["_Together"], list[int]]:
        """The groups of ``jobs`` that play together, and the jobs (indices) that play alone."""
        groups: dict[tuple, list[int]] = {}
        alone = []
        clips = Counter(job.rig.name for job in jobs)  # per character
        for k, job in enumerate(jobs):
            b: ClipBinding = job.binding
            plain = (job.mode is Mode.OVERRIDE and b.mover == 0 and not b.moved_joints.size and not b.morph_columns.size
                     and b.motion.joint_translations is None and clips[job.rig.name] == 1)
            if plain:
                groups.setdefault((content_key(b.motion), job.controller.loop, b.columns.tobytes()), []).append(k)
            else:
                alone.append(k)
        return [_Together.group(jobs, rows) for rows in groups.values()], alone

    @staticmethod
    def group(jobs: Jobs, rows: list[int]) -> "_Together":
        chosen = [jobs[k] for k in rows]
        b = chosen[0].binding
        index, first = jobs.table.character_index, jobs.table.first_joint
        clips = [job.controller for job in chosen]
        drives = [job.binding.drives_root for job in chosen]
        moving = [k for k, (clip, root) in enumerate(zip(clips, drives)) if root and clip.root_motion]
        held = [k for k, (clip, root) in enumerate(zip(clips, drives)) if root and not clip.root_motion]
        return _Together(
            b.motion, clips[0].loop, np.array(rows), np.array([[clip.offset_s] for clip in clips]), np.array([[clip.speed] for clip in clips]),
            np.concatenate([first[job.rig.name] + job.binding.joints for job in chosen]), b.columns,
            np.array(moving, dtype=np.int64), np.array([index[chosen[k].rig.name] for k in moving], dtype=np.int64),
            np.array([chosen[k].binding.step for k in moving]).reshape(-1, 3),
            np.array(held, dtype=np.int64), np.array([index[chosen[k].rig.name] for k in held], dtype=np.int64),
            b.columns.size == b.motion.skeleton.num_joints and bool((b.columns == np.arange(b.columns.size)).all()),
            np.array([root and clip.turn is not None for clip, root in zip(clips, drives)], dtype=bool),
            np.array([quat.identity() if clip.turn is None else clip.turn for clip in clips]),
            np.array([np.zeros(3) if clip.shift is None else clip.shift for clip in clips]))

    def evaluate(self, jobs: Jobs, block: Block) -> None:
        """Sample the clip at every job's times at once (as :meth:`Clip.evaluate_one` does, job by job),
        write the joints and the roots side by side."""
        count, frames = len(self.rows), jobs.local_times.shape[1]
        local = self.offset_s + np.maximum(jobs.local_times[self.rows], 0.0) * self.speed  # (n, F)
        # Sampled as each job alone would be: held on the clip's frames when all its times are, else interpolated.
        position, cycles = clip_positions(self.motion, local, self.loop)
        on = on_frames(position)
        sampled = None if self.every else self.sources
        if on.all() or not on.any():  # one way for all (a block of one frame: always)
            r, root, _, _ = sample_positions(self.motion, position.ravel(), cycles.ravel(), sampled)
            rot = r.reshape(count, frames, -1, 4)
            root = root.reshape(count, frames, 3)
        else:
            rot, root = np.empty((count, frames, self.sources.size, 4)), np.empty((count, frames, 3))
            for rows in (np.flatnonzero(on), np.flatnonzero(~on)):
                r, t, _, _ = sample_positions(self.motion, position[rows].ravel(), cycles[rows].ravel(), sampled)
                rot[rows], root[rows] = r.reshape(rows.size, frames, -1, 4), t.reshape(rows.size, frames, 3)
        if self.placed.any():  # each placed job's root joint turned (the first sampled column: the root)
            rot = rot.copy()
            p = self.placed
            rot[p, :, 0] = quat.multiply(self.turns[p][:, None], rot[p, :, 0])
        joints = rot.shape[2]
        side_by_side = np.swapaxes(rot, 0, 1).reshape(frames, count * joints, 4)
        weights = jobs.weights[self.rows]  # (n, F)
        poses = [jobs[k].pose for k in self.rows]
        full = bool((weights >= 1.0).all())
        block.table.set_rotations(self.columns, side_by_side, None if full else np.repeat(weights.T, joints, axis=1),
                                  Mode.OVERRIDE, poses)
        # The roots the clip drives: carried on by the cycles completed, or held at its first frame.
        table = block.table
        if self.moving.size:
            m = self.moving
            travel = root[m] + cycles[m][..., None] * self.steps[:, None]
            if self.placed[m].any():
                travel = quat.rotate(self.turns[m][:, None], travel) + self.shifts[m][:, None]
            table.set_roots(self.moving_characters, np.swapaxes(travel, 0, 1), weights[m].T, Mode.OVERRIDE, ())
        if self.held.size:
            first = np.broadcast_to(self.motion.root_translations[0], (frames, self.held.size, 3))
            if self.placed[self.held].any():
                first = np.broadcast_to(quat.rotate(self.turns[self.held], first[0]) + self.shifts[self.held], first.shape)
            table.set_roots(self.held_characters, first, weights[self.held].T, Mode.OVERRIDE, ())
