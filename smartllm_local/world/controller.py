"""The one way into the world: open an ``ai2thor`` Controller on a floor plan.

It drives a real Unity build when one is given (``build=`` or the environment
variable ``SMARTLLM_THOR_BUILD``), else the project's headless stand-in. Both
are started and spoken to by the unmodified ai2thor 5.0.0 Controller; the
subclass below only adds supervision that ai2thor lacks:

- when the AI2-THOR process dies, ai2thor 5.0.0 spins on the closed pipe until
  its timeout (100 s by default) or blocks for ever if the process never
  opened it. A watchdog thread waits on the process and, when it exits
  unexpectedly, writes an end-of-message header into the pipe so the pending
  read returns at once;
- failures while starting leave the process running; here it is stopped;
- errors that mean "the process is gone or silent" become :class:`WorldError`
  with the exit status and where its log is.
"""

from __future__ import annotations

import os
import shlex
import struct
import sys
import threading
import time
from pathlib import Path
from typing import Any

from ai2thor.controller import Controller

from ..errors import UserError, WorldError
from .scenes import floor_plan_name
from .simulator import DEFAULT_VISIBILITY_DISTANCE

BUILD_ENV = "SMARTLLM_THOR_BUILD"
STAND_IN_TIMEOUT = 10.0
UNITY_TIMEOUT = 100.0
_EOM = struct.pack("!BI", 255, 0)
_LOG_HINT = "~/.ai2thor/log/unity.log"


def stand_in_command() -> str:
    """The command that starts the stand-in, as a string the Controller can shlex-split."""
    script = Path(sys.executable).with_name("smartllm-thor-server")
    if script.is_file() and os.access(script, os.X_OK):
        return shlex.quote(str(script))
    return f"{shlex.quote(sys.executable)} -m smartllm_local.world.thor_server"


class SupervisedController(Controller):
    """ai2thor's Controller, with the stand-in's process watched and start-up failures cleaned up."""

    def __init__(self, *args: Any, **kwargs: Any):
        self._stopping = False
        self._closed = False
        self._watchdog: threading.Thread | None = None
        try:
            super().__init__(*args, **kwargs)
        except Exception as exc:
            dead = self._process_status()
            self._shutdown()
            if isinstance(exc, WorldError):
                raise
            if dead is not None or isinstance(exc, (TimeoutError, BrokenPipeError)):
                raise WorldError(self._describe("failed to start", exc, dead)) from exc
            raise

    def _start_unity_thread(self, env, width, height, server_params, image_name):  # type: ignore[override]
        super()._start_unity_thread(env, width, height, server_params, image_name)
        proc = self.server.unity_proc
        pipe_path = getattr(self.server, "server_pipe_path", None)
        if proc is not None and pipe_path:
            self._watchdog = threading.Thread(
                target=self._watch, args=(proc, pipe_path), name="ai2thor-watchdog", daemon=True
            )
            self._watchdog.start()

    def _watch(self, proc: Any, pipe_path: str) -> None:
        proc.wait()
        deadline = time.monotonic() + self.server_start_timeout
        while not (self._stopping or self.killing_unity):
            try:
                # Unblocks a reader waiting in open() or read(); it sees an empty message.
                fd = os.open(pipe_path, os.O_WRONLY | os.O_NONBLOCK)
                break
            except OSError:
                # No reader yet (the Controller has not reached its first read): wait for it.
                if time.monotonic() > deadline:
                    return
                time.sleep(0.05)
        else:
            return
        try:
            os.write(fd, _EOM)
        except OSError:
            pass
        finally:
            os.close(fd)

    def _process_status(self) -> int | None:
        proc = getattr(getattr(self, "server", None), "unity_proc", None)
        return None if proc is None else proc.poll()

    def _describe(self, what: str, exc: BaseException, status: int | None) -> str:
        command = getattr(getattr(self, "_build", None), "executable_path", "?")
        if isinstance(exc, TimeoutError):
            cause = f"it did not answer within {self.server_timeout} s and was stopped"
        elif status is not None:
            cause = f"the process exited with status {status}"
        else:
            cause = f"{type(exc).__name__}: {exc}"
        return f"AI2-THOR ({command}) {what}: {cause}. Its output is in {_LOG_HINT}."

    def _shutdown(self) -> None:
        self._stopping = True
        self._closed = True
        try:
            if getattr(self, "server", None) is not None:
                self.stop_unity()
                self.server.stop()
                proc = self.server.unity_proc
                if proc is not None:
                    proc.kill()
                    proc.wait(timeout=5)
        except Exception:
            pass

    def step(self, action: Any = None, **action_args: Any):  # type: ignore[override]
        if self._closed:
            raise WorldError("this Controller has stopped; open a new one")
        try:
            return super().step(action, **action_args)
        except (BrokenPipeError, TimeoutError, RuntimeError, ValueError, OSError) as exc:
            status = self._process_status()
            if status is None and not isinstance(exc, (TimeoutError, BrokenPipeError)):
                raise
            name = action.get("action") if isinstance(action, dict) else action
            self._shutdown()
            raise WorldError(self._describe(f"failed while running {name!r}", exc, status)) from exc

    def stop(self) -> None:
        self._stopping = True
        self._closed = True
        if getattr(self, "server", None) is None:
            return
        super().stop()
        proc = self.server.unity_proc
        if proc is not None:
            try:
                proc.wait(timeout=5)
            except Exception:
                pass


def open_controller(
    floor_plan: int | str,
    agent_count: int = 1,
    *,
    build: str | os.PathLike[str] | None = None,
    visibility_distance: float = DEFAULT_VISIBILITY_DISTANCE,
    grid_size: float = 0.25,
    server_timeout: float | None = None,
    **controller_kwargs: Any,
) -> Controller:
    """Start AI2-THOR on ``floor_plan`` with ``agent_count`` agents and return its Controller.

    Args:
        floor_plan: a floor plan number or name (``6``, ``"FloorPlan6"``).
        agent_count: how many agents (robots) the scene holds.
        build: a Unity build's executable; default ``$SMARTLLM_THOR_BUILD``, else the stand-in.
        visibility_distance: how far (m) an agent reaches objects, AI2-THOR's Initialize parameter.
        grid_size: the reachable-position grid (m).
        server_timeout: seconds to wait for any answer before giving up on the process.
        controller_kwargs: passed to ``ai2thor.controller.Controller`` (e.g. ``platform=`` for a real build).

    Raises:
        UnknownFloorPlanError: the floor plan is not an iTHOR scene.
        UserError: the given build does not exist or is not executable.
        WorldError: the process could not be started or stopped answering.
    """
    scene = floor_plan_name(floor_plan)
    if not isinstance(agent_count, int) or not 1 <= agent_count <= 16:
        raise UserError(f"agent_count must be between 1 and 16, got {agent_count!r}")
    build = build or os.environ.get(BUILD_ENV) or None
    if build:
        path = Path(build).expanduser()
        if not path.is_file() or not os.access(path, os.X_OK):
            raise UserError(
                f"AI2-THOR build {path} is not an executable file; pass the Unity executable "
                f"(e.g. ~/.ai2thor/releases/thor-Linux64-<commit>/thor-Linux64-<commit>) or unset {BUILD_ENV}"
            )
        executable = shlex.quote(str(path))
        timeout = server_timeout or UNITY_TIMEOUT
    else:
        executable = stand_in_command()
        timeout = server_timeout or STAND_IN_TIMEOUT
    kwargs: dict[str, Any] = dict(
        local_executable_path=executable,
        scene=scene,
        agentCount=agent_count,
        visibilityDistance=visibility_distance,
        gridSize=grid_size,
        headless=True,
        # ai2thor 5.0.0 passes DISPLAY=None to Popen when no display is named; the stand-in needs none.
        x_display=os.environ.get("DISPLAY") or ":0",
        server_timeout=timeout,
        server_start_timeout=max(timeout, 30.0),
    )
    kwargs.update(controller_kwargs)
    return SupervisedController(**kwargs)
