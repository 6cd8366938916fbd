"""Plans carried out by a lab's own code: one Python entry point per skill.

A dispatch file (TOML) names, for each skill, the function that makes a robot do it::

    timeout = 60                                # seconds an action may take (default 60)

    [skills]
    GoToObject = "mylab.robots:go_to_object"    # module:function, importable where the plan runs
    PickupObject = "mylab.robots:pick_up"

The scheduler is the simulator's (:mod:`.scheduler`): sub-tasks launched together run together,
a tick at a time, and each tick's skill calls are dispatched at once, each in a thread of its own,
the tick ending when all have returned. A function is called as ``function(robots, *objects)``:
``robots`` the acting catalogue :class:`~smartllm_local.robots.Robot` s (one, or a team for a pooled
lift), ``objects`` the call's object names. It reports failure by raising (the message is the
action's error) or by returning False; anything else is success. One that has not returned after
``timeout`` seconds fails with that message and the run goes on; its thread is left to finish (Python
cannot stop it), so a lab's function should honour its own deadline too.
"""

from __future__ import annotations

import importlib
import threading
import time
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib

from ..errors import UserError
from ..plan_language import Plan
from ..robots import Robot
from ..skills import Skill, SkillSet
from .scheduler import DEFAULT_MAX_TICKS, Execution, check_team, run
from .team_actions import Outcome

DEFAULT_TIMEOUT = 60.0


@dataclass(frozen=True)
class Dispatch:
    """Which function carries out each skill, and how long an action may take."""

    functions: dict[str, Callable[..., Any]]
    timeout: float
    path: str

    def unnamed(self, skills: Iterable[str]) -> list[str]:
        """The skills among ``skills`` that this file names no function for, sorted."""
        return sorted(set(skills) - set(self.functions))


def load_dispatch(path: str | Path, skills: SkillSet) -> Dispatch:
    """Read a dispatch file and import its functions; every problem is a :class:`UserError` naming it."""
    path = Path(path)
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except OSError as exc:
        raise UserError(f"cannot read the dispatch file {path}: {exc.strerror or exc}") from None
    except UnicodeDecodeError as exc:
        raise UserError(f"dispatch file {path} is not UTF-8 text ({exc.reason})") from None
    except tomllib.TOMLDecodeError as exc:
        raise UserError(f"dispatch file {path}: not valid TOML: {exc}") from None
    unknown = sorted(set(data) - {"timeout", "skills"})
    if unknown:
        raise UserError(f"dispatch file {path}: unknown key(s) {', '.join(unknown)}; it has `timeout` and [skills]")
    timeout = data.get("timeout", DEFAULT_TIMEOUT)
    if isinstance(timeout, bool) or not isinstance(timeout, (int, float)) or not 0 < timeout <= 86_400:
        raise UserError(f"dispatch file {path}: timeout must be a number of seconds above 0, got {timeout!r}")
    table = data.get("skills")
    if not isinstance(table, dict) or not table:
        raise UserError(f"dispatch file {path}: needs a [skills] table, e.g. GoToObject = \"mylab.robots:go_to\"")
    functions = {}
    for skill, target in table.items():
        where = f"dispatch file {path}, skills.{skill}"
        if skill not in skills:
            raise UserError(f"{where}: no such skill; the catalogue's skills are {', '.join(skills)}")
        functions[skill] = _entry_point(target, where)
    return Dispatch(functions, float(timeout), str(path))


def _entry_point(target: Any, where: str) -> Callable[..., Any]:
    if not isinstance(target, str) or target.count(":") != 1:
        raise UserError(f"{where}: give the function as \"module:function\", got {target!r}")
    module_name, name = target.split(":")
    try:
        module = importlib.import_module(module_name)
    except Exception as exc:  # an import runs the lab's code: any error is the file's to fix
        raise UserError(f"{where}: cannot import {module_name}: {type(exc).__name__}: {exc} "
                        "(is it on PYTHONPATH where the plan runs?)") from None
    function = getattr(module, name, None)
    if not callable(function):
        raise UserError(f"{where}: {module_name} has no function {name}")
    return function


class DispatchWorld:
    """Each tick's skill calls, handed to the lab's functions at once."""

    def __init__(self, dispatch: Dispatch, team: Sequence[Robot]):
        self.dispatch = dispatch
        self.team = list(team)

    def perform_all(self, steps: Sequence[tuple[Skill, Sequence[str], Sequence[int]]]) -> list[Outcome]:
        calls = [_Call(self.dispatch.functions[skill.name], skill.name,
                       [self.team[m] for m in members], list(objects)) for skill, objects, members in steps]
        deadline = time.monotonic() + self.dispatch.timeout  # each call has the timeout from the tick's start
        for call in calls:
            call.thread.start()
        for call in calls:
            call.thread.join(max(0.0, deadline - time.monotonic()))
        return [call.outcome(self.dispatch.timeout) for call in calls]

    def release(self) -> None:
        pass

    @property
    def objects(self) -> list[dict[str, Any]]:
        return []  # a lab's world reports no AI2-THOR metadata

    @property
    def layout(self) -> None:
        return None  # nor where its robots are


class _Call:
    """One skill call on a thread of its own (a daemon: one that never returns cannot keep the run alive)."""

    def __init__(self, function: Callable[..., Any], skill: str, robots: list[Robot], objects: list[str]):
        self.function, self.skill, self.robots, self.objects = function, skill, robots, objects
        self.result: tuple[bool, str] | None = None
        self.thread = threading.Thread(target=self._call, name=f"dispatch-{skill}", daemon=True)

    def _call(self) -> None:
        try:
            returned = self.function(self.robots, *self.objects)
        except BaseException as exc:  # the lab's code: whatever it raises is that action's failure
            self.result = (False, f"{type(exc).__name__}: {exc}")
            return
        self.result = (False, f"{self.skill} returned False") if returned is False else (True, "")

    def outcome(self, timeout: float) -> Outcome:
        result = self.result
        if result is None:
            result = (False, f"{self.skill} did not return within {timeout:g} s")
        return Outcome(success=result[0], error=result[1], action=self.skill)


def dispatch_plan(plan: Plan, team: Sequence[Robot], dispatch: Dispatch, *, skills: SkillSet,
                  max_ticks: int = DEFAULT_MAX_TICKS) -> Execution:
    """Run an allocated plan with the lab's functions carrying out its skill calls.

    Raises:
        UserError: the plan does not fit the team, or uses a skill the dispatch file names no function for.
    """
    check_team(plan, len(team))
    missing = dispatch.unnamed(call.skill for call in plan.skill_calls())
    if missing:
        raise UserError(f"the plan uses {', '.join(missing)}, which the dispatch file {dispatch.path} "
                        "names no function for; add them under [skills]")
    return run(plan, DispatchWorld(dispatch, team), team, skills=skills, max_ticks=max_ticks)
