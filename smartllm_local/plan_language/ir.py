"""The plan IR: what a parsed plan is, as plain frozen data.

A plan is a set of sub-task functions and a main flow (the module's top level)
that launches them, in threads or directly, and waits for them. Robot
arguments are kept symbolic (``robots[1]``, ``robot_list[0]``...) and are
resolved against a team by :func:`resolve_robots` when a sub-task runs.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Literal

Form = Literal["decomposed", "allocated"]

#: The name plans use for the whole team.
TEAM_NAME = "robots"


@dataclass(frozen=True)
class TeamRobot:
    """``robots[i]``: the i-th robot of the team."""

    index: int


@dataclass(frozen=True)
class ParamRobot:
    """``robot_list[i]``: the i-th robot passed in a function parameter."""

    param: str
    index: int


@dataclass(frozen=True)
class ParamList:
    """``robot_list``: every robot passed in a function parameter, acting together."""

    param: str


@dataclass(frozen=True)
class WholeTeam:
    """``robots``: the whole team, acting together."""


@dataclass(frozen=True)
class RobotGroup:
    """``[robots[0], robot_list[1]]``: a list of single robots, acting together."""

    members: tuple[TeamRobot | ParamRobot, ...]


RobotRef = TeamRobot | ParamRobot | ParamList | WholeTeam | RobotGroup


@dataclass(frozen=True)
class SkillCall:
    """One primitive step: ``PutObject(robot_list[0], 'Apple', 'Fridge')``."""

    skill: str
    robots: RobotRef | None  # None in a decomposed plan
    objects: tuple[str, ...]
    line: int
    col: int


@dataclass(frozen=True)
class Sleep:
    """``time.sleep(seconds)``: wait without acting."""

    seconds: float
    line: int
    col: int


@dataclass(frozen=True)
class Call:
    """A call of a plan function: inside a function it runs inline, at top level it runs a sub-task and waits."""

    function: str
    args: tuple[RobotRef, ...]
    line: int
    col: int


@dataclass(frozen=True)
class NewThread:
    """``t1 = threading.Thread(target=f, args=(...))``."""

    var: str
    function: str
    args: tuple[RobotRef, ...]
    line: int
    col: int


@dataclass(frozen=True)
class Start:
    var: str
    line: int
    col: int


@dataclass(frozen=True)
class Join:
    var: str
    line: int
    col: int


Step = SkillCall | Sleep | Call
MainStep = NewThread | Start | Join | Call | Sleep


@dataclass(frozen=True)
class Function:
    """A plan function: a sub-task, or a helper that sub-tasks call."""

    name: str
    params: tuple[str, ...]
    body: tuple[Step, ...]
    line: int
    col: int
    description: str = ""  # its first comment or docstring line


@dataclass(frozen=True)
class Plan:
    """A validated plan."""

    form: Form
    functions: tuple[Function, ...]
    main: tuple[MainStep, ...]
    source: str = field(repr=False, default="")
    refusal: str | None = None  # the reason of a "# INFEASIBLE: ..." plan

    @property
    def by_name(self) -> Mapping[str, Function]:
        return {f.name: f for f in self.functions}

    @property
    def is_refusal(self) -> bool:
        return self.refusal is not None

    def skill_calls(self) -> list[SkillCall]:
        """Every skill call written in the plan, in source order."""
        return [s for f in self.functions for s in f.body if isinstance(s, SkillCall)]

    def stages(self) -> list[list[str]]:
        """The written parallel/sequential structure: groups of sub-tasks launched together.

        A group collects the sub-tasks launched (thread starts, direct calls)
        with no wait in between; a join, a direct call's return or a sleep ends
        it. Robot conflicts can split a group at run time; the executor's
        transitions are the measured count.
        """
        stages: list[list[str]] = []
        current: list[str] = []
        targets: dict[str, str] = {}
        for step in self.main:
            if isinstance(step, NewThread):
                targets[step.var] = step.function
            elif isinstance(step, Start):
                current.append(targets[step.var])
            elif isinstance(step, Call):
                current.append(step.function)
                stages.append(current)
                current = []
            elif current:
                stages.append(current)
                current = []
        if current:
            stages.append(current)
        return stages


class RobotIndexError(Exception):
    """A robot reference points past the end of the list it indexes."""

    def __init__(self, message: str):
        super().__init__(message)
        self.message = message


def resolve_robots(ref: RobotRef, env: Mapping[str, tuple[int, ...]], team_size: int | None) -> tuple[int, ...]:
    """The team indices a robot reference stands for, given the parameter bindings.

    With ``team_size`` None, indices into the whole team are not checked.
    """
    if isinstance(ref, TeamRobot):
        if team_size is not None and ref.index >= team_size:
            raise RobotIndexError(
                f"robots[{ref.index}] does not exist: the team has {team_size} robot(s), "
                f"robots[0]..robots[{team_size - 1}]"
            )
        return (ref.index,)
    if isinstance(ref, ParamRobot):
        bound = env[ref.param]
        if ref.index >= len(bound):
            raise RobotIndexError(
                f"{ref.param}[{ref.index}] does not exist: this call passes {len(bound)} robot(s) in {ref.param}"
            )
        return (bound[ref.index],)
    if isinstance(ref, ParamList):
        return env[ref.param]
    if isinstance(ref, WholeTeam):
        if team_size is None:
            return ()
        return tuple(range(team_size))
    indices: list[int] = []
    for member in ref.members:
        for index in resolve_robots(member, env, team_size):
            if index not in indices:
                indices.append(index)
    return tuple(indices)


def bind(function: Function, args: tuple[RobotRef, ...], env: Mapping[str, tuple[int, ...]],
         team_size: int | None) -> dict[str, tuple[int, ...]]:
    """The parameter bindings of a call of ``function`` with ``args`` evaluated in ``env``."""
    return {p: resolve_robots(a, env, team_size) for p, a in zip(function.params, args)}
