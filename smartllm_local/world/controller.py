"""The one way into the world: open an ``ai2thor`` Controller on a floor plan.

It drives a real Unity build when one is given (``build=`` or the environment
variable ``SMARTLLM_THOR_BUILD``), else the project's headless stand-in. Both
are started and spoken to by the unmodified ai2thor 5.0.0 Controller; the
subclass below only adds supervision that ai2thor lacks:

- when the AI2-THOR process dies, ai2thor 5.0.0 spins on the closed pipe until
  its timeout (100 s by default) or blocks for ever if the process never
  opened it. A watchdog thread waits on the process and, when it exits
  unexpectedly, writes an end-of-message header into the pipe so the pending
  read returns at once, and opens the action pipe's far end so that a pending
  open() of it returns;
- ai2thor's open() of a pipe has no timeout, so a process that never opens its
  pipes blocks it for ever. Start-up therefore has deadlines: the process must
  greet within ``server_start_timeout`` (what ai2thor allows the first event)
  and then open the action pipe within ``server_timeout`` (what it allows every
  later answer); past one, the watchdog kills it, which unblocks as above;
- failures while starting leave the process running; here it is stopped;
- errors that mean "the process is gone or silent" become :class:`WorldError`
  with the exit status and where its log is.
"""

from __future__ import annotations

import os
import shlex
import signal
import struct
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import Any

from ai2thor.controller import Controller

from ..errors import UserError, WorldError
from .scenes import check_scene_data, floor_plan_name
from .simulator import DEFAULT_VISIBILITY_DISTANCE

BUILD_ENV = "SMARTLLM_THOR_BUILD"
STAND_IN_TIMEOUT = 10.0
UNITY_TIMEOUT = 100.0
_EOM = struct.pack("!BI", 255, 0)
_LOG_HINT = "~/.ai2thor/log/unity.log"
_POLL_S = 0.02  # how often the watchdog looks at start-up progress; a normal start never waits on it


def stand_in_command() -> str:
    """The command that starts the stand-in, as a string the Controller can shlex-split."""
    script = Path(sys.executable).with_name("smartllm-thor-server")
    if script.is_file() and os.access(script, os.X_OK):
        return shlex.quote(str(script))
    return f"{shlex.quote(sys.executable)} -m smartllm_local.world.thor_server"


class SupervisedController(Controller):
    """ai2thor's Controller, with the stand-in's process watched and start-up failures cleaned up.

    ``stand_in`` says the executable is this project's own (a failure to run it
    is then a broken install, not a bad build path).
    """

    def __init__(self, *args: Any, stand_in: bool = False, **kwargs: Any):
        self._stand_in = stand_in
        self._stopping = False
        self._closed = False
        self._late: str | None = None  # set when start-up missed a deadline: what was late
        self._watchdog: threading.Thread | None = None
        try:
            super().__init__(*args, **kwargs)
        except Exception as exc:
            dead = self._process_status(grace=0.5 if isinstance(exc, BrokenPipeError) else 0.0)
            self._shutdown()
            if isinstance(exc, (UserError, WorldError)):
                raise
            if self._late is not None or dead is not None or isinstance(exc, (TimeoutError, BrokenPipeError)):
                raise WorldError(self._describe("failed to start", exc, dead)) from exc
            raise

    def _start_unity_thread(self, env, width, height, server_params, image_name):  # type: ignore[override]
        try:
            super()._start_unity_thread(env, width, height, server_params, image_name)
        except OSError as exc:
            command = self._build.executable_path
            why = exc.strerror or str(exc)
            if self._stand_in:
                raise WorldError(
                    f"cannot run the AI2-THOR stand-in ({command}): {why}; reinstall smartllm-local"
                ) from exc
            raise UserError(
                f"cannot run the AI2-THOR build {command}: {why}; pass a Unity executable for this machine "
                f"(a script needs a #! line naming an installed interpreter) or unset {BUILD_ENV}"
            ) from exc
        proc = self.server.unity_proc
        if proc is not None and getattr(self.server, "server_pipe_path", None):
            self._watchdog = threading.Thread(
                target=self._watch, args=(proc, self.server), name="ai2thor-watchdog", daemon=True
            )
            self._watchdog.start()

    def _watch(self, proc: Any, server: Any) -> None:
        self._guard_start(proc, server)
        proc.wait()
        if self._stopping or self.killing_unity:
            return
        # ai2thor may be about to open() the action pipe for writing, which blocks until a reader
        # appears: be that reader until it has opened it (its write then fails or its read sees EOM).
        held = None
        if getattr(server, "client_pipe", None) is None and getattr(server, "client_pipe_path", None):
            try:
                held = os.open(server.client_pipe_path, os.O_RDONLY | os.O_NONBLOCK)
            except OSError:
                pass
        try:
            self._unblock_reader(server.server_pipe_path)
            deadline = time.monotonic() + self.server_start_timeout
            while held is not None and server.client_pipe is None and not self._stopping:
                if time.monotonic() > deadline:
                    break
                time.sleep(_POLL_S)
        finally:
            if held is not None:
                os.close(held)

    def _guard_start(self, proc: subprocess.Popen, server: Any) -> None:
        """Kill the process if it misses a start-up deadline; return once start-up is past its blocking open()s."""
        limit = self.server_start_timeout
        deadline = time.monotonic() + limit
        greeted = False
        while getattr(server, "client_pipe", None) is None and not self._stopping:
            if proc.poll() is not None:
                return
            if not greeted and getattr(server, "raw_metadata", None) is not None:
                greeted = True
                limit = self.server_timeout or self.server_start_timeout
                deadline = time.monotonic() + limit
            if time.monotonic() > deadline:
                self._late = (
                    f"it did not open its action pipe within {limit} s of greeting"
                    if greeted
                    else f"it did not greet within {limit} s (server_start_timeout)"
                )
                _kill_tree(proc)
                return
            time.sleep(_POLL_S)

    def _unblock_reader(self, pipe_path: str) -> None:
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

    def _process_status(self, grace: float = 0.0) -> int | None:
        """The exit status, or None while it runs; waits up to ``grace`` s for one that is exiting.

        A closed pipe is seen before the process is reaped (by the watchdog, which
        holds Popen's wait lock meanwhile, so poll() answers None): the grace lets
        the error name the status.
        """
        proc = getattr(getattr(self, "server", None), "unity_proc", None)
        if proc is None:
            return None
        try:
            return proc.wait(timeout=grace) if grace else proc.poll()
        except subprocess.TimeoutExpired:
            return None

    def _describe(self, what: str, exc: BaseException, status: int | None) -> str:
        command = getattr(getattr(self, "_build", None), "executable_path", "?")
        if self._late is not None:
            cause = f"{self._late} and was stopped"
        elif isinstance(exc, TimeoutError):
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
                if self.server.unity_proc is not None:
                    _kill_tree(self.server.unity_proc)
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
            status = self._process_status(grace=0.5 if isinstance(exc, BrokenPipeError) else 0.0)
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


def _kill_tree(proc: subprocess.Popen) -> None:
    """Kill a process and everything it started: a build may be a script that runs the real program."""
    below = _descendants(proc.pid) if proc.poll() is None else []
    proc.kill()
    for pid in below:
        try:
            os.kill(pid, signal.SIGKILL)
        except OSError:
            pass


def _descendants(pid: int) -> list[int]:
    """The processes below ``pid``, read from /proc (none where there is no /proc)."""
    children: dict[int, list[int]] = {}
    try:
        entries = [e for e in os.listdir("/proc") if e.isdigit()]
    except OSError:
        return []
    for entry in entries:
        try:
            with open(f"/proc/{entry}/stat", "rb") as f:
                stat = f.read()
            # The name (field 2) may hold spaces and ")": the fields resume after its last ")".
            ppid = int(stat[stat.rindex(b")") + 2:].split()[1])
        except (OSError, ValueError, IndexError):
            continue
        children.setdefault(ppid, []).append(int(entry))
    found, stack = [], [pid]
    while stack:
        for child in children.get(stack.pop(), []):
            found.append(child)
            stack.append(child)
    return found


def check_build(build: str | os.PathLike[str] | None) -> Path | None:
    """The Unity build to run: ``build``, else ``$SMARTLLM_THOR_BUILD``, as an absolute path (so that Popen does
    not look a bare name up on PATH); None for the stand-in. Commands call it before any work, so that a wrong
    path is not found only when the first plan is to run.

    Raises:
        UserError: the build is not an executable file.
    """
    build = build or os.environ.get(BUILD_ENV) or None
    if not build:
        return None
    path = Path(os.path.abspath(Path(build).expanduser()))
    if not path.is_file() or not os.access(path, os.X_OK):
        raise UserError(
            f"AI2-THOR build {path} is not an executable file; pass the Unity executable "
            f"(e.g. ~/.ai2thor/releases/thor-Linux64-<commit>/thor-Linux64-<commit>) or unset {BUILD_ENV}"
        )
    return path


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
        server_timeout: seconds to wait for any answer before giving up on the process; the first
            one (start-up) may take max(this, 30 s), or ``server_start_timeout=`` if given.
        controller_kwargs: passed to ``ai2thor.controller.Controller`` (e.g. ``platform=`` for a real build).

    Raises:
        UnknownFloorPlanError: the floor plan is not an iTHOR scene.
        UserError: the given build does not exist or cannot be run.
        SceneDataError: no build is given and the scene data the stand-in reads is missing or corrupt.
        WorldError: the process failed to start in time, exited, or stopped answering.
    """
    scene = floor_plan_name(floor_plan)
    if not isinstance(agent_count, int) or not 1 <= agent_count <= 16:
        raise UserError(f"agent_count must be between 1 and 16, got {agent_count!r}")
    path = check_build(build)
    if path is not None:
        executable = shlex.quote(str(path))
        timeout = server_timeout or UNITY_TIMEOUT
    else:
        # The stand-in reads the scene data; a problem with it is the user's to fix, so say so here.
        check_scene_data()
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
    return SupervisedController(stand_in=not build, **kwargs)
