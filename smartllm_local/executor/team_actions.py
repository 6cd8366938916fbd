"""What one skill call does, for one robot or a team, through the ai2thor Controller.

Robots are the Controller's agents: team member i is ``agentId=i``. Skills and
mass limits are the robots' (the world knows neither), so they are enforced
here:

- a team acts with the union of its members' skills; the member that performs
  the AI2-THOR action is the one that meets its precondition (holds the object
  to put down, holds the knife, has a free hand), preferring members that have
  the skill themselves;
- slicing needs a Knife or ButterKnife in the acting member's hand. AI2-THOR's
  SliceObject does not check what the agent holds (ALFRED adds the same rule in
  its own environment), so the skill refuses before any action is sent, and a
  plan scores the same on a Unity build and on the stand-in;
- picking something up needs lifting capacity for its mass (what it holds
  included): the acting robot's, plus that of free-handed team members within
  reach, who then help carry it until it is put down;
- an object type resolves to the nearest instance (to the acting robot) that
  has the affordance the skill needs; ``GoToObject`` moves every member to the
  nearest free reachable cells and turns them to face it.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Collection, Sequence
from dataclasses import dataclass
from typing import Any

from ..robots import Robot
from ..skills import Skill, SkillSet, has_affordance
from ..world.navigation import Box, facing_yaw
from ..world.object_types import OPEN_TOPPED, SLICE_RESULTS, base_type
from ..world.rules import linked
from .focus import CREATING_ACTIONS, focus_ids

KNIVES = frozenset({"Knife", "ButterKnife"})
# Scene masses are float32 values (a 0.4 kg cup is 0.4000000059604645): a capacity that equals
# the mass as written must suffice.
_MASS_TOLERANCE = 1e-6

#: What an action can change: an instance it cannot (a cabinet open already, to open) is meant only where no other is.
_CHANGES: dict[str, Callable[[dict[str, Any]], bool]] = {
    "OpenObject": lambda o: not o.get("isOpen"),
    "CloseObject": lambda o: bool(o.get("isOpen")),
    "ToggleObjectOn": lambda o: not o.get("isToggled"),
    "ToggleObjectOff": lambda o: bool(o.get("isToggled")),
}
#: The actions by which a robot lets go of what it holds.
RELEASE_ACTIONS = frozenset({"PutObject", "DropHandObject", "ThrowObject"})


@dataclass
class Outcome:
    success: bool
    error: str = ""
    object_id: str | None = None
    action: str = ""
    actor: int | None = None
    # Where each acting member stands after the call, and the object it acted on (x, z in metres): the
    # run viewer's map. None where the world has no positions (a lab's robots).
    positions: list[tuple[float, float]] | None = None
    object_position: tuple[float, float] | None = None


class TeamWorld:
    """The team's view of the world: the latest event, and the Controller to act through.

    With ``focus`` (the object names a plan uses), every agent reports only the
    objects those names can involve (see :mod:`.focus`) until :meth:`release`.
    """

    def __init__(self, controller: Any, team: Sequence[Robot], skills: SkillSet,
                 *, focus: Collection[str] | None = None):
        self.controller = controller
        self.team = list(team)
        self.skills = skills
        self.event = controller.last_event
        reply = controller.step(action="GetReachablePositions")
        self.event = reply
        self.cells = [(p["x"], p["z"]) for p in reply.metadata["actionReturn"] or []]
        self.cell_y = (reply.metadata["actionReturn"] or [{"y": 0.9}])[0]["y"]
        self.helping: dict[int, str] = {}  # member -> object it helps carry
        self.meant: dict[tuple[int, str], str] = {}  # (member, fixture type) -> the instance it last meant
        self.gone_to: dict[int, str] = {}  # member -> the object it last went to
        self.put_in: frozenset[str] = frozenset()  # the holders the team has put something in
        # control -> the fixtures it works (a knob's burner): fixed for a scene, so read once, before any filter
        self.controls = {o["objectId"]: tuple(o["controlledObjects"]) for o in self.objects
                         if o.get("controlledObjects")}
        # Target box -> the cells nearest first; the cells are fixed for a TeamWorld, so no ranking goes stale.
        self._ranked_cells: dict[tuple[float, float, float, float], list[tuple[float, float]]] = {}
        self.start = [self.position(m) for m in range(len(self.event.events))]
        self.focus = set(focus) if focus is not None else None
        if self.focus is not None:
            self._set_filter()

    # ---------------------------------------------------------------- filter

    def _set_filter(self) -> None:
        """Filter every agent's objects down to the focus; reads the full list from the current event."""
        ids = focus_ids(self.objects, self.focus or ())
        try:
            first = self.controller.step(action="SetObjectFilter", objectIds=ids, agentId=0)
        except ValueError:  # a build without the action: ai2thor raises on InvalidAction
            first = None
        if first is None or not first.events[0].metadata["lastActionSuccess"]:
            self.focus = None
            return
        self.event = first
        for member in range(1, len(self.event.events)):
            self._step(member, action="SetObjectFilter", objectIds=ids)

    def release(self) -> None:
        """Lift the filter, so that the latest event holds every object of the scene."""
        if self.focus is None:
            return
        for member in reversed(range(len(self.event.events))):
            self._step(member, action="ResetObjectFilter")
        self.focus = None

    def _refocus(self) -> None:
        """After objects appeared: read the full list through agent 0, then filter everyone again."""
        self._step(0, action="ResetObjectFilter")
        self._set_filter()

    # ------------------------------------------------------------------ state

    def _view(self, member: int) -> dict[str, Any]:
        return self.event.events[member].metadata

    @property
    def objects(self) -> list[dict[str, Any]]:
        return self.event.metadata["objects"]

    def position(self, member: int) -> tuple[float, float]:
        pos = self._view(member)["agent"]["position"]
        return pos["x"], pos["z"]

    def holding(self, member: int) -> dict[str, Any] | None:
        inventory = self._view(member).get("inventoryObjects") or []
        if not inventory:
            return None
        held_id = inventory[0]["objectId"]
        return next((o for o in self.objects if o["objectId"] == held_id), None)

    def hand_free(self, member: int) -> bool:
        return self.holding(member) is None and member not in self.helping

    def sees(self, member: int, object_id: str) -> bool:
        return any(o["objectId"] == object_id and o.get("visible") for o in self._view(member)["objects"])

    def _step(self, member: int, **action: Any) -> dict[str, Any]:
        self.event = self.controller.step(dict(action, agentId=member))
        return self._view(member)

    # -------------------------------------------------------------- resolving

    def _held_by_team(self, members: Sequence[int]) -> dict[str, int]:
        held = {}
        for m in members:
            obj = self.holding(m)
            if obj is not None:
                held[obj["objectId"]] = m
        return held

    def resolve(self, name: str, affordance: str, near: int, members: Sequence[int], *,
                going: bool = False, action: str = "") -> dict[str, Any] | None:
        """The instance a plan's object name means: among usable matches, one the ``action`` can change (a cabinet
        to open is a closed one), then for a fixture (what is not picked up) the one ``near`` last meant by its type,
        where it is going there or sees it, else the nearest to ``near``; "the stove burner" a robot switched on, or
        whose knob it switched, is the one it comes back to put the pot on, though another is nearer the sink it
        comes from (dev6-p1), "the cabinet" it opens by the spray bottle is the one by it, and "the cabinet" it opens
        by the pot the closed one holding it, not the one beside it the robot opened before (dev6-p1); a holder of
        the thing ``near`` last went to comes before the fixture meant before ("the cabinet" opened by the pan is the
        pan's, not the wall cabinet nearer the robot: dev6-c2); then one ready for another: the empty burner a
        switched-on knob heats, the knob of the burner the team put something in (the knob one robot switched and
        the burner another put the pot on did not match, and the pot stayed cold: dev6-p1)."""
        if "|" in name:
            return next((o for o in self.objects if o["objectId"] == name.strip()), None)
        wanted = name.strip().lower()
        ours = self._held_by_team(members)
        held_elsewhere = {
            o["objectId"] for i in range(len(self.event.events)) if i not in members
            for o in [self.holding(i)] if o is not None
        }

        def usable(o: dict[str, Any]) -> bool:
            return (
                not (o.get("isSliced") and o["objectType"] in SLICE_RESULTS)
                and o["objectId"] not in held_elsewhere
                and has_affordance(o, affordance)
            )

        matches = [o for o in self.objects if o["objectType"].lower() == wanted and usable(o)]
        if not matches:
            # "the apple" after slicing it: its pieces
            matches = [o for o in self.objects if base_type(o["objectType"]).lower() == wanted
                       and o["objectType"].lower() != wanted and usable(o)]
        if not matches:
            return None
        held = [o for o in matches if o["objectId"] in ours]
        if held:
            return held[0]
        x, z = self.position(near)
        shut = self._shut_away()
        # The fixture meant before counts where the robot is going to it or sees it (each asked once, not per match).
        before = {self.meant.get((near, o["objectType"])) for o in matches} - {None}
        meant = {i for i in before if going or self.sees(near, i)}
        changes = _CHANGES.get(action, lambda o: True)
        by_it = self._holders_of(self.gone_to.get(near))
        # Prefer instances the robots can get at (not in a closed fridge or drawer), then whole ones (a broken
        # one can be neither picked up nor broken again), then ones the action changes, then a holder of what the
        # robot went to, then the fixture meant before, then one ready for another, then the nearest.
        paired = self._paired(matches)
        chosen = min(matches, key=lambda o: (o["objectId"] in shut, bool(o.get("isBroken")), not changes(o),
                                             o["objectId"] not in by_it, o["objectId"] not in meant,
                                             o["objectId"] not in paired, round(Box.of(o).distance(x, z), 6),
                                             o["objectId"]))
        if not chosen.get("pickupable"):
            self.meant.update({(m, chosen["objectType"]): chosen["objectId"] for m in {near, *members}})
            for fixture in chosen.get("controlledObjects") or ():  # a knob means its burner too
                kind = next((o["objectType"] for o in self.objects if o["objectId"] == fixture), None)
                self.meant.update({(m, kind): fixture for m in {near, *members} if kind is not None})
        return chosen

    def _paired(self, matches: Sequence[dict[str, Any]]) -> set[str]:
        """Among ``matches``, fixtures ready for each other: an empty one a switched-on control works (a burner its
        knob heats), and a control whose fixture the team put something in (the knob of the burner the pot went on,
        not of the one a kettle stood on from the start). Read only where the matches take part in a control."""
        if len(matches) < 2:
            return set()
        ids = {o["objectId"] for o in matches}
        pairs = [(c, f) for c, fixtures in self.controls.items() for f in fixtures if c in ids or f in ids]
        if not pairs:
            return set()
        involved = {i for pair in pairs for i in pair}
        now = {o["objectId"]: o for o in self.objects if o["objectId"] in involved}
        paired = set()
        for control, fixture in ((now[c], now[f]) for c, f in pairs if c in now and f in now):
            if fixture["objectId"] in self.put_in and fixture.get("receptacleObjectIds"):
                paired.add(control["objectId"])
            elif control.get("isToggled") and not fixture.get("receptacleObjectIds"):
                paired.add(fixture["objectId"])
        return paired

    def _holders_of(self, object_id: str | None) -> set[str]:
        return next((set(o.get("parentReceptacles") or ()) for o in self.objects if o["objectId"] == object_id), set())

    def _shut_away(self) -> set[str]:
        closed = {o["objectId"] for o in self.objects
                  if o.get("openable") and o.get("receptacle") and not o.get("isOpen")
                  and o["objectType"] not in OPEN_TOPPED}
        return {o["objectId"] for o in self.objects if set(o.get("parentReceptacles") or ()) & closed}

    def _carried_mass(self, obj: dict[str, Any]) -> float:
        """Its mass and that of everything in it, nested contents included."""
        by_id = {o["objectId"]: o for o in self.objects}
        inside = linked(by_id, [obj["objectId"]], "receptacleObjectIds") - {obj["objectId"]}
        return float(obj.get("mass") or 0.0) + sum(float(by_id[i].get("mass") or 0.0) for i in sorted(inside))

    # ---------------------------------------------------------------- acting

    def perform_all(self, steps: Sequence[tuple[Skill, Sequence[str], Sequence[int]]]) -> list[Outcome]:
        """One tick's steps, one after another in launch order (a later step sees what earlier ones did), each
        with where its members and its object are after it."""
        outcomes = []
        for step in steps:
            outcome = self.perform(*step)
            outcome.positions = [self.position(m) for m in step[2]]
            found = next((o for o in self.objects if o["objectId"] == outcome.object_id), None)
            if found is not None:
                outcome.object_position = (found["position"]["x"], found["position"]["z"])
            outcomes.append(outcome)
        return outcomes

    @property
    def layout(self) -> dict[str, Any]:
        """The floor as the run saw it, for a map: the reachable cells, where each member started, and the
        fixed objects (furniture, appliances: what is not picked up) where the run left them."""
        return {"cells": [list(c) for c in self.cells], "start": [list(p) for p in self.start],
                "landmarks": [{"id": o["objectId"], "type": o["objectType"],
                               "x": o["position"]["x"], "z": o["position"]["z"]}
                              for o in self.objects if not o.get("pickupable")]}

    def perform(self, skill: Skill, objects: Sequence[str], members: Sequence[int]) -> Outcome:
        """Run one skill call by the team members ``members`` (team indices)."""
        names = ", ".join(self.team[m].name for m in members)
        if not any(skill.name in self.team[m].skills for m in members):
            return Outcome(False, f"{names} cannot {skill.name}: no member has that skill")
        if skill.action == "":
            return self._go_to(objects[0], members)
        if skill.action == "PickupObject":
            return self._pickup(skill, objects[0], members)
        if skill.action in RELEASE_ACTIONS:
            return self._release(skill, objects, members)
        return self._object_action(skill, objects[0], members)

    def _members_by_preference(self, skill: Skill, members: Sequence[int], condition) -> list[int]:
        ranked = sorted(members, key=lambda m: (not condition(m), skill.name not in self.team[m].skills))
        return [m for m in ranked if condition(m)] or []

    def _go_to(self, name: str, members: Sequence[int]) -> Outcome:
        target = self.resolve(name, "", members[0], members, going=True)
        if target is None:
            return Outcome(False, f"there is no {name!r} to go to", action="Teleport")
        if target["objectId"] in self._held_by_team(members):
            return Outcome(True, object_id=target["objectId"], action="Teleport")
        ranked = self._cells_nearest(Box.of(target))
        chosen: set[tuple[float, float]] = set()
        for member in members:
            others = {self.position(i) for i in range(len(self.event.events)) if i != member}
            cell = next((c for c in ranked if c not in others and c not in chosen), None)
            if cell is None:
                return Outcome(False, f"no free place near {target['objectId']}", target["objectId"], "Teleport",
                               member)
            chosen.add(cell)
            yaw = facing_yaw(cell[0], cell[1], target["position"]["x"], target["position"]["z"])
            view = self._step(member, action="Teleport", position={"x": cell[0], "y": self.cell_y, "z": cell[1]},
                              rotation={"x": 0.0, "y": yaw, "z": 0.0}, horizon=30.0, standing=True)
            if not view["lastActionSuccess"]:
                return Outcome(False, view["errorMessage"], target["objectId"], "Teleport", member)
        self.gone_to.update((member, target["objectId"]) for member in members)
        return Outcome(True, object_id=target["objectId"], action="Teleport")

    def _cells_nearest(self, box: Box) -> list[tuple[float, float]]:
        """The reachable cells nearest to ``box`` first (ties by cell), ranked once per box rather than
        scanned once per member and call: GoToObject's first free cell in this order is its nearest free one."""
        key = (box.x0, box.x1, box.z0, box.z1)
        ranked = self._ranked_cells.get(key)
        if ranked is None:
            ranked = self._ranked_cells[key] = sorted(self.cells, key=lambda c: (round(box.distance(*c), 6), c))
        return ranked

    def _pickup(self, skill: Skill, name: str, members: Sequence[int]) -> Outcome:
        free = self._members_by_preference(skill, members, self.hand_free)
        if not free:
            return Outcome(False, "every robot of the team already has its hands full", action=skill.action)
        actor = free[0]
        target = self.resolve(name, skill.arguments[0], actor, members)
        if target is None:
            return Outcome(False, f"there is no pickupable {name!r} free to pick up", action=skill.action, actor=actor)
        if target["objectId"] in self._shut_away():
            # Say so, rather than that the teammates (who cannot see it either) are out of reach.
            return Outcome(False, f"{target['objectId']} is inside a closed receptacle; open it first",
                           target["objectId"], skill.action, actor)
        mass = self._carried_mass(target)
        lifters = [actor]
        capacity = self.team[actor].mass_capacity
        for m in members:
            if capacity + _MASS_TOLERANCE >= mass:
                break
            if m != actor and self.hand_free(m) and self.sees(m, target["objectId"]):
                lifters.append(m)
                capacity += self.team[m].mass_capacity
        if capacity + _MASS_TOLERANCE < mass:
            who = ", ".join(self.team[m].name for m in lifters)
            return Outcome(False, f"{target['objectId']} weighs {mass:.3g} kg, more than {who} can lift "
                                  f"({capacity:.3g} kg); bring more robots within reach", target["objectId"],
                           skill.action, actor)
        view = self._step(actor, action=skill.action, objectId=target["objectId"])
        if not view["lastActionSuccess"]:
            return Outcome(False, view["errorMessage"], target["objectId"], skill.action, actor)
        for helper in lifters[1:]:
            self.helping[helper] = target["objectId"]
        return Outcome(True, object_id=target["objectId"], action=skill.action, actor=actor)

    def _release(self, skill: Skill, objects: Sequence[str], members: Sequence[int]) -> Outcome:
        wanted = objects[0].strip().lower()
        holder = None
        for m in members:
            held = self.holding(m)
            if held is not None and (held["objectId"] == objects[0].strip() or wanted in
                                     (held["objectType"].lower(), base_type(held["objectType"]).lower())):
                holder = m
                break
        if holder is None:
            names = ", ".join(self.team[m].name for m in members)
            return Outcome(False, f"{names} do not hold a {objects[0]!r}", action=skill.action)
        held_id = self.holding(holder)["objectId"]  # type: ignore[index]
        args: dict[str, Any] = {}
        target_id = None
        if skill.action == "PutObject" or (skill.action == "ThrowObject" and len(objects) > 1):
            receptacle = self.resolve(objects[1], "receptacle", holder, members)
            if receptacle is None or receptacle["objectId"] == held_id:
                return Outcome(False, f"there is no receptacle {objects[1]!r} here", held_id, skill.action, holder)
            target_id = receptacle["objectId"]
            if skill.action == "PutObject":
                args["objectId"] = target_id
            else:
                x, z = self.position(holder)
                yaw = facing_yaw(x, z, receptacle["position"]["x"], receptacle["position"]["z"])
                self._step(holder, action="Teleport", position={"x": x, "y": self.cell_y, "z": z},
                           rotation={"x": 0.0, "y": yaw, "z": 0.0})
                distance = math.hypot(receptacle["position"]["x"] - x, receptacle["position"]["z"] - z)
                args["moveMagnitude"] = max(5.0, min(30.0, 10.0 * distance))
        elif skill.action == "ThrowObject":
            args["moveMagnitude"] = 7.0
        view = self._step(holder, action=skill.action, **args)
        if not view["lastActionSuccess"]:
            return Outcome(False, view["errorMessage"], target_id or held_id, skill.action, holder)
        for member, carried in list(self.helping.items()):
            if carried == held_id:
                del self.helping[member]
        if target_id is not None:
            self.put_in |= {target_id}
        return Outcome(True, object_id=target_id or held_id, action=skill.action, actor=holder)

    def _object_action(self, skill: Skill, name: str, members: Sequence[int]) -> Outcome:
        if skill.action == "SliceObject":
            def ready(m: int) -> bool:
                held = self.holding(m)
                return held is not None and held["objectType"] in KNIVES
        else:
            def ready(m: int) -> bool:
                return True
        candidates = self._members_by_preference(skill, members, ready) or list(members)
        actor = candidates[0]
        affordance = skill.arguments[0]
        target = self.resolve(name, affordance, actor, members, action=skill.action)
        if target is None and affordance == "toggleable":
            target = self._switch_for(name, actor, members)
        if target is None:
            need = f"{affordance} " if affordance else ""
            return Outcome(False, f"there is no {need}{name!r} to {skill.name}", action=skill.action, actor=actor)
        if not ready(actor):  # only slicing has a precondition here: no member holds a knife
            names = ", ".join(self.team[m].name for m in members)
            return Outcome(False, f"SliceObject needs a Knife or ButterKnife in hand, and none is held by {names}",
                           target["objectId"], skill.action, actor)
        view = self._step(actor, action=skill.action, objectId=target["objectId"])
        if not view["lastActionSuccess"]:
            return Outcome(False, view["errorMessage"], target["objectId"], skill.action, actor)
        if skill.action in CREATING_ACTIONS and self.focus is not None:
            self._refocus()
        return Outcome(True, object_id=target["objectId"], action=skill.action, actor=actor)

    def _switch_for(self, name: str, actor: int, members: Sequence[int]) -> dict[str, Any] | None:
        """A StoveBurner is switched through the StoveKnob that controls it."""
        target = self.resolve(name, "", actor, members)
        if target is None:
            return None
        return next((o for o in self.objects if target["objectId"] in (o.get("controlledObjects") or [])
                     and o.get("toggleable")), None)
