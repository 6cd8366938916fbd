"""What a plan's constraint knows of a function written so far: its steps, what it holds, where it went."""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field

from ...executor.team_actions import RELEASE_ACTIONS
from .candidates import STATE_ACTIONS
from .world_check import Call

#: A call line of a plan: its skill, its robot_list slot (if it names one) and its one or two objects.
CALL_LINE = re.compile(r"^\s+(\w+)\((?:robot_list(?:\[(\d+)\])?, )?'([^']+)'(?:, '([^']+)')?\)$")
_ROBOT = re.compile(r"robots\[(\d+)\]")
_SLEEP = re.compile(r"^\s+time\.sleep\(([\d.]+)\)$")


def sleep_ticks(line: str) -> int:
    """The ticks the executor waits at a body line: a tick for each second a sleep waits (part of one a whole);
    none at any other line."""
    sleep = _SLEEP.match(line.rstrip("\n"))
    return math.ceil(float(sleep.group(1))) if sleep else 0


def robots_named(piece: str) -> list[int]:
    """The team indices a launch line gives its function, in order (``[robots[2], robots[0]]``: 2, 0)."""
    return [int(i) for i in _ROBOT.findall(piece)]


@dataclass
class WrittenFunction:
    """What the constraint knows of a function written so far."""

    name: str
    steps: int = 0
    max_index: int = -1  # the highest robot_list[i] used; -1: none (robot_list alone counts as 0)
    last: str = ""  # the kind of the last line: "action", "goto", "sleep" or "comment"
    last_step: str = ""  # the same, comments aside
    comments: int = 0
    held: set[str] = field(default_factory=set)  # object types picked up and not yet put down
    states: dict[str, str] = field(default_factory=dict)  # type -> the last state action on it
    last_call: tuple[str, str] = ("", "")  # (AI2-THOR action, object) of the last step
    calls: list[Call] = field(default_factory=list)  # (robot_list slot, skill, objects)
    written: int = 0  # lines of a restated body written so far
    went: bool = False  # whether it has gone somewhere (with a world check, it acts only after that)
    slots_went: set[int] = field(default_factory=set)  # robot_list slots that went somewhere in it
    together: bool = False  # the last GoToObject took the whole robot_list
    whole: bool = False  # a step named the whole robot_list (see feasibility.shortest_list)

    def track(self, line: str, actions: dict[str, str]) -> None:
        match = CALL_LINE.match(line.rstrip("\n"))
        if not match:
            self.last_call = ("", "")
            return
        skill, first = match.group(1), match.group(3)
        slot = int(match.group(2)) if match.group(2) is not None else None
        self.calls.append((slot, skill, tuple(o for o in match.group(3, 4) if o is not None)))
        action = actions.get(skill, "")
        self.last_call = (action, first) if action else ("", "")
        if action == "PickupObject":
            self.held.add(first)
        elif action in RELEASE_ACTIONS:
            self.held.discard(first)
        elif action in STATE_ACTIONS:
            self.states[first] = action
