"""AI2-THOR event metadata for the stand-in, packed the way the Controller reads it.

Unity sends, for every agent, the full object list with the per-agent fields
``distance``, ``visible`` and ``isInteractable``. Packing that naively costs
more than the simulation itself, so each object's agent-independent part is
packed once per object version and each agent's part once per (agent pose,
object version); a step then only joins cached bytes. The result is the same
msgpack a plain ``msgpack.packb`` of the metadata dict would give.
"""

from __future__ import annotations

import math
import struct
from typing import Any

import msgpack

from .simulator import ActionResult, Simulator

#: The fields of an object that differ from agent to agent (the rest is the object's own).
AGENT_FIELDS = ("distance", "visible", "isInteractable")
_pack = msgpack.Packer(use_bin_type=True).pack
# The per-agent fields packed by hand (they are packed for every object at every move):
# "distance" as a float64, then "visible" and "isInteractable", which are equal.
_FLOAT = struct.Struct(">Bd")
_TAIL_KEYS = (_pack("distance"), _pack("visible"))
_TRUE_TWICE = _pack(True) + _pack("isInteractable") + _pack(True)
_FALSE_TWICE = _pack(False) + _pack("isInteractable") + _pack(False)


def _map_header(n: int) -> bytes:
    return bytes([0x80 | n]) if n < 16 else b"\xde" + struct.pack(">H", n)


def _array_header(n: int) -> bytes:
    if n < 16:
        return bytes([0x90 | n])
    return b"\xdc" + struct.pack(">H", n) if n < 65536 else b"\xdd" + struct.pack(">I", n)


def _pack_items(d: dict[str, Any]) -> bytes:
    return b"".join(_pack(k) + _pack(v) for k, v in d.items())


def agent_view(sim: Simulator, agent_id: int, obj: dict[str, Any]) -> tuple[float, bool]:
    """An object's per-agent fields: its ``distance`` from the agent, and whether it is ``visible``
    to it (AI2-THOR's ``isInteractable`` says the same here)."""
    agent = sim.agents[agent_id]
    pos = obj["position"]
    distance = math.sqrt((pos["x"] - agent.x) ** 2 + (pos["y"] - agent.y) ** 2 + (pos["z"] - agent.z) ** 2)
    return distance, sim.is_visible(agent_id, obj)


class MetadataEncoder:
    """Packs a :class:`Simulator`'s state as AI2-THOR's multi-agent metadata."""

    def __init__(self, width: int = 300, height: int = 300):
        self.width = width
        self.height = height
        self._scene: str | None = None
        self._base: dict[str, tuple[int, bytes, int]] = {}
        self._tail: dict[tuple[int, str], tuple[int, int, bytes]] = {}
        self.last_results: list[tuple[str, ActionResult]] = []

    def reset_agents(self, count: int) -> None:
        self.last_results = [("", ActionResult()) for _ in range(count)]

    def _object_base(self, sim: Simulator, oid: str) -> tuple[bytes, int]:
        version = sim.versions.get(oid, 0)
        cached = self._base.get(oid)
        if cached is None or cached[0] != version:
            obj = {k: v for k, v in sim.objects[oid].items() if k not in AGENT_FIELDS}
            cached = (version, _pack_items(obj), len(obj))
            self._base[oid] = cached
        return cached[1], cached[2]

    def _object_tail(self, sim: Simulator, agent_id: int, oid: str) -> bytes:
        agent = sim.agents[agent_id]
        version = sim.versions.get(oid, 0)
        key = (agent_id, oid)
        cached = self._tail.get(key)
        if cached is None or cached[0] != agent.version or cached[1] != version:
            distance, visible = agent_view(sim, agent_id, sim.objects[oid])
            tail = _TAIL_KEYS[0] + _FLOAT.pack(0xCB, distance) + _TAIL_KEYS[1] \
                + (_TRUE_TWICE if visible else _FALSE_TWICE)
            cached = (agent.version, version, tail)
            self._tail[key] = cached
        return cached[2]

    def _objects(self, sim: Simulator, agent_id: int) -> bytes:
        reported = sim.reported_objects(agent_id)
        parts = [_array_header(len(reported))]
        for oid in reported:
            base, n = self._object_base(sim, oid)
            parts.append(_map_header(n + len(AGENT_FIELDS)))
            parts.append(base)
            parts.append(self._object_tail(sim, agent_id, oid))
        return b"".join(parts)

    def _result_fields(self, agent_id: int, scene_name: str, action: str, result: ActionResult,
                       sequence_id: int) -> dict[str, Any]:
        return {
            "agentId": agent_id,
            "sceneName": scene_name,
            "lastAction": action,
            "lastActionSuccess": result.success,
            "errorMessage": result.error_message,
            "errorCode": result.error_code,
            "actionReturn": result.action_return,
            "sequenceId": sequence_id,
            "screenWidth": self.width,
            "screenHeight": self.height,
        }

    def agent_fields(self, sim: Simulator, agent_id: int, sequence_id: int) -> dict[str, Any]:
        """One agent's metadata, all but its ``objects`` (see :func:`agent_view` for their per-agent fields)."""
        agent = sim.agents[agent_id]
        action, result = self.last_results[agent_id]
        held = sim.objects.get(agent.held) if agent.held else None
        return {
            **self._result_fields(agent_id, sim.scene_name + "_physics", action, result, sequence_id),
            "agent": {
                "name": "agent",
                "position": {"x": agent.x, "y": agent.y, "z": agent.z},
                "rotation": {"x": 0.0, "y": agent.yaw, "z": 0.0},
                "cameraHorizon": agent.horizon,
                "isStanding": agent.standing,
                "inHighFrictionArea": False,
            },
            "inventoryObjects": [{"objectId": held["objectId"], "objectType": held["objectType"]}] if held else [],
            "cameraPosition": {"x": agent.x, "y": agent.y + 0.675, "z": agent.z},
            "fov": 90.0,
            "visibilityDistance": sim.visibility_distance,
            "thirdPartyCameras": [],
            "collided": False,
            "collidedObjects": [],
            "isSceneAtRest": True,
            "colors": [],
            "actionIntReturn": 0,
            "actionFloatReturn": 0.0,
            "actionStringsReturn": [],
            "actionFloatsReturn": [],
            "actionVector3sReturn": [],
        }

    def _agent(self, sim: Simulator, agent_id: int, sequence_id: int, *, with_objects: bool = True) -> bytes:
        fields = self.agent_fields(sim, agent_id, sequence_id)
        if not with_objects:
            return _map_header(len(fields)) + _pack_items(fields)
        return _map_header(len(fields) + 1) + _pack_items(fields) + _pack("objects") + self._objects(sim, agent_id)

    def encode_patch(self, sim: Simulator, *, agent_id: int, sequence_id: int, with_objects: bool) -> bytes:
        """The body of a METADATA_PATCH: the acting agent's fields, merged by the Controller into
        the previous event. Only valid when no object changed, so the other agents' views still hold."""
        return self._agent(sim, agent_id, sequence_id, with_objects=with_objects)

    def encode(self, sim: Simulator, *, active_agent: int, sequence_id: int) -> bytes:
        """The msgpack body of one METADATA message for the current state."""
        if self._scene != sim.scene_name:
            self._scene = sim.scene_name
            self._base.clear()
            self._tail.clear()
        agents = b"".join(self._agent(sim, i, sequence_id) for i in range(len(sim.agents)))
        return (
            _map_header(4)
            + _pack("agents") + _array_header(len(sim.agents)) + agents
            + _pack("thirdPartyCameras") + _pack([])
            + _pack("activeAgentId") + _pack(active_agent)
            + _pack("sequenceId") + _pack(sequence_id)
        )

    def encode_bare(self, *, scene_name: str, sequence_id: int, result: ActionResult, action: str) -> bytes:
        """Metadata for the moments before a scene is loaded (the greeting, GetScenesInBuild)."""
        agent = {
            **self._result_fields(0, scene_name, action, result, sequence_id),
            "thirdPartyCameras": [],
            "objects": [],
            "agent": {"name": "agent", "position": {"x": 0.0, "y": 0.0, "z": 0.0},
                      "rotation": {"x": 0.0, "y": 0.0, "z": 0.0}, "cameraHorizon": 0.0, "isStanding": True},
            "inventoryObjects": [],
        }
        return _pack({"agents": [agent], "thirdPartyCameras": [], "activeAgentId": 0, "sequenceId": sequence_id})
