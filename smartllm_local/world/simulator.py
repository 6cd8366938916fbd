"""A symbolic AI2-THOR scene: the objects, the agents, and what actions do to them.

The simulator knows nothing of pipes or the Controller; :mod:`.thor_server`
serves it over AI2-THOR's protocol. Every action returns an
:class:`ActionResult`; a failed action is a result with ``success=False`` and
an AI2-THOR-style message, never an exception. Arguments the action cannot do
without, or an action AI2-THOR does not have, come back with the error codes
(``MissingArguments``, ``InvalidAction``) on which the real Controller raises,
as it does with a Unity build.
"""

from __future__ import annotations

import copy
import itertools
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from . import rules
from .navigation import Box, ReachableGrid
from .object_types import OPEN_TOPPED, SLICE_RESULTS
from .scenes import floor_plan_name, load_scene

DEFAULT_VISIBILITY_DISTANCE = 1.5
_HORIZON_LIMITS = (-30.0, 60.0)

# One clock for every version number, so that a version identifies a state across
# resets: version 0 is always the object as the scene data has it.
_clock = itertools.count(1)
_grids: dict[tuple[str, float], ReachableGrid] = {}


class ActionFailed(Exception):
    """Raised inside an action handler; turned into a failed :class:`ActionResult`."""

    def __init__(self, message: str, code: str = ""):
        super().__init__(message)
        self.message = message
        self.code = code


@dataclass
class ActionResult:
    success: bool = True
    error_message: str = ""
    error_code: str = ""
    action_return: Any = None


@dataclass
class Agent:
    x: float
    y: float
    z: float
    yaw: float = 0.0
    horizon: float = 0.0
    standing: bool = True
    held: str | None = None
    # AI2-THOR's SetObjectFilter: the objectIds this agent's metadata reports (None: all).
    object_filter: frozenset[str] | None = None
    # Changes whenever the agent's position does: what it can reach depends on nothing else.
    version: int = field(default_factory=lambda: next(_clock))

    def moved(self) -> None:
        self.version = next(_clock)


@dataclass
class Simulator:
    """One scene with ``agent_count`` agents, following AI2-THOR's object semantics."""

    floor_plan: str
    agent_count: int = 1
    visibility_distance: float = DEFAULT_VISIBILITY_DISTANCE
    grid_size: float = 0.25
    objects: dict[str, dict[str, Any]] = field(init=False)
    agents: list[Agent] = field(init=False)
    versions: dict[str, int] = field(init=False)

    def __post_init__(self) -> None:
        self.scene_name = floor_plan_name(self.floor_plan)
        loaded = load_scene(self.scene_name)
        for obj in loaded:
            obj["isPickedUp"] = False
            obj.setdefault("isInteractable", True)
        self.objects = {obj["objectId"]: obj for obj in loaded}
        self.versions = {oid: 0 for oid in self.objects}
        self.generation = 0  # counts object changes; unchanged means every object is as it was
        key = (self.scene_name, self.grid_size)
        if key not in _grids:
            _grids[key] = ReachableGrid(loaded, self.grid_size)
        self.grid = _grids[key]
        self.agents = self._start_agents(self.agent_count)
        self._handlers: dict[str, Callable[[int, dict[str, Any]], ActionResult]] = {
            "GetReachablePositions": self._get_reachable_positions,
            "Teleport": self._teleport,
            "TeleportFull": self._teleport,
            "MoveAhead": lambda a, act: self._move(a, act, 0.0),
            "MoveRight": lambda a, act: self._move(a, act, 90.0),
            "MoveBack": lambda a, act: self._move(a, act, 180.0),
            "MoveLeft": lambda a, act: self._move(a, act, 270.0),
            "RotateRight": lambda a, act: self._rotate(a, act, 1.0),
            "RotateLeft": lambda a, act: self._rotate(a, act, -1.0),
            "LookUp": lambda a, act: self._look(a, act, -1.0),
            "LookDown": lambda a, act: self._look(a, act, 1.0),
            "Stand": lambda a, act: self._stand(a, True),
            "Crouch": lambda a, act: self._stand(a, False),
            "Done": self._noop,
            "Pass": self._noop,
            "SetObjectFilter": self._set_object_filter,
            "ResetObjectFilter": self._reset_object_filter,
            "PickupObject": self._pickup,
            "PutObject": self._put,
            "DropHandObject": self._drop,
            "ThrowObject": self._throw,
            "OpenObject": lambda a, act: self._open(a, act, True),
            "CloseObject": lambda a, act: self._open(a, act, False),
            "ToggleObjectOn": lambda a, act: self._toggle(a, act, True),
            "ToggleObjectOff": lambda a, act: self._toggle(a, act, False),
            "SliceObject": self._slice,
            "BreakObject": self._break,
            "CleanObject": lambda a, act: self._dirty(a, act, False),
            "DirtyObject": lambda a, act: self._dirty(a, act, True),
            "PushObject": lambda a, act: self._push(a, act, 1.0),
            "PullObject": lambda a, act: self._push(a, act, -1.0),
        }

    # ------------------------------------------------------------------ public

    def step(self, agent_id: int, action: dict[str, Any]) -> ActionResult:
        """Run one action for one agent."""
        name = action.get("action")
        handler = self._handlers.get(name) if isinstance(name, str) else None
        if handler is None:
            return ActionResult(False, f"Invalid action: {name!r} is not an action this AI2-THOR stand-in knows",
                                "InvalidAction")
        if not 0 <= agent_id < len(self.agents):
            return ActionResult(False, f"Invalid agentId {agent_id}: the scene has {len(self.agents)} agent(s)",
                                "InvalidArgument")
        try:
            result = handler(agent_id, action)
        except ActionFailed as failure:
            return ActionResult(False, failure.message, failure.code)
        rules.apply_contextual_effects(self.objects, self.touch)
        return result

    def touch(self, object_id: str) -> None:
        """Record that an object's metadata changed."""
        self.versions[object_id] = next(_clock)
        self.generation += 1

    def reach(self, agent_id: int, obj: dict[str, Any]) -> float:
        """Horizontal distance from an agent to the nearest point of an object's box."""
        agent = self.agents[agent_id]
        return Box.of(obj).distance(agent.x, agent.z)

    def is_enclosed(self, obj: dict[str, Any]) -> bool:
        """True when the object sits inside a closed openable receptacle (a shut fridge, drawer...)."""
        for parent_id in obj.get("parentReceptacles") or []:
            parent = self.objects.get(parent_id)
            if parent and parent.get("openable") and not parent.get("isOpen") \
                    and parent["objectType"] not in OPEN_TOPPED:
                return True
            if parent and parent.get("parentReceptacles") and self.is_enclosed(parent):
                return True
        return False

    def is_visible(self, agent_id: int, obj: dict[str, Any]) -> bool:
        """Whether an agent can see (and so act on) an object: in range, not shut away, not in another's hand."""
        if obj.get("isSliced") and obj["objectType"] in SLICE_RESULTS:
            return False
        if obj.get("isPickedUp"):
            return self.agents[agent_id].held == obj["objectId"]
        return self.reach(agent_id, obj) <= self.visibility_distance and not self.is_enclosed(obj)

    # -------------------------------------------------------------- agents

    def _start_agents(self, count: int) -> list[Agent]:
        """Agents start on distinct cells, spread from the cell nearest the floor's centre."""
        if count < 1:
            raise ValueError("agentCount must be at least 1")
        if count > len(self.grid.cells):
            raise ValueError(f"agentCount {count} exceeds the {len(self.grid.cells)} free cells of {self.scene_name}")
        cx = sum(x for x, _ in self.grid.cells) / len(self.grid.cells)
        cz = sum(z for _, z in self.grid.cells) / len(self.grid.cells)
        ranked = sorted(self.grid.cells, key=lambda c: (round(math.hypot(c[0] - cx, c[1] - cz), 6), c))
        chosen: list[tuple[float, float]] = []
        for cell in ranked:
            if all(math.hypot(cell[0] - o[0], cell[1] - o[1]) >= 0.5 for o in chosen):
                chosen.append(cell)
            if len(chosen) == count:
                break
        for cell in ranked:
            if len(chosen) == count:
                break
            if cell not in chosen:
                chosen.append(cell)
        return [Agent(x, self.grid.y, z) for x, z in chosen]

    def _occupied(self, except_agent: int) -> set[tuple[float, float]]:
        return {(a.x, a.z) for i, a in enumerate(self.agents) if i != except_agent}

    def _place_agent(self, agent_id: int, x: float, z: float) -> None:
        agent = self.agents[agent_id]
        if (agent.x, agent.z) != (x, z):
            agent.x, agent.z = x, z
            agent.moved()
        if agent.held:
            self._carry(agent_id)

    def _carry(self, agent_id: int) -> None:
        """Move the held object (and what it holds) to the agent's hand."""
        agent = self.agents[agent_id]
        held = self.objects[agent.held] if agent.held else None
        if held is None:
            return
        yaw = math.radians(agent.yaw)
        hand = {"x": agent.x + 0.3 * math.sin(yaw), "y": agent.y, "z": agent.z + 0.3 * math.cos(yaw)}
        self._move_object(held, hand)

    def _move_object(self, obj: dict[str, Any], target: dict[str, float]) -> None:
        dx = target["x"] - obj["position"]["x"]
        dy = target["y"] - obj["position"]["y"]
        dz = target["z"] - obj["position"]["z"]
        for moved in [obj, *rules.contents(self.objects, obj["objectId"])]:
            pos = moved["position"]
            moved["position"] = {"x": pos["x"] + dx, "y": pos["y"] + dy, "z": pos["z"] + dz}
            box = moved.get("axisAlignedBoundingBox")
            if box:
                c = box["center"]
                box["center"] = {"x": c["x"] + dx, "y": c["y"] + dy, "z": c["z"] + dz}
                box["cornerPoints"] = [[p[0] + dx, p[1] + dy, p[2] + dz] for p in box.get("cornerPoints") or []]
            moved["objectOrientedBoundingBox"] = None
            self.touch(moved["objectId"])

    def _get_reachable_positions(self, agent_id: int, action: dict[str, Any]) -> ActionResult:
        return ActionResult(action_return=self.grid.positions())

    def _teleport(self, agent_id: int, action: dict[str, Any]) -> ActionResult:
        agent = self.agents[agent_id]
        pos = action.get("position")
        if pos is None and all(k in action for k in ("x", "z")):
            pos = {"x": action["x"], "y": action.get("y", agent.y), "z": action["z"]}
        if pos is None:
            pos = {"x": agent.x, "y": agent.y, "z": agent.z}
        try:
            x, z = float(pos["x"]), float(pos["z"])
        except (KeyError, TypeError, ValueError) as exc:
            raise ActionFailed(f"Teleport position must have numeric x and z, got {pos!r}", "InvalidArgument") from exc
        cell = self.grid.snap(x, z)
        if cell is None and not action.get("forceAction"):
            raise ActionFailed(f"Teleport failed: ({x:.2f}, {z:.2f}) is not a reachable position in {self.scene_name}")
        target = cell or (round(x, 4), round(z, 4))
        if target in self._occupied(agent_id):
            raise ActionFailed(f"Teleport failed: another agent stands at ({target[0]:.2f}, {target[1]:.2f})")
        rotation = action.get("rotation")
        if isinstance(rotation, dict):
            agent.yaw = float(rotation.get("y", agent.yaw)) % 360.0
        elif isinstance(rotation, (int, float)):
            agent.yaw = float(rotation) % 360.0
        if isinstance(action.get("horizon"), (int, float)):
            agent.horizon = float(action["horizon"])
        if isinstance(action.get("standing"), bool):
            agent.standing = action["standing"]
        self._place_agent(agent_id, *target)
        return ActionResult()

    def _move(self, agent_id: int, action: dict[str, Any], offset: float) -> ActionResult:
        agent = self.agents[agent_id]
        step = float(action.get("moveMagnitude") or self.grid_size)
        heading = math.radians(agent.yaw + offset)
        x, z = agent.x + step * math.sin(heading), agent.z + step * math.cos(heading)
        cell = self.grid.snap(x, z)
        if cell is None or cell in self._occupied(agent_id):
            raise ActionFailed(f"{action['action']} failed: the way is blocked")
        self._place_agent(agent_id, *cell)
        return ActionResult()

    def _rotate(self, agent_id: int, action: dict[str, Any], sign: float) -> ActionResult:
        agent = self.agents[agent_id]
        agent.yaw = (agent.yaw + sign * float(action.get("degrees", 90.0))) % 360.0
        if agent.held:
            self._carry(agent_id)
        return ActionResult()

    def _look(self, agent_id: int, action: dict[str, Any], sign: float) -> ActionResult:
        agent = self.agents[agent_id]
        horizon = agent.horizon + sign * float(action.get("degrees", 30.0))
        if not _HORIZON_LIMITS[0] <= horizon <= _HORIZON_LIMITS[1]:
            raise ActionFailed(f"{action['action']} failed: the camera horizon must stay within {_HORIZON_LIMITS}")
        agent.horizon = horizon
        return ActionResult()

    def _stand(self, agent_id: int, standing: bool) -> ActionResult:
        agent = self.agents[agent_id]
        if agent.standing == standing:
            raise ActionFailed("The agent is already " + ("standing" if standing else "crouching"))
        agent.standing = standing
        return ActionResult()

    def _noop(self, agent_id: int, action: dict[str, Any]) -> ActionResult:
        return ActionResult()

    def _set_object_filter(self, agent_id: int, action: dict[str, Any]) -> ActionResult:
        """Report only these objects in this agent's metadata, as AI2-THOR's ProcTHOR-era speed-up does.

        Ids of no object in the scene are ignored, and objects created later (slices) stay out
        until the filter is set again."""
        if "objectIds" not in action:
            raise ActionFailed("SetObjectFilter requires objectIds", "MissingArguments")
        ids = action["objectIds"]
        if not isinstance(ids, list) or not all(isinstance(i, str) for i in ids):
            raise ActionFailed(f"SetObjectFilter: objectIds must be a list of strings, got {ids!r}", "InvalidArgument")
        self.agents[agent_id].object_filter = frozenset(i for i in ids if i in self.objects)
        return ActionResult()

    def _reset_object_filter(self, agent_id: int, action: dict[str, Any]) -> ActionResult:
        self.agents[agent_id].object_filter = None
        return ActionResult()

    def reported_objects(self, agent_id: int) -> list[str]:
        """The objectIds an agent's metadata carries, in scene order."""
        kept = self.agents[agent_id].object_filter
        return list(self.objects) if kept is None else [oid for oid in self.objects if oid in kept]

    # ------------------------------------------------------------- objects

    def _target(self, agent_id: int, action: dict[str, Any], *, key: str = "objectId") -> dict[str, Any]:
        """Look up the object an action names and check the agent can act on it."""
        if key not in action:
            raise ActionFailed(f"{action['action']} requires {key}", "MissingArguments")
        object_id = action[key]
        obj = self.objects.get(object_id) if isinstance(object_id, str) else None
        if obj is None:
            raise ActionFailed(f"Object ID appears to be invalid: {object_id!r} is not in {self.scene_name}")
        if obj.get("isSliced") and obj["objectType"] in SLICE_RESULTS:
            raise ActionFailed(f"{object_id} has been sliced; act on its pieces instead")
        if obj.get("isPickedUp") and self.agents[agent_id].held != object_id:
            raise ActionFailed(f"{object_id} is held by another agent")
        if self.is_enclosed(obj):
            raise ActionFailed(f"{object_id} is inside a closed receptacle; open it first")
        if not action.get("forceAction") and not obj.get("isPickedUp"):
            distance = self.reach(agent_id, obj)
            if distance > self.visibility_distance:
                raise ActionFailed(
                    f"{object_id} is not visible: it is {distance:.2f} m away, beyond the "
                    f"visibilityDistance of {self.visibility_distance} m"
                )
        return obj

    def _require(self, obj: dict[str, Any], prop: str, verb: str) -> None:
        if not obj.get(prop):
            raise ActionFailed(f"{obj['objectId']} is not {verb}")

    def _detach(self, obj: dict[str, Any]) -> None:
        for parent_id in obj.get("parentReceptacles") or []:
            parent = self.objects.get(parent_id)
            if parent and obj["objectId"] in (parent.get("receptacleObjectIds") or []):
                parent["receptacleObjectIds"] = [i for i in parent["receptacleObjectIds"] if i != obj["objectId"]]
                self.touch(parent_id)
        obj["parentReceptacles"] = None
        self.touch(obj["objectId"])

    def _attach(self, obj: dict[str, Any], receptacle: dict[str, Any], position: dict[str, float]) -> None:
        self._move_object(obj, position)
        obj["parentReceptacles"] = [receptacle["objectId"]]
        ids = list(receptacle.get("receptacleObjectIds") or [])
        ids.append(obj["objectId"])
        receptacle["receptacleObjectIds"] = ids
        self.touch(receptacle["objectId"])
        self.touch(obj["objectId"])

    def _held(self, agent_id: int, action_name: str) -> dict[str, Any]:
        agent = self.agents[agent_id]
        if agent.held is None:
            raise ActionFailed(f"{action_name} failed: the agent is not holding any object")
        return self.objects[agent.held]

    def _release(self, agent_id: int, held: dict[str, Any]) -> None:
        held["isPickedUp"] = False
        self.agents[agent_id].held = None
        self.touch(held["objectId"])

    def _pickup(self, agent_id: int, action: dict[str, Any]) -> ActionResult:
        agent = self.agents[agent_id]
        obj = self._target(agent_id, action)
        self._require(obj, "pickupable", "pickupable")
        if agent.held == obj["objectId"]:
            raise ActionFailed(f"{obj['objectId']} is already in the agent's hand")
        if agent.held is not None:
            raise ActionFailed(f"Agent hand is full: it already holds {agent.held} (one object at a time)")
        if obj.get("isBroken"):
            raise ActionFailed(f"{obj['objectId']} is broken and cannot be picked up")
        self._detach(obj)
        obj["isPickedUp"] = True
        agent.held = obj["objectId"]
        self._carry(agent_id)
        return ActionResult()

    def _put(self, agent_id: int, action: dict[str, Any]) -> ActionResult:
        held = self._held(agent_id, "PutObject")
        receptacle = self._target(agent_id, action)
        if receptacle["objectId"] == held["objectId"] or receptacle in rules.contents(self.objects, held["objectId"]):
            raise ActionFailed(f"cannot put {held['objectId']} into itself")
        self._require(receptacle, "receptacle", "a receptacle")
        if receptacle.get("openable") and not receptacle.get("isOpen"):
            raise ActionFailed(f"{receptacle['objectId']} is closed; open it before putting anything in")
        reason = rules.refuses(held, receptacle)
        if reason:
            raise ActionFailed(f"No valid positions to place object found: {reason}")
        self._release(agent_id, held)
        box = Box.of(receptacle)
        surface = {"x": (box.x0 + box.x1) / 2, "y": box.y1 if not receptacle.get("openable") else (box.y0 + box.y1) / 2,
                   "z": (box.z0 + box.z1) / 2}
        self._attach(held, receptacle, surface)
        return ActionResult()

    def _land(self, agent_id: int, obj: dict[str, Any], distance: float) -> None:
        """Let a released object come down along the agent's heading: into the first receptacle
        under its path that takes it, else onto the floor at the end of the path."""
        agent = self.agents[agent_id]
        yaw = math.radians(agent.yaw)
        excluded = {obj["objectId"], *(o["objectId"] for o in rules.contents(self.objects, obj["objectId"]))}
        floor = next(o for o in self.objects.values() if o["objectType"] == "Floor")
        steps = max(1, int(distance / 0.05))
        for i in range(1, steps + 1):
            d = distance * i / steps
            x, z = agent.x + d * math.sin(yaw), agent.z + d * math.cos(yaw)
            candidates = [
                r for r in self.objects.values()
                if r.get("receptacle") and r["objectType"] != "Floor" and r["objectId"] not in excluded
                and not r.get("isPickedUp") and not (r.get("isSliced") and r["objectType"] in SLICE_RESULTS)
                and not (r.get("openable") and not r.get("isOpen")) and Box.of(r).covers(x, z, 0.0)
                and rules.refuses(obj, r) is None and not self.is_enclosed(r)
            ]
            if candidates:
                top = max(candidates, key=lambda r: (Box.of(r).y1, r["objectId"]))
                b = Box.of(top)
                self._attach(obj, top, {"x": x, "y": b.y1, "z": z})
                return
        x, z = agent.x + distance * math.sin(yaw), agent.z + distance * math.cos(yaw)
        self._attach(obj, floor, {"x": x, "y": Box.of(floor).y1, "z": z})

    def _drop(self, agent_id: int, action: dict[str, Any]) -> ActionResult:
        held = self._held(agent_id, "DropHandObject")
        self._release(agent_id, held)
        self._land(agent_id, held, 0.6)
        return ActionResult()

    def _throw(self, agent_id: int, action: dict[str, Any]) -> ActionResult:
        held = self._held(agent_id, "ThrowObject")
        magnitude = float(action.get("moveMagnitude") or 10.0)
        self._release(agent_id, held)
        self._land(agent_id, held, min(0.6 + 0.1 * magnitude, 3.0))
        return ActionResult()

    def _open(self, agent_id: int, action: dict[str, Any], opening: bool) -> ActionResult:
        obj = self._target(agent_id, action)
        self._require(obj, "openable", "openable")
        if bool(obj.get("isOpen")) == opening:
            raise ActionFailed(f"{obj['objectId']} is already {'open' if opening else 'closed'}")
        obj["isOpen"] = opening
        obj["openness"] = float(action.get("openness", 1.0)) if opening else 0.0
        if opening and obj["objectType"] == "Microwave" and obj.get("isToggled"):
            obj["isToggled"] = False  # opening the door stops a running microwave
        self.touch(obj["objectId"])
        for inside in rules.contents(self.objects, obj["objectId"]):
            self.touch(inside["objectId"])
        return ActionResult()

    def _toggle(self, agent_id: int, action: dict[str, Any], on: bool) -> ActionResult:
        obj = self._target(agent_id, action)
        self._require(obj, "toggleable", "toggleable")
        if bool(obj.get("isToggled")) == on:
            raise ActionFailed(f"{obj['objectId']} is already {'on' if on else 'off'}")
        if on and obj["objectType"] == "Microwave" and obj.get("isOpen"):
            raise ActionFailed(f"{obj['objectId']} cannot be switched on while its door is open")
        obj["isToggled"] = on
        self.touch(obj["objectId"])
        for burner_id in obj.get("controlledObjects") or []:
            burner = self.objects.get(burner_id)
            if burner is not None:
                burner["isToggled"] = rules.is_heating(self.objects, burner)
                self.touch(burner_id)
        return ActionResult()

    def _cut(self, obj: dict[str, Any], flag: str) -> None:
        """Replace a sliced or cracked object by its pieces, where they lay."""
        parents = list(obj.get("parentReceptacles") or [])
        obj[flag] = True
        pieces = rules.make_pieces(obj) if obj["objectType"] in SLICE_RESULTS else []
        if pieces:
            self._detach(obj)
            obj["isInteractable"] = False
        for piece in pieces:
            piece = copy.deepcopy(piece)
            self.objects[piece["objectId"]] = piece
            piece["parentReceptacles"] = parents or None
            # A version of its own: version 0 means "as the scene data has it", and the encoder may
            # still hold a piece cut elsewhere (before a reset) at that version.
            self.touch(piece["objectId"])
            for parent_id in parents:
                parent = self.objects[parent_id]
                parent["receptacleObjectIds"] = [*(parent.get("receptacleObjectIds") or []), piece["objectId"]]
                self.touch(parent_id)
        self.touch(obj["objectId"])

    def _slice(self, agent_id: int, action: dict[str, Any]) -> ActionResult:
        """Slice what is not in a hand; as in Unity's SliceObject, what the agent holds is not checked.

        Needing a knife is the robots' rule, enforced by the executor's SliceObject skill.
        """
        obj = self._target(agent_id, action)
        self._require(obj, "sliceable", "sliceable")
        if obj.get("isSliced"):
            raise ActionFailed(f"{obj['objectId']} is already sliced")
        if obj.get("isPickedUp"):
            raise ActionFailed(f"{obj['objectId']} must be put down before it is sliced")
        self._cut(obj, "isSliced")
        return ActionResult()

    def _break(self, agent_id: int, action: dict[str, Any]) -> ActionResult:
        obj = self._target(agent_id, action)
        self._require(obj, "breakable", "breakable")
        if obj.get("isBroken"):
            raise ActionFailed(f"{obj['objectId']} is already broken")
        if obj.get("isPickedUp"):
            raise ActionFailed(f"{obj['objectId']} must be put down before it is broken")
        obj["isFilledWithLiquid"] = False
        obj["fillLiquid"] = None
        if obj["objectType"] == "Egg":
            self._cut(obj, "isBroken")
        else:
            obj["isBroken"] = True
            self.touch(obj["objectId"])
        return ActionResult()

    def _dirty(self, agent_id: int, action: dict[str, Any], dirty: bool) -> ActionResult:
        obj = self._target(agent_id, action)
        self._require(obj, "dirtyable", "dirtyable")
        if bool(obj.get("isDirty")) == dirty:
            raise ActionFailed(f"{obj['objectId']} is already {'dirty' if dirty else 'clean'}")
        obj["isDirty"] = dirty
        self.touch(obj["objectId"])
        return ActionResult()

    def _push(self, agent_id: int, action: dict[str, Any], sign: float) -> ActionResult:
        obj = self._target(agent_id, action)
        if not (obj.get("moveable") or obj.get("pickupable")):
            raise ActionFailed(f"{obj['objectId']} is neither moveable nor pickupable")
        if obj.get("isPickedUp"):
            raise ActionFailed(f"{obj['objectId']} is in the agent's hand; put it down first")
        agent = self.agents[agent_id]
        shift = sign * min(0.05 * float(action.get("moveMagnitude") or 5.0), 0.5)
        yaw = math.radians(agent.yaw)
        pos = obj["position"]
        self._move_object(obj, {"x": pos["x"] + shift * math.sin(yaw), "y": pos["y"],
                                "z": pos["z"] + shift * math.cos(yaw)})
        return ActionResult()

