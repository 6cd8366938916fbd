"""Dry runs of skill calls: the executor's own decisions, on an in-process world that can branch.

A planner that offers only calls that will succeed asks, for every candidate
call of a plan line, what the executor would do from the state the lines so
far produce. Through a Controller (a process, pipes, msgpack) each answer costs
milliseconds. Here :class:`TeamWorld`, unchanged, acts through :class:`_Thor`,
which has the Controller's face (``last_event``, ``step``) but steps a
:class:`Simulator` in process and hands back ai2thor's own ``Event`` objects,
with the fields the stand-in's metadata encoder sends. A call therefore
succeeds here exactly when the executor's would.

Branching is copy-on-write by version: the simulator gives an object a new
version at every change (the encoder's caches rely on it), so a snapshot is the
objects' pickled copies at their versions, shared with earlier snapshots, and a
restore puts back only the objects whose versions differ. An event's object
lists are built when first read: the events of a tried call are read for the
agents' own fields only.
"""

from __future__ import annotations

import math
import pickle
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

from ai2thor.server import Event, MetadataWrapper, MultiAgentEvent

from ..robots import Robot
from ..skills import DEFAULT_SKILL_SET, SkillSet
from ..world.metadata import AGENT_FIELDS, MetadataEncoder, agent_view
from ..world.scenes import floor_plan_name
from ..world.simulator import ActionResult, Simulator
from .team_actions import Outcome, TeamWorld

# The error codes on which ai2thor's Controller.step raises ValueError instead of returning the event.
_RAISING_CODES = frozenset({"InvalidAction", "MissingArguments", "AmbiguousAction", "InvalidArgument"})


def notional_robot(skills: SkillSet = DEFAULT_SKILL_SET, mass_capacity: float = math.inf) -> Robot:
    """A robot with every skill and no mass limit (or ``mass_capacity``): a dry run with it asks what the world
    allows."""
    return Robot(id=-1, name="notional robot", skills=frozenset(skills), mass_capacity=mass_capacity)


class _Metadata(MetadataWrapper):
    """An agent's event metadata whose ``objects`` are built when first read (subscript, ``get``, ``in``).

    Only valid while the world is in the state of the event's step, which is how
    TeamWorld reads events: the latest one, or one restored with its state.
    """

    def __init__(self, fields: dict[str, Any], objects: Callable[[], list[dict[str, Any]]]):
        super().__init__(fields)
        self._objects = objects

    def __missing__(self, key: str) -> Any:
        if key != "objects":
            raise KeyError(key)
        self["objects"] = objects = self._objects()
        return objects

    def __contains__(self, key: object) -> bool:
        return key == "objects" or super().__contains__(key)

    def get(self, key: str, default: Any = None) -> Any:
        return self[key] if key in self else default


class _Thor:
    """What TeamWorld uses of ai2thor's Controller, over a Simulator in this process.

    ``frozen`` holds each object's pickled copy at its version (made on demand),
    for snapshots to share and for the events' object views.
    """

    def __init__(self, sim: Simulator):
        self.sim = sim
        self.encoder = MetadataEncoder()
        self.encoder.reset_agents(len(sim.agents))
        self.sequence_id = 0
        self.frozen: dict[str, tuple[int, bytes]] = {}
        self.frozen_shared = False  # a snapshot holds ``frozen``: copy it before changing it
        self._bases: dict[str, tuple[int, dict[str, Any]]] = {}
        self._views: dict[tuple[int, str], tuple[int, int, dict[str, Any]]] = {}
        self.last_event: Event | MultiAgentEvent = self._event(0, None)

    def step(self, action: str | dict[str, Any] | None = None, **action_args: Any) -> Event | MultiAgentEvent:
        """Run one action, as ``Controller.step`` does (raising ValueError where it raises)."""
        action = dict(action) if isinstance(action, dict) else {"action": action}
        action.update(action_args)
        agent_id = action.get("agentId", 0)
        sim = self.sim
        generation = sim.generation
        result = sim.step(agent_id, action)
        if not result.success and result.error_code in _RAISING_CODES:
            raise ValueError(result.error_message)
        self.sequence_id += 1
        self.encoder.last_results[agent_id] = (action["action"], result)
        self.last_event = self._event(agent_id, self.last_event if sim.generation == generation else None)
        return self.last_event

    def _event(self, active: int, unchanged: Event | MultiAgentEvent | None) -> Event | MultiAgentEvent:
        """The event after an action of agent ``active``. When no object changed, the other agents'
        views are those of the previous event ``unchanged``, as with the stand-in's METADATA_PATCH."""
        events = []
        for i in range(len(self.sim.agents)):
            if unchanged is not None and i != active:
                events.append(unchanged.events[i])
                continue
            fields = self.encoder.agent_fields(self.sim, i, self.sequence_id)
            event = Event(fields)
            event.metadata = _Metadata(fields, lambda i=i: self._objects(i))
            events.append(event)
        return events[0] if len(events) == 1 else MultiAgentEvent(active, events)

    def _objects(self, agent_id: int) -> list[dict[str, Any]]:
        """An agent's ``objects``: each a copy made once per (agent pose, object version), never changed."""
        sim = self.sim
        pose = sim.agents[agent_id].version
        views = []
        for oid in sim.reported_objects(agent_id):
            version = sim.versions[oid]
            cached = self._views.get((agent_id, oid))
            if cached is None or cached[0] != pose or cached[1] != version:
                distance, visible = agent_view(sim, agent_id, sim.objects[oid])
                view = {**self._base(oid, version), "distance": distance, "visible": visible, "isInteractable": visible}
                cached = self._views[agent_id, oid] = (pose, version, view)
            views.append(cached[2])
        return views

    def _base(self, oid: str, version: int) -> dict[str, Any]:
        """An object's own fields at its current version (what every agent reports alike)."""
        cached = self._bases.get(oid)
        if cached is None or cached[0] != version:
            obj = pickle.loads(self.freeze(oid))
            cached = self._bases[oid] = (version, {k: v for k, v in obj.items() if k not in AGENT_FIELDS})
        return cached[1]

    def freeze(self, oid: str) -> bytes:
        """The object's pickled copy at its current version, made once per version."""
        version = self.sim.versions[oid]
        frozen = self.frozen.get(oid)
        if frozen is None or frozen[0] != version:
            if self.frozen_shared:
                self.frozen, self.frozen_shared = dict(self.frozen), False
            frozen = self.frozen[oid] = (version, pickle.dumps(self.sim.objects[oid], pickle.HIGHEST_PROTOCOL))
        return frozen[1]


@dataclass(frozen=True)
class Snapshot:
    """A dry run's state, for :meth:`DryRun.restore`; its contents are the dry run's business."""

    objects: dict[str, tuple[int, bytes]]  # objectId -> (version, pickled object), in scene order
    agents: tuple[dict[str, Any], ...]
    generation: int
    results: tuple[tuple[str, ActionResult], ...]  # each agent's last action, as its metadata reports it
    event: Event | MultiAgentEvent
    helping: dict[int, str]
    meant: dict[tuple[int, str], str]
    gone_to: dict[int, str]
    put_in: frozenset[str]


class DryRun:
    """A team in a floor plan, whose skill calls are tried or performed in process, with the executor's logic.

    Members are team indices (``robots[i]`` of a plan is member ``i``); a call's
    outcome is the :class:`Outcome` the executor's TeamWorld gives it, from the
    state the calls applied so far produce (calls applied in the order the
    executor ran them give the same outcomes as its run).
    """

    def __init__(self, floor_plan: int | str, team: Sequence[Robot], skills: SkillSet = DEFAULT_SKILL_SET):
        self.team = list(team)
        self.skills = skills
        sim = Simulator(floor_plan_name(floor_plan), agent_count=len(self.team))
        self._scene_size = len(sim.objects)
        self._thor = _Thor(sim)
        self._world = TeamWorld(self._thor, self.team, skills)
        self._saved: Snapshot | None = None  # the current state's snapshot, until a call is applied

    @property
    def objects(self) -> list[dict[str, Any]]:
        """The scene's objects now, as the executor sees them (read-only: they are shared with snapshots)."""
        return self._world.objects

    @property
    def world(self) -> TeamWorld:
        """The executor's view of the team here: where each member stands, what it holds or helps carry."""
        return self._world

    @property
    def controller(self) -> Any:
        """This world with the Controller's face, for the executor to run a whole plan in process."""
        return self._thor

    def succeeds(self, members: Sequence[int], skill_name: str, objects: Sequence[str]) -> Outcome:
        """What the call would do from the current state, which it leaves as it was."""
        saved = self.snapshot()
        try:
            return self.apply(members, skill_name, objects)
        finally:
            self.restore(saved)

    def apply(self, members: Sequence[int], skill_name: str, objects: Sequence[str]) -> Outcome:
        """Perform the call; a failed call changes the world only as the executor's would (not at all,
        or by the moves a GoToObject made before it failed)."""
        self._saved = None
        return self._world.perform(self.skills[skill_name], list(objects), list(members))

    def snapshot(self) -> Snapshot:
        """The current state, to come back to with :meth:`restore` (any number of times)."""
        if self._saved is None:
            thor, sim = self._thor, self._thor.sim
            for oid in sim.objects:
                thor.freeze(oid)
            thor.frozen_shared = True
            self._saved = Snapshot(thor.frozen, tuple(vars(a).copy() for a in sim.agents), sim.generation,
                                   tuple(thor.encoder.last_results), thor.last_event, dict(self._world.helping),
                                   dict(self._world.meant), dict(self._world.gone_to), self._world.put_in)
        return self._saved

    def restore(self, snap: Snapshot) -> None:
        """Return to a state :meth:`snapshot` gave (of this dry run), whatever was applied since."""
        thor, sim = self._thor, self._thor.sim
        kept = snap.objects
        if (len(kept) > self._scene_size or len(sim.objects) > self._scene_size) and list(kept) != list(sim.objects):
            # Pieces cut in one branch and not the other: rebuild the table in the snapshot's order.
            sim.objects = {oid: sim.objects[oid] if sim.versions.get(oid) == version else pickle.loads(data)
                           for oid, (version, data) in kept.items()}
            sim.versions = {oid: version for oid, (version, _) in kept.items()}
        else:
            versions = sim.versions
            for oid, version in versions.items():
                old = kept[oid]
                if old[0] != version:
                    sim.objects[oid] = pickle.loads(old[1])
                    versions[oid] = old[0]
        for agent, fields in zip(sim.agents, snap.agents):
            vars(agent).update(fields)
        sim.generation = snap.generation
        thor.frozen, thor.frozen_shared = kept, True
        thor.encoder.last_results = list(snap.results)
        thor.last_event = self._world.event = snap.event
        self._world.helping = dict(snap.helping)
        self._world.meant = dict(snap.meant)
        self._world.gone_to = dict(snap.gone_to)
        self._world.put_in = snap.put_in
        self._saved = snap
