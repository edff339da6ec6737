"""The gaze controller: a character looks at a target with its eyes, head and spine.

``Gaze(target, influence="WAIST", priority="eyes", offset_angle_deg=0, offset_direction=None, ...)``
is played by the :class:`~infuse.runtime.Runtime` in the GAZE layer, additively on the pose below.
Targets are anything :func:`infuse.runtime.as_target` takes: a point, an (F, 3) track, a function of
time, or ``"character:joint"`` (``"character:face"`` means the eyes, or the head); a plain name is
resolved by the runtime when evaluated (a named scene object, or a character's face). The blend weight
scales the turn *before* smoothing and speed limits, so blending in and out obeys the speeds too.

Characters without eyes gaze with the head and spine (the head then points at the target); this
and other gaps are reported once per character.
"""
from __future__ import annotations

from typing import Mapping

import numpy as np

from infuse import quaternions as quat
from infuse.errors import UsageError
from infuse.runtime import Controller, Layer, Mode, as_target
from infuse.runtime.pose import chain_fk, chain_plan
from infuse.runtime.swing import swing
from infuse.runtime.targets import JointTarget

from .binding import GazeBinding, GazeState, bind_chain
from .model import DEFAULT_INFLUENCE, GROUP_NAMES, GROUPS, INFLUENCES, OFFSET_DIRECTIONS, SLOTS, group_name, smoothing_factor
from .solver import Faces, SolverInput, solve

_FORWARD = 2  # an aligned frame's forward axis (+Z): its matrix's third column
#: Radians under which an ended gaze's turn is back at rest (the runtime then evaluates it no more).
SETTLED_RAD = 1e-6


def offset_vector(angle_deg: float, direction) -> tuple[float, float]:
    """(heading, pitch) radians of an offset of ``angle_deg`` toward ``direction``: a BML word
    (RIGHT, UPLEFT...) or a polar angle in degrees (0 = the character's right, 90 = up)."""
    if direction is None or angle_deg == 0:
        return 0.0, 0.0
    if isinstance(direction, str):
        key = direction.strip().upper()
        if key not in OFFSET_DIRECTIONS:
            raise UsageError(f"offset direction {direction!r}: expected one of {', '.join(OFFSET_DIRECTIONS)} or degrees")
        polar = OFFSET_DIRECTIONS[key]
    else:
        polar = float(direction)
    a, p = np.radians(angle_deg), np.radians(polar)
    return float(-a * np.cos(p)), float(a * np.sin(p))  # heading is positive to the left


class Gaze(Controller):
    """Look at ``target`` (see the module doc).

    - ``influence``: EYES, HEAD, SHOULDER, WAIST or WHOLE (how far down the chain the turn reaches),
      or ``groups``: the group names that move (overrides ``influence``; e.g. SmartBody's joint range);
    - ``priority``: the group that points exactly at the target (default the eyes): groups below it
      share the turn, groups above take what is left;
    - ``offset_angle_deg`` and ``offset_direction``: look beside the target;
    - ``limits``: {group: (heading, up, down, roll) degrees}, ``smooth``: {group: 0..1},
      ``speed_deg_s``: {group: degrees per second} override the model's values (:data:`GROUPS`).
    """

    kind = "gaze"
    layer = Layer.GAZE
    mode = Mode.ADDITIVE
    blend_in_s = 0.3
    blend_out_s = 0.5

    def __init__(self, target, influence: str | None = None, priority: str = "eyes", offset_angle_deg: float = 0.0,
                 offset_direction=None, groups=None, limits: Mapping | None = None, smooth: Mapping | None = None,
                 speed_deg_s: Mapping | None = None):
        self.target = as_target(target) if not (isinstance(target, str) and target.count(":") == 0) else target
        influence = (influence or DEFAULT_INFLUENCE).upper()
        if influence not in INFLUENCES:
            raise UsageError(f"gaze influence {influence!r}: expected one of {', '.join(INFLUENCES)}")
        self.influence = influence
        self.moving = tuple(group_name(g) for g in groups) if groups else INFLUENCES[influence]
        self.priority_group = group_name(priority)
        self.offset = offset_vector(float(offset_angle_deg), offset_direction)
        settings = list(GROUPS)
        for table, apply in ((limits, lambda g, v: g.with_changes(heading_deg=v[0], up_deg=v[1], down_deg=v[2], roll_deg=v[3])),
                             (smooth, lambda g, v: g.with_changes(smooth=float(v))),
                             (speed_deg_s, lambda g, v: g.with_changes(speed_deg_s=float(v)))):
            for key, value in (table or {}).items():
                i = GROUP_NAMES.index(group_name(key))
                settings[i] = apply(settings[i], value)
        for g in settings:
            if g.speed_deg_s <= 0 or not 0 <= g.smooth < 1 or min(g.heading_deg, g.up_deg, g.down_deg, g.roll_deg) < 0:
                raise UsageError(f"gaze group {g.name!r}: speeds must be > 0, smooth in [0, 1), limits >= 0")
        self.settings = tuple(settings)
        self.limits = np.array([g.limits_rad for g in self.settings])  # (G, 4) radians
        self._rates: dict[float, tuple[np.ndarray, np.ndarray]] = {}
        # Evaluated after its end until the slowest group is back: its largest turn at its speed.
        self.settle_s = max(g.heading_deg / g.speed_deg_s for g in self.settings) + 0.5

    def describe(self) -> str:
        return f"gaze ({self.influence.lower()})"

    def rates(self, dt: float) -> tuple[np.ndarray, np.ndarray]:
        """Per group (G,): the share of the distance left covered in a frame of ``dt`` seconds, and the
        largest step in radians."""
        rates = self._rates.get(dt)
        if rates is None:
            rates = (np.array([smoothing_factor(g.smooth, dt) for g in self.settings]),
                     np.array([np.radians(g.speed_deg_s) * dt for g in self.settings]))
            self._rates[dt] = rates
        return rates

    # -- binding -------------------------------------------------------------------------------------
    def bind(self, rig, report) -> GazeBinding:
        """:func:`~.binding.bind_chain`'s binding, worked out once per character and the groups it moves
        and points (:class:`GazeBindings`); what it reports is reported again each time."""
        key = (self.moving, self.priority_group)
        kept = rig.state_of(GazeBindings)
        found = kept.get(key)
        if found is None:
            notes: list[str] = []
            try:
                binding = bind_chain(rig, self.moving, self.priority_group, notes.append)
            except Exception:
                for note in notes:
                    report(note)
                raise
            for array in vars(binding).values():
                if isinstance(array, np.ndarray):
                    array.flags.writeable = False
            found = kept[key] = (binding, tuple(notes))
        for note in found[1]:
            report(note)
        return found[0]

    # -- evaluation ----------------------------------------------------------------------------------
    @classmethod
    def evaluate(cls, jobs, block) -> None:
        """One solver row per character: its gaze activities take turns (see :func:`_in_charge`)."""
        rows: dict[str, list] = {}
        for job in jobs:
            rows.setdefault(job.rig.name, []).append(job)
        rows = {name: row if len(row) == 1 else _drop_superseded(sorted(row, key=lambda j: (j.activity.start_s, j.activity.id)), block)
                for name, row in rows.items()}
        frames, dt = len(block), block.dt
        # The characters in the table's order: the same from block to block, whatever order their gazes began in.
        names = sorted(rows, key=block.table.character_index.__getitem__)
        leads = [rows[name][0] for name in names]
        # The chains depend only on the leading gazes: kept while they lead (a gaze taking over blends in
        # over many blocks). The usual case, one additive gaze per character: its settings are kept too.
        single = all(len(row) == 1 for row in rows.values()) and all(job.mode is Mode.ADDITIVE for job in leads)
        previous = jobs.last()
        chains = jobs.memo(lambda chosen: _Chains(chosen, block.table, previous if isinstance(previous, _Chains) else None), leads)
        owned = None if single else _owners(rows, names, block)
        if single:
            arrays = chains.settings(frames, dt)  # with "kept", what the solver keeps of them
            # the jobs' own weights stacked, when they are the leads (one gaze per character, in their order)
            in_order = len(jobs) == len(leads) and all(job is lead for job, lead in zip(jobs, leads))
            arrays["weights"] = jobs.weights if in_order else np.array([job.weight for job in leads])
            spans = [[(job, slice(None))] for job in leads]
        elif owned is not None:  # a gaze taking over in blocks it leads whole (blocks of one frame: always)
            arrays = chains.settings(frames, dt, owned[0])
            arrays["weights"] = owned[1]
            spans = [[(job, slice(None))] for job in owned[0]]
        else:
            arrays, spans = _settings_per_frame(rows, names, block)
        # The pose below, along each chain; characters on one skeleton share the forward kinematics.
        chain = dict(zip(("frames_world", "positions", "origin"), _chain_frames(leads, chains, block.table)))
        positions = chain["positions"]  # each slot's joint in the world
        # Where the priority joint points: the mean forward (+Z) axis of the eyes or the head.
        forward_axes = chain["frames_world"][..., _FORWARD]  # (C, F, S, 3)
        lead_weights = chains.lead_weights if single else chains.lead_weights_of([span[0][0] for span in spans])
        chain["forward"] = _weighted_slots(lead_weights, forward_axes)
        for c in (c for c in range(len(names)) if len(spans[c]) > 1):  # a gaze led otherwise may take over
            for job, these in spans[c][1:]:
                chain["forward"][c, these] = _weighted_slots(job.binding.lead_weights()[None], forward_axes[c:c + 1, these])[0]
        # Targets. A character looking at another gazing one (its eyes or head) takes that character's
        # joints from the chain above, and again from its solved chain (``refine``).
        targets = arrays["targets"] = np.empty((len(names), frames, 3))
        refine, elsewhere, lost, faces = (chains.plan(block) if single else chains.plan(block, rows, owned[0]) if owned
                                          else _plan_targets(rows, names, spans, chains, block))
        for c, job, these, target in elsewhere:
            targets[c, these] = target.positions(block.times, block)[these]
        if lost and arrays["weights"] is jobs.weights:
            arrays["weights"] = jobs.weights.copy()  # the jobs' own stay as they are
        for c, job, these, problem in lost:  # a target that names nothing in the scene: this gaze rests
            job.report(f"gaze target {job.controller.target!r} cannot be found ({problem}); the gaze is skipped")
            targets[c, these] = 0.0
            arrays["weights"][c, these] = 0.0
        faces.place(targets, positions)
        inp = SolverInput(present=chains.present, counts=chains.counts, refine=tuple(refine), faces=faces, **arrays, **chain)
        # The smoothing's state, per character (whichever of its gazes leads), stacked for the solver,
        # which updates it in place: each character's state holds views of the stacked arrays.
        states = [job.rig.state_of(GazeState) for job in leads]
        offsets = solve(inp, *(chains.stacked_states(states) if single or owned else _stacked_states(states)))
        _end_settled([rows[name] for name in names], states, block)
        # Each slot's turn Δ as a local offset A Δ A⁻¹ of its joint (A: its aligned frame), for every
        # character at once, written onto every character's joints at once.
        cells = np.swapaxes(offsets, 0, 1).reshape(frames, -1, 2)[:, chains.present_cells]  # (F, P, 2)
        turns = swing(cells[..., 0], cells[..., 1])  # (F, P, 4)
        present = np.swapaxes(np.swapaxes(turns, 0, 1) @ chains.present_to_local, 0, 1)
        block.table.add_offsets(chains.columns, present, None, [job.pose for job in leads])


class GazeBindings(dict):
    """The gaze bindings of one runtime character, by (groups moved, group pointing): (binding, what binding
    reported). They depend only on its mapped joints and their aligned frames, fixed with the rig. Kept
    in the character's rig (:meth:`~infuse.runtime.rig.Rig.state_of`), read-only, shared by its gazes."""


def _stacked_states(states: list) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The turns of ``states`` (each character's :class:`GazeState`, in order) stacked: groups (C, G, 2),
    eyes (C, 2, 2) and first pass (C, G, 2); each state then holds its rows of them (views)."""
    stacked = (np.stack([st.groups for st in states]), np.stack([st.eyes for st in states]),
               np.stack([st.first for st in states]))
    for c, state in enumerate(states):
        state.groups, state.eyes, state.first = stacked[0][c], stacked[1][c], stacked[2][c]
    return stacked


def _plan_targets(rows: dict, names: list, spans: list, chains: "_Chains", block) -> tuple[list, list, list, Faces]:
    """What each gaze of ``spans`` looks at: (c, c2, slots, frames) entries of faces of gazing
    characters (``refine``), (c, job, frames, target) of other targets and (c, job, frames, problem)
    of targets that cannot be found; and ``refine`` as :class:`~infuse_gaze.solver.Faces`."""
    index = {name: c for c, name in enumerate(names)}
    refine: list[tuple[int, int, tuple[int, ...], slice | np.ndarray]] = []
    elsewhere, lost = [], []
    for c, name in enumerate(names):
        for job, these in spans[c]:
            target = job.controller.target
            try:
                target = block.runtime.target(target) if isinstance(target, str) else target
                slots: tuple[int, ...] = ()
                if isinstance(target, JointTarget) and target.character in index:
                    slots = chains.slots_of(target, rows[target.character][0], block)
                if slots:  # on the frames this gaze leads, whether or not another leads the rest of the block
                    refine.append((c, index[target.character], slots, these))
                else:
                    elsewhere.append((c, job, these, target))
            except UsageError as exc:
                lost.append((c, job, these, exc))
    return refine, elsewhere, lost, Faces(refine)


def _owners(rows: dict, names: list, block) -> tuple[list, np.ndarray] | None:
    """Per character (``names``, their gaze jobs ``rows``), the gaze in charge (:func:`_in_charge`) when one is
    over the whole block, and the blend weights (C, F); None when a character's changes within the block
    or one of its gazes overrides the pose below."""
    owners, weights = [], []
    for name in names:
        row = rows[name]
        if any(job.mode is not Mode.ADDITIVE for job in row):
            return None
        owner, weight = _in_charge(row, block.times)
        if (owner != owner[0]).any():
            return None
        owners.append(row[int(owner[0])])
        weights.append(weight)
    return owners, np.array(weights)


def _settings_per_frame(rows: dict, names: list, block) -> tuple[dict, list]:
    """The solver's settings (C, F, ...) when a character's gazes take turns within the block (or one
    overrides the pose below), frame by frame, and per character the (job, frames it leads) spans."""
    frames, dt = len(block), block.dt
    n_groups = len(GROUPS)
    shape = (len(names), frames)
    arrays = {
        "weights": np.empty(shape), "active": np.empty(shape + (n_groups,)),
        "fractions": np.empty(shape + (n_groups,)), "limits": np.empty(shape + (n_groups, 4)),
        "smoothing": np.empty(shape + (n_groups,)), "max_step": np.empty(shape + (n_groups,)),
        "offsets": np.empty(shape + (2,)),
    }
    spans = []
    for c, name in enumerate(names):
        row = rows[name]
        owner, arrays["weights"][c] = _in_charge(row, block.times)
        # (job, the frames it leads): a slice when one gaze leads the whole block
        spans.append([(row[0], slice(None))] if len(row) == 1 else
                     [(job, owner == k) for k, job in enumerate(row) if np.any(owner == k)])
        for job, these in spans[c]:
            b, gaze = job.binding, job.controller
            if job.mode is Mode.OVERRIDE:  # the gaze joints start from their rest rotation, not the pose below
                joints = b.joints
                rest = job.rig.skeleton.rest_rotations[joints]
                leads = np.zeros(frames, dtype=bool)
                leads[these] = True
                job.pose.set_rotations(joints, np.broadcast_to(rest, (frames,) + rest.shape), job.weight * leads)
            arrays["active"][c, these] = b.active
            arrays["fractions"][c, these] = b.fractions
            arrays["offsets"][c, these] = gaze.offset
            arrays["limits"][c, these] = gaze.limits
            arrays["smoothing"][c, these], arrays["max_step"][c, these] = gaze.rates(dt)
    return arrays, spans


class _Chains:
    """The gazing characters' chains side by side, one leading gaze each (``jobs``, in order): what the
    solver needs of them that changes only with the gazes.

    - ``present`` (C, S), ``counts`` (C, G), ``aligned`` (C, S, 4): each binding's, stacked;
    ``present_to_local`` (P, 4, 4): per present slot (``present_cells``), the transposed matrix of
    ``A Δ A⁻¹`` (A: the slot's aligned frame) acting on Δ;
    - ``lead_weights`` and ``origin_weights`` (C, S): the slots the gaze points and starts from (the
      leading gaze's: a gaze taking over within the block may point other slots);
    - ``world`` (C, 1, S, 1) or None: the slots that are the world itself (no pelvis);
    - ``skeletons``: a :class:`_ChainGroup` per skeleton and chain, for one forward kinematics over
      its characters; ``aligned_matrices`` (C, S, 3, 3): ``aligned`` as matrices;
    - ``columns`` (P,): the table columns of every character's present slots, ``present_cells`` (P,):
      their cells ``c S + s`` among every character's slots.

    ``previous``: the chains of the gazes these follow, if any: what was worked out there for gazes that
    then took over and lead here is taken over.
    """

    def __init__(self, jobs, table, previous: "_Chains | None" = None):
        bindings = [job.binding for job in jobs]
        self.jobs = jobs
        self.layout = table.layout
        self.lead_weights = np.array([b.lead_weights() for b in bindings])
        self.origin_weights = np.array([b.origin_weights() for b in bindings])
        self._states: tuple[list, tuple[np.ndarray, np.ndarray, np.ndarray]] | None = None
        self._placed: tuple[list, tuple[np.ndarray, np.ndarray, np.ndarray]] | None = None
        if previous is not None and previous.layout is table.layout and len(previous.jobs) == len(jobs) \
                and all(was.rig is job.rig for was, job in zip(previous.jobs, jobs)):
            # The same characters in the same table: a chain, its slots and their frames are the character's
            # whatever its gaze (which moves only some of them), so they are those already worked out.
            for name in _CHARACTERS_OWN:
                setattr(self, name, getattr(previous, name))
        else:
            self.present = np.stack([b.present for b in bindings])
            self.counts = np.stack([b.counts for b in bindings])
            self.aligned = np.stack([b.chain_aligned for b in bindings])  # (C, S, 4)
            to_local = quat.left_matrix(self.aligned) @ quat.right_matrix(quat.conjugate(self.aligned))  # (C, S, 4, 4)
            world = np.stack([b.slot_source < 0 for b in bindings])[:, None, :, None]
            self.world = world if world.any() else None
            same_chain: dict[tuple, list[int]] = {}
            for c, job in enumerate(jobs):
                same_chain.setdefault((id(job.rig.skeleton), tuple(job.binding.slot_joints)), []).append(c)
            self.skeletons = [_ChainGroup(members, [jobs[c] for c in members], table) for members in same_chain.values()]
            self.aligned_matrices = quat.unit_to_matrix(self.aligned)  # (C, S, 3, 3)
            self.columns = np.concatenate([table.first_joint[job.rig.name] + b.joints for job, b in zip(jobs, bindings)])
            self.present_cells = np.flatnonzero(self.present)
            self.present_to_local = np.swapaxes(to_local.reshape(-1, 4, 4)[self.present_cells], -1, -2)
        self._settings: dict[tuple, dict] = {}  # by frames, dt and what the gazes set (:func:`_settings_of`)
        self._own: dict[tuple, dict] = {}  # the chains' own gazes' of those, by frames and dt
        self._set: dict[int, int] = {}  # by each gaze's activity id, the number of what it sets (:meth:`_setting`)
        self._sets: dict[tuple, int] = {}  # :func:`_settings_of` gazes, numbered
        self._slots: dict[tuple, tuple[int, ...]] = {}
        self._plans: dict[tuple, tuple[list, list, list, Faces]] = {}
        self._lead_weights: dict[tuple, np.ndarray] = {}
        if previous is not None and previous.present is self.present:
            # The same characters: the settings worked out for gazes that set the same (a gaze taking over
            # from one set alike, or that took over and leads now) hold, and the solver's products with them.
            self._settings.update(previous._settings)
            self._set.update(previous._set)
            self._sets.update(previous._sets)
            ids = tuple(job.activity.id for job in jobs)  # and the targets' plan of gazes that took over and lead now
            self._plans.update({(version, None): plan for (version, owners), plan in previous._plans.items() if owners == ids})

    def placements(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Where the characters stand: their rotations (C, 4), as matrices (C, 3, 3), and positions (C, 3);
        kept while each rig holds the same placement arrays (a scene turning a character gives its
        rig a new rotation)."""
        rigs = [job.rig for job in self.jobs]
        kept = self._placed
        if kept is None or any(rig.rotation is not rotation or rig.position is not position
                               for rig, (rotation, position) in zip(rigs, kept[0])):
            rotation = np.stack([rig.rotation for rig in rigs])
            kept = self._placed = ([(rig.rotation, rig.position) for rig in rigs],
                                   (rotation, quat.unit_to_matrix(rotation), np.stack([rig.position for rig in rigs])))
        return kept[1]

    def settings(self, frames: int, dt: float, owners: list | None = None) -> dict:
        """The solver's settings (C, F, ...) of one gaze per character over ``frames`` frames of ``dt``
        seconds (read-only views: the same for every frame), and the solver's ``kept`` dict for them. The
        gazes are the chains' own, or ``owners`` (one job each, in order: gazes taking over, in charge of the
        whole block)."""
        if owners is None and (frames, dt) in self._own:
            return dict(self._own[(frames, dt)])
        jobs = self.jobs if owners is None else owners
        key = (frames, dt, tuple(map(self._setting, jobs)))
        kept = self._settings.get(key)
        if kept is None:
            if len(self._settings) > 8:  # gazes taking over one after the other: only the latest are needed
                self._settings.clear()
            gazes = [job.controller for job in jobs]
            count = len(gazes)
            rates = [gaze.rates(dt) for gaze in gazes]
            per_character = {
                "active": np.stack([job.binding.active for job in jobs]),
                "fractions": np.stack([job.binding.fractions for job in jobs]),
                "limits": np.stack([gaze.limits for gaze in gazes]),
                "smoothing": np.stack([r[0] for r in rates]), "max_step": np.stack([r[1] for r in rates]),
                "offsets": np.array([gaze.offset for gaze in gazes], dtype=np.float64).reshape(count, 2),
            }
            kept = self._settings[key] = {name: np.broadcast_to(value[:, None], (count, frames) + value.shape[1:])
                                          for name, value in per_character.items()}
            kept["kept"] = {}
        if owners is None:
            self._own[(frames, dt)] = kept
        return dict(kept)

    def _setting(self, job) -> int:
        """The number of what ``job``'s gaze sets (:func:`_settings_of`): the same for gazes that set the same."""
        number = self._set.get(job.activity.id)
        if number is None:
            if len(self._set) > 256:  # gazes come and go: the numbers of those gone are not needed
                self._set.clear()
            if len(self._sets) > 256:  # numbered afresh, what was kept under the numbers before goes with them
                self._sets.clear()
                self._set.clear()
                self._settings.clear()
            number = self._set[job.activity.id] = self._sets.setdefault(_settings_of(job), len(self._sets))
        return number

    def stacked_states(self, states: list) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """:func:`_stacked_states`, the arrays of the last block again while every state still holds the
        rows it was given (the solver updated them in place)."""
        kept = self._states
        if kept is None or any(st.groups is not rows[0] or st.eyes is not rows[1] or st.first is not rows[2]
                               for st, rows in zip(states, kept[0])):
            stacked = _stacked_states(states)
            kept = self._states = ([(st.groups, st.eyes, st.first) for st in states], stacked)
        return kept[1]

    def plan(self, block, rows: dict | None = None, owners: list | None = None) -> tuple[list, list, list, Faces]:
        """:func:`_plan_targets` of the gazes (one each, leading the block; or ``owners``, in charge of the
        whole block, of the characters' gaze jobs ``rows``), kept while the runtime resolves target names
        as it did."""
        jobs = self.jobs if owners is None else owners
        key = (block.runtime.targets_version, None if owners is None else tuple(job.activity.id for job in owners))
        plan = self._plans.get(key)
        if plan is None:
            if len(self._plans) > 8:
                self._plans.clear()
            rows = {job.rig.name: [job] for job in self.jobs} if rows is None else rows
            plan = self._plans[key] = _plan_targets(rows, [job.rig.name for job in jobs], [[(job, slice(None))] for job in jobs],
                                                    self, block)
        return plan

    def lead_weights_of(self, jobs: list) -> np.ndarray:
        """(C, S) the slots each of ``jobs`` (one each, in order) points (:attr:`lead_weights` of other gazes)."""
        key = tuple(job.activity.id for job in jobs)
        weights = self._lead_weights.get(key)
        if weights is None:
            if len(self._lead_weights) > 8:
                self._lead_weights.clear()
            weights = self._lead_weights[key] = np.array([job.binding.lead_weights() for job in jobs])
        return weights

    def slots_of(self, target: JointTarget, job, block) -> tuple[int, ...]:
        """:func:`_slots_of`, kept per target and gazing character's binding."""
        key = (target, id(job.binding))
        slots = self._slots.get(key)
        if slots is None:
            slots = self._slots[key] = _slots_of(target, job, block)
        return slots



def _settings_of(job) -> tuple:
    """What :meth:`_Chains.settings` reads of a gaze job: the groups its binding moves and their shares, and
    its gaze's group settings and offset (two gazes setting the same share what is worked out of them)."""
    gaze, b = job.controller, job.binding
    return b.active.tobytes(), b.fractions.tobytes(), gaze.settings, gaze.offset


#: What :class:`_Chains` works out of the characters alone (their rigs and places in the table), whatever
#: their gazes: its chains' arrays and forward kinematics, and its caches of the characters' placements and turns.
_CHARACTERS_OWN = ("present", "counts", "aligned", "world", "skeletons", "aligned_matrices", "columns", "present_cells",
                   "present_to_local", "_states", "_placed")


def _drop_superseded(row, block) -> list:
    """A character's gaze jobs (sorted by start) without those an open-ended gaze has taken over from.

    Once the latest gaze without an end (a ``gazeShift``) is fully blended in by the block's first
    frame, it leads until it is stopped and its weight 1 is the largest: the gazes before it can no
    longer lead nor weigh (:func:`_in_charge`). They end where that gaze's blend-in completed (or
    earlier, where they ended), without a settle (:meth:`~infuse.runtime.Runtime.end`): the character's
    turn is carried on by the gaze that took over, so the runtime evaluates them no more; the frames are
    the same. A gaze so ended does not come back when the one that took over is later stopped: the
    character then returns to rest."""
    first = block.times[0]
    takeover = max((k for k, job in enumerate(row) if job.activity.end_s is None
                    and job.activity.start_s + job.activity.blend_in_s <= first + 1e-9), default=0)
    lead = row[takeover].activity
    ended = lead.start_s + lead.blend_in_s
    for job in row[:takeover]:
        block.runtime.end(job.activity, ended)
    return row[takeover:]


def _end_settled(rows: list, states: list, block) -> None:
    """End the gazes no later frame needs, without a settle (:meth:`~infuse.runtime.Runtime.end`), per
    character (``rows``: its gaze jobs sorted by start; ``states``: its turn): one that has ended by the
    block's last frame once a later one has started (that one carries the turn on: :func:`_in_charge`),
    and all of them once every one has ended and the turn is back at rest (every offset under
    :data:`SETTLED_RAD`): for the rest of their settling time they would only carry that turn on."""
    last = block.times[-1] + 1e-9
    if all(job.activity.end_s is None or job.activity.end_s > last for row in rows for job in row):
        return  # the usual case: nothing to end
    for row, state in zip(rows, states):
        ended = [job.activity.end_s is not None and job.activity.end_s <= last for job in row]
        if not any(ended):
            continue  # the usual case: nothing to end
        if all(ended) and max(np.abs(state.groups).max(), np.abs(state.eyes).max(), np.abs(state.first).max()) < SETTLED_RAD:
            done = row
        else:
            newest = max(k for k, job in enumerate(row) if job.activity.start_s <= last)
            done = [job for job, over in zip(row[:newest], ended) if over]
        for job in done:
            block.runtime.end(job.activity, block.times[-1])


def _in_charge(row, times) -> tuple[np.ndarray, np.ndarray]:
    """Which of a character's gaze activities (sorted by start) leads at each time, and the blend weight.

    A character has one gaze at a time: the latest started that has not ended leads; the others stop
    counting. When a new gaze takes over from one still running, it does not fade in from nothing:
    the weight is the largest of the running gazes', and the turn moves from where it was to the new
    target under the smoothing and speed limits. When none runs, the last one to lead keeps the
    turn returning to rest (weight 0)."""
    if len(row) == 1:
        return np.zeros(len(times), dtype=np.int64), row[0].weight
    starts = np.array([j.activity.start_s for j in row])
    ends = np.array([np.inf if j.activity.end_s is None else j.activity.end_s for j in row])
    t = np.asarray(times)[None]
    running = (starts[:, None] <= t + 1e-9) & (t < ends[:, None] - 1e-9)
    started = starts[:, None] <= t + 1e-9
    ranks = np.arange(len(row))[:, None]
    latest_running = np.max(np.where(running, ranks, -1), axis=0)
    latest_started = np.max(np.where(started, ranks, 0), axis=0)
    owner = np.where(latest_running >= 0, latest_running, latest_started)
    weights = np.stack([j.weight for j in row])
    weight = np.max(np.where(running, weights, 0.0), axis=0)
    own = weights[owner, np.arange(len(owner))]
    return owner, np.where(latest_running >= 0, np.maximum(weight, own), own)


def _chain_frames(jobs, chains: _Chains, table):
    """For the gazing characters (one job each, their ``chains``), from the pose below in ``table``:
    each slot's aligned frame (C, F, S, 3, 3, rotation matrices) and position (C, F, S, 3) in the world,
    and where the gaze starts (C, F, 3). Characters on one skeleton share one forward kinematics; all
    else runs on every character at once."""
    frames = table.frames
    matrices = len(jobs) * frames <= MATRIX_FK_MAX_ROWS
    rot = np.empty((len(jobs), frames, len(SLOTS)) + ((3, 3) if matrices else (4,)))
    pos = np.empty((len(jobs), frames, len(SLOTS), 3))
    for group in chains.skeletons:
        members = [jobs[c] for c in group.members]
        rot[group.members], pos[group.members] = group.slot_poses(members, table) if matrices else group.slot_quaternions(members, table)
    # Into the world, where each character stands, and into the aligned frames: one constant product
    # on either side per character and slot.
    rotation, placement, position = chains.placements()  # (C, 4), (C, 3, 3), (C, 3)
    if matrices:
        frames_w = placement[:, None, None] @ rot @ chains.aligned_matrices[:, None]
    else:
        frames_w = quat.unit_to_matrix(_apply_per_slot(quat.left_matrix(rotation)[:, None] @ quat.right_matrix(chains.aligned), rot))
    pos = (pos.reshape(len(jobs), -1, 3) @ np.swapaxes(placement, -1, -2)).reshape(pos.shape)
    pos += position[:, None, None]
    if chains.world is not None:  # the world itself (no pelvis) stays put
        frames_w = np.where(chains.world[..., None], chains.aligned_matrices[:, None], frames_w)
        pos = np.where(chains.world, 0.0, pos)
    origin = _weighted_slots(chains.origin_weights, pos)
    return frames_w, pos, origin


#: Up to this many characters times frames the chains' forward kinematics runs on rotation matrices
#: (one numpy call per depth); above, on quaternions (:func:`~infuse.runtime.pose.chain_fk`, whose
#: written-out products cost less per rotation than numpy's products of stacks of 3 x 3 matrices).
MATRIX_FK_MAX_ROWS = 256


def _apply_per_slot(matrices: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Matrices (C, S, 4, 4), one per character and slot, times quaternions (C, F, S, 4) (columns)."""
    return np.swapaxes(np.swapaxes(q, 1, 2) @ np.swapaxes(matrices, -1, -2), 1, 2)


class _ChainGroup:
    """Gazing characters on one skeleton with one chain (``members``, their indices among the gazing
    ones; ``jobs``, one each), and what their forward kinematics down the chain needs of them: the
    chain's :class:`~infuse.runtime.pose.ChainPlan` (N joints, parents first), their table columns
    (C_k, N) and roots (C_k,) in ``table``, each slot's joint in the chain (S,) (an absent slot repeats
    its parent's; the world's slots are set apart by the caller) and the rest offsets of the joints
    below the chain's roots (n, 3, 1)."""

    def __init__(self, members: list[int], jobs: list, table):
        lead = jobs[0]
        b = lead.binding
        self.members, self.lead = members, lead
        self.plan = plan = chain_plan(lead.rig.skeleton, tuple(b.joints.tolist()), tuple(b.columns.tolist()))
        self.columns = np.array([table.first_joint[job.rig.name] + job.binding.columns for job in jobs])[:, plan.source]
        self.characters = np.array([table.character_index[job.rig.name] for job in jobs])
        self.source = plan.out[np.maximum(b.slot_source, 0)]
        self.paths = plan.paths[self.source]  # (S, N)
        self.rest = lead.rig.skeleton.rest_translations[plan.chain]  # (N, 3)
        self.inner_rest = self.rest[plan.inner, :, None]

    def slot_poses(self, jobs, table) -> tuple[np.ndarray, np.ndarray]:
        """Rotation matrices (C_k, F, S, 3, 3) and positions (C_k, F, S, 3) of each slot's joint in the
        characters' own frames, from the pose in ``table``: the forward kinematics of
        :func:`~infuse.runtime.pose.chain_fk`, on matrices, one product per depth."""
        plan = self.plan
        rot = quat.unit_to_matrix(np.swapaxes(table.local_rotations[:, self.columns], 0, 1))  # (C, F, N, 3, 3)
        for members, parents in plan.levels:
            rot[:, :, members] = rot[:, :, parents] @ rot[:, :, members]
        moved = [j.pose.joint_translations for j in jobs]
        steps = np.empty(rot.shape[:-1])
        if any(t is not None for t in moved):
            columns = self.lead.binding.columns[plan.source]
            offsets = np.stack([np.broadcast_to(self.rest, rot.shape[1:2] + self.rest.shape) if t is None else t[:, columns]
                                for t in moved])
            inner = offsets[..., plan.inner, :, None]
        else:
            offsets, inner = self.rest, self.inner_rest
        steps[:, :, plan.inner] = (rot[:, :, plan.inner_parents] @ inner)[..., 0]
        if plan.roots.size:
            steps[:, :, plan.roots] = offsets[..., plan.roots, :]
        if plan.root is not None:
            steps[:, :, plan.root] = np.swapaxes(table.root_translations[:, self.characters], 0, 1)
        return rot[:, :, self.source], self.paths @ steps

    def slot_quaternions(self, jobs, table) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`slot_poses` with the rotations as unit quaternions (C_k, F, S, 4), by
        :func:`~infuse.runtime.pose.chain_fk`."""
        b, plan = self.lead.binding, self.plan
        local = np.swapaxes(table.local_rotations[:, self.columns], 0, 1)  # (C, F, N, 4), the chain's order
        root = np.swapaxes(table.root_translations[:, self.characters], 0, 1)
        moved = [j.pose.joint_translations for j in jobs]
        translations = None
        if any(t is not None for t in moved):
            columns = b.columns[plan.source]
            translations = np.stack([np.broadcast_to(self.rest, local.shape[1:2] + self.rest.shape) if t is None else t[:, columns]
                                     for t in moved])
        chain = plan.chain[self.source]  # the slots' joints, by skeleton index
        return chain_fk(self.lead.rig.skeleton, local, root, translations, chain, plan.chain)


def _weighted_slots(weights: np.ndarray, values: np.ndarray) -> np.ndarray:
    """(C, F, 3) sums of ``values`` (C, F, S, 3) over the slots, weighted by ``weights`` (C, S)."""
    return np.einsum("cs,cfsk->cfk", weights, values)


def _slots_of(target: JointTarget, job, block) -> tuple[int, ...]:
    """The chain slots of gazing character ``job`` whose mean is ``target``, if they all are slots."""
    _, joints = target.resolve(block.runtime)
    slots = list(job.binding.slot_joints)
    return tuple(slots.index(j) for j in joints) if all(j in slots for j in joints) else ()
