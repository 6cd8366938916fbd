"""Stage 2's constraint: the coalition policy, one comment line per sub-task."""

from __future__ import annotations

import string
from typing import Sequence

from ..robots import Robot
from .constraints import REASON_CHARS, Choose, Constraint, longest, refusal_line, robot_list, text_run
from .feasibility import Need, feasible_teams
from .grammar import Node, Ref, alt, chars, opt, rep, seq


class CoalitionConstraint(Constraint):
    """Stage 2: one comment line per sub-task naming the robot or team of the team that does it.

    Robots are named only as ``robots[i]`` with i inside the team: the free
    text of a line admits no digits or brackets, except in a mass (``2.5 kg``).
    With the sub-tasks' needs known, a line admits only teams that can do the
    sub-task, and a refusal is the only answer when some sub-task has none
    (``free=True`` leaves both choices to the model). A line's reason is made of
    up to six pieces (a run of words, a robot, a mass); fewer when the budget
    left must also cover the lines still to come.
    """

    PIECE = 24  # longest piece of a reason
    MAX_PIECES = 6

    def __init__(self, function_names: Sequence[str], team: Sequence[Robot] | int, *,
                 needs: Sequence[Need] | None = None, free: bool = False, allow_refusal: bool = True):
        super().__init__()
        self.names = list(function_names)
        self.team_size = team if isinstance(team, int) else len(team)
        self.allow_refusal = allow_refusal
        self.lines = 0
        teams: list[list[tuple[int, ...]] | None] = [None] * len(self.names)
        if needs is not None and not free and not isinstance(team, int):
            teams = [feasible_teams(team, need) for need in needs]
        # The model decides on refusing unless every sub-task's teams are known.
        self.free = any(t is None for t in teams)
        self.must_refuse = allow_refusal and any(t == [] for t in teams)
        mass = seq(rep(chars(string.digits), 1, 3), opt(seq(".", rep(chars(string.digits), 1, 2))), " kg")
        self.rules: dict[str, Node] = {
            "robot": alt(*(f"robots[{i}]" for i in range(self.team_size))),
            "piece": alt(text_run(REASON_CHARS, self.PIECE), Ref("robot"), mass),
            "refusal": refusal_line(),
        }
        for k, allowed in enumerate(teams):
            if allowed:
                self.rules[f"team-{k}"] = alt(*(" and ".join(f"robots[{i}]" for i in c) for c in allowed))
            else:
                self.rules[f"team-{k}"] = robot_list(self.team_size, 1, " and ")
        self.fixed = [len(self._prefix(k)) + longest(Ref(f"team-{k}"), self.rules) + len("; ") + 1
                      for k in range(len(self.names))]
        self.refusal_len = longest(Ref("refusal"), self.rules)

    def _prefix(self, k: int) -> str:
        return f"# SubTask {k + 1} ({self.names[k]}): "

    def minimum_budget(self) -> int:
        if self.must_refuse:
            return self.refusal_len
        return sum(f + self.PIECE for f in self.fixed)

    def next(self, remaining: int) -> Choose | None:
        k = self.lines
        if self.refusal is not None or k == len(self.names):
            return None
        if self.must_refuse:
            return self._choose(self.rules, {"refusal": Ref("refusal")})
        reserve = sum(f + self.PIECE for f in self.fixed[k + 1:])
        pieces = min(self.MAX_PIECES, (remaining - reserve - self.fixed[k]) // self.PIECE)
        options: dict[str, Node] = {}
        if self.allow_refusal and self.free and self.refusal_len <= remaining:
            options["refusal"] = Ref("refusal")
        options["line"] = seq(self._prefix(k), Ref(f"team-{k}"), "; ", rep(Ref("piece"), 1, max(1, pieces)), "\n")
        return self._choose(self.rules, options)

    def _advance(self, kind: str, piece: str) -> None:
        if kind == "line":
            self.lines += 1
