"""The orchestration of a plan under construction: launching every function exactly once, in a
block of threads or directly, with the robot lists each may take; and what those lines cost.

A mixin of :class:`.plan_constraint.PlanConstraint`, which holds the state it reads: the
functions written, those launched and those in the block being written, the team and the
world check. With a world check, functions are launched in the order they were checked in.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

from .constraints import Choose, robot_list
from .feasibility import feasible_lists, shortest_list
from .grammar import Node, Ref, alt, seq

if TYPE_CHECKING:
    from .plan_constraint import PlanConstraint as _Base
    from .plan_constraint import WrittenFunction
else:
    _Base = object


class Orchestration(_Base):
    """Launch lines (``t1 = threading.Thread(...)``, ``f([robots[0]])``), their robot lists and costs."""

    def _unlaunched(self) -> list[str]:
        return [f.name for f in self.functions if f.name not in self.launched and f.name not in self.threads]

    def _calls_cost(self, names: Sequence[str]) -> int:
        return sum(self._call_len(n) for n in names)

    def _call_len(self, name: str) -> int:
        """A direct call of a function: ``name()`` or ``name([robots...])`` with the longest list."""
        return len(name) + 3 + (self._robot_list_len(self.team_size) if self.allocated else 0)

    def _thread_len(self, name: str, n: int) -> int:
        robots = len(", args=(,)") + self._robot_list_len(self.team_size) if self.allocated else 0
        return len(f"t{n} = threading.Thread(target=") + len(name) + robots + 2

    @staticmethod
    def _robot_list_len(n: int) -> int:
        return 2 + sum(len(f"robots[{i}]") for i in range(n)) + max(0, n - 1) * 2

    @staticmethod
    def _starts_joins(n: int) -> int:
        return sum(len(f"t{i}.start()\n") + len(f"t{i}.join()\n") for i in range(1, n + 1))

    def _orch_rules(self, remaining: int) -> dict[str, Node]:
        unlaunched = self._unlaunched()
        # With a world check, functions run in the order they were checked in (a block of threads runs
        # consecutive ones together); otherwise in any order.
        names = unlaunched[:1] if self.world is not None else unlaunched
        index = {f.name: k for k, f in enumerate(self.functions)}
        rules: dict[str, Node] = {}
        if not names:
            return rules
        if self.allocated:
            for name in names:
                rules[f"team-{index[name]}"] = seq("[", self._robot_lists(self.functions[index[name]]), "]")
            rules["direct"] = alt(*(seq(n, "(", Ref(f"team-{index[n]}"), ")\n") for n in names))
        else:
            rules["direct"] = alt(*(f"{n}()\n" for n in names))
        n = len(self.threads) + 1
        cost = self._calls_cost(unlaunched)
        targets = [t for t in names
                   if self._thread_len(t, n) + self._starts_joins(n) + cost - self._call_len(t) <= remaining]
        if targets:
            if self.allocated:
                rules["target"] = alt(*(seq(f"{t}, args=(", Ref(f"team-{index[t]}"), ",)") for t in targets))
            else:
                rules["target"] = alt(*targets)
        return rules

    def _robot_lists(self, fn: WrittenFunction) -> Node:
        """The robot lists a function may be run with: long enough for its robot_list[i], and, when
        the team is known, such that every step has an actor with the skill and the strength."""
        need = self._need(fn)
        if self.team is not None:
            lists = self._checked_lists(fn, need)
            if lists:
                return alt(*(", ".join(f"robots[{i}]" for i in order) for order in lists))
        return robot_list(self.team_size, need, ", ", ordered=True)

    def _checked_lists(self, fn: WrittenFunction, need: int) -> list[tuple[int, ...]] | None:
        """Capable robot lists (and of those, the ones the world allows), kept for this point of the plan."""
        key = (fn.name, len(self.launched) + len(self.threads))
        if key not in self._lists:
            lists = feasible_lists(self.team, self._steps(fn), need)
            self._lists[key] = self._working_lists(fn, lists) if lists else lists
        return self._lists[key]

    def _working_lists(self, fn: WrittenFunction, lists: list[tuple[int, ...]]) -> list[tuple[int, ...]]:
        """Of the capable robot lists, those the world allows (all, without a team world check)."""
        return lists

    def _need(self, fn: WrittenFunction) -> int:
        """How many robots the function's list needs (see :func:`.feasibility.shortest_list`)."""
        return shortest_list(fn.whole, fn.max_index, self.team_size,
                             notional=self.world is not None and not self._team_checks_lists())

    def _team_checks_lists(self) -> bool:
        """Whether each robot list is dry-run with the team's own robots (see :func:`.feasibility.shortest_list`)."""
        return False

    def _orch_options(self, remaining: int) -> dict[str, Node]:
        rules = self._orch_rules(remaining)
        options: dict[str, Node] = {}
        if "target" in rules:
            options["thread"] = seq(f"t{len(self.threads) + 1} = threading.Thread(target=", Ref("target"), ")\n")
        elif self._unlaunched():
            self._cap("a thread")
        if "direct" in rules:
            options["direct"] = Ref("direct")
        return options

    def _orch(self, remaining: int) -> Choose | None:
        options = self._orch_options(remaining)
        if not options:
            return None
        return self._choose({**self.rules, **self._orch_rules(remaining)}, options)

    def _threads(self, remaining: int) -> Choose:
        options = {k: v for k, v in self._orch_options(remaining).items() if k == "thread"}
        options["start"] = "t1.start()\n"
        return self._choose({**self.rules, **self._orch_rules(remaining)}, options)

    def _launch(self, name: str, piece: str) -> None:
        """A function was launched with the robot list of ``piece`` (nothing to do without a team world)."""
