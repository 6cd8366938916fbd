"""The headless AI2-THOR process: the symbolic simulator served over AI2-THOR's FIFO protocol.

``ai2thor.controller.Controller(local_executable_path=<smartllm-thor-server>)``
starts this program as it would start the Unity build. The Controller creates
two named pipes and passes their paths in ``AI2THOR_FIFO_SERVER_PIPE_PATH``
(this process writes events to it) and ``AI2THOR_FIFO_CLIENT_PIPE_PATH`` (it
reads actions from it). Every message is a 1-byte field type and a 4-byte
big-endian length, then the body; a message ends with an END_OF_MESSAGE header.
Actions arrive as JSON, metadata leaves msgpack-packed. This process speaks
first, then answers each action with one event. It exits when the Controller
closes its end of the pipes, so it never outlives its parent's session.
"""

from __future__ import annotations

import json
import os
import struct
import sys
import traceback
from typing import Any, BinaryIO

from ..errors import UnknownFloorPlanError
from .metadata import MetadataEncoder
from .scenes import all_floor_plans, floor_plan_name
from .simulator import DEFAULT_VISIBILITY_DISTANCE, ActionResult, Simulator

METADATA = 1
ACTION = 2
METADATA_PATCH = 11
END_OF_MESSAGE = 255
_HEADER = struct.Struct("!BI")
MAX_AGENTS = 16
_FULL_EVENT_ACTIONS = frozenset({"Reset", "Initialize", "ChangeResolution"})


class ThorStandIn:
    """Dispatches the Controller's actions to a :class:`Simulator` and encodes its replies."""

    def __init__(self, width: int = 300, height: int = 300):
        self.encoder = MetadataEncoder(width, height)
        self.sim: Simulator | None = None
        self.scene: str | None = None
        self.sequence_id = 0

    def greeting(self) -> bytes:
        return self.encoder.encode_bare(scene_name="", sequence_id=0, result=ActionResult(), action="")

    def handle(self, action: dict[str, Any]) -> tuple[int, bytes]:
        """Run one action; return the message type and msgpack body that answer it.

        When an action changed no object, only the acting agent's view can differ
        from the previous event, and a METADATA_PATCH carrying just that view is
        exact (the Controller merges it into the previous event); otherwise every
        agent's view is sent.
        """
        self.sequence_id = int(action.get("sequenceId", self.sequence_id + 1))
        name = action.get("action")
        agent_id = action.get("agentId", 0)
        sim_before = self.sim
        generation = sim_before.generation if sim_before else -1
        valid_agent = sim_before is not None and isinstance(agent_id, int) and not isinstance(agent_id, bool) \
            and 0 <= agent_id < len(sim_before.agents)
        view = self._view(sim_before, agent_id) if valid_agent else None
        try:
            result = self._dispatch(name, action, agent_id)
        except Exception as exc:  # a bug here must not kill the Controller's session
            traceback.print_exc(file=sys.stderr)
            result = ActionResult(False, f"internal error in the AI2-THOR stand-in: {exc}", "")
        if self.sim is None:
            return METADATA, self.encoder.encode_bare(
                scene_name=self.scene or "", sequence_id=self.sequence_id, result=result, action=str(name)
            )
        active = agent_id if valid_agent else 0
        self.encoder.last_results[active] = (str(name), result)
        if (self.sim is sim_before and valid_agent and self.sim.generation == generation
                and name not in _FULL_EVENT_ACTIONS):
            moved = self._view(self.sim, active) != view
            body = self.encoder.encode_patch(self.sim, agent_id=active, sequence_id=self.sequence_id,
                                             with_objects=moved)
            return METADATA_PATCH, body
        return METADATA, self.encoder.encode(self.sim, active_agent=active, sequence_id=self.sequence_id)

    @staticmethod
    def _view(sim: Simulator, agent_id: int) -> tuple[int, frozenset[str] | None]:
        """What an agent's list of objects depends on when no object changes: its pose and its filter."""
        agent = sim.agents[agent_id]
        return agent.version, agent.object_filter

    def _dispatch(self, name: Any, action: dict[str, Any], agent_id: Any) -> ActionResult:
        if name == "GetScenesInBuild":
            return ActionResult(action_return=[f"{s}_physics" for s in all_floor_plans()])
        if name == "Reset":
            return self._reset(action)
        if name in ("ChangeResolution", "ChangeQuality"):
            if name == "ChangeResolution":
                self.encoder.width = int(action.get("x", self.encoder.width))
                self.encoder.height = int(action.get("y", self.encoder.height))
            return ActionResult()
        if self.scene is None:
            return ActionResult(False, f"{name}: no scene is loaded; send Reset first", "InvalidAction")
        if name == "Initialize":
            return self._initialize(action)
        if self.sim is None:
            return ActionResult(False, f"{name}: the scene is not initialised; send Initialize first", "InvalidAction")
        if not isinstance(agent_id, int) or isinstance(agent_id, bool):
            return ActionResult(False, f"agentId must be an integer, got {agent_id!r}", "InvalidArgument")
        return self.sim.step(agent_id, action)

    def _reset(self, action: dict[str, Any]) -> ActionResult:
        scene = action.get("sceneName")
        try:
            self.scene = floor_plan_name(str(scene))
        except UnknownFloorPlanError as exc:
            return ActionResult(False, str(exc), "InvalidArgument")
        self._build(agent_count=1, visibility=DEFAULT_VISIBILITY_DISTANCE, grid=0.25)
        return ActionResult()

    def _initialize(self, action: dict[str, Any]) -> ActionResult:
        count = action.get("agentCount", 1)
        if not isinstance(count, int) or isinstance(count, bool) or not 1 <= count <= MAX_AGENTS:
            return ActionResult(False, f"agentCount must be an integer from 1 to {MAX_AGENTS}, got {count!r}",
                                "InvalidArgument")
        visibility = action.get("visibilityDistance", DEFAULT_VISIBILITY_DISTANCE)
        grid = action.get("gridSize", 0.25)
        if not isinstance(visibility, (int, float)) or visibility <= 0:
            return ActionResult(False, f"visibilityDistance must be a positive number, got {visibility!r}",
                                "InvalidArgument")
        if not isinstance(grid, (int, float)) or not 0.05 <= grid <= 1.0:
            return ActionResult(False, f"gridSize must be between 0.05 and 1.0, got {grid!r}", "InvalidArgument")
        self._build(agent_count=count, visibility=float(visibility), grid=float(grid))
        return ActionResult(action_return={"cameraNearPlane": 0.1, "cameraFarPlane": 20.0})

    def _build(self, *, agent_count: int, visibility: float, grid: float) -> None:
        assert self.scene is not None
        self.sim = Simulator(self.scene, agent_count=agent_count, visibility_distance=visibility, grid_size=grid)
        self.encoder.reset_agents(agent_count)


def _read_exact(pipe: BinaryIO, size: int) -> bytes | None:
    data = b""
    while len(data) < size:
        chunk = pipe.read(size - len(data))
        if not chunk:
            return None
        data += chunk
    return data


def _read_action(pipe: BinaryIO) -> dict[str, Any] | None:
    """Read one action message; None when the Controller has gone away."""
    body = b""
    while True:
        header = _read_exact(pipe, _HEADER.size)
        if header is None:
            return None
        kind, length = _HEADER.unpack(header)
        if kind == END_OF_MESSAGE:
            break
        chunk = _read_exact(pipe, length) if length else b""
        if chunk is None:
            return None
        if kind == ACTION:
            body = chunk
    action = json.loads(body.decode("utf-8")) if body else {}
    return action if isinstance(action, dict) else {"action": None}


def _write_event(pipe: BinaryIO, kind: int, metadata: bytes) -> None:
    pipe.write(_HEADER.pack(kind, len(metadata)) + metadata + _HEADER.pack(END_OF_MESSAGE, 0))
    pipe.flush()


def serve(server_pipe_path: str, client_pipe_path: str) -> int:
    """Serve until the Controller closes the pipes; returns the exit status."""
    width = int(os.environ.get("SMARTLLM_THOR_WIDTH", "300"))
    stand_in = ThorStandIn(width, width)
    with open(server_pipe_path, "wb", buffering=0) as out:
        _write_event(out, METADATA, stand_in.greeting())
        with open(client_pipe_path, "rb", buffering=0) as inp:
            while True:
                try:
                    action = _read_action(inp)
                except (ValueError, UnicodeDecodeError) as exc:
                    action = {"action": None, "_error": str(exc)}
                if action is None:
                    return 0
                try:
                    _write_event(out, *stand_in.handle(action))
                except BrokenPipeError:
                    return 0


def main(argv: list[str] | None = None) -> int:
    """Entry point of ``smartllm-thor-server``; the Controller passes Unity's flags, which are ignored."""
    server_type = os.environ.get("AI2THOR_SERVER_TYPE", "FIFO")
    server_pipe = os.environ.get("AI2THOR_FIFO_SERVER_PIPE_PATH")
    client_pipe = os.environ.get("AI2THOR_FIFO_CLIENT_PIPE_PATH")
    if server_type != "FIFO" or not server_pipe or not client_pipe:
        print(
            "smartllm-thor-server speaks AI2-THOR's FIFO protocol only and is started by "
            "ai2thor.controller.Controller(local_executable_path=...) with the default FifoServer; "
            f"got AI2THOR_SERVER_TYPE={server_type!r}",
            file=sys.stderr,
        )
        return 2
    try:
        return serve(server_pipe, client_pipe)
    except KeyboardInterrupt:
        return 0


if __name__ == "__main__":
    sys.exit(main())
