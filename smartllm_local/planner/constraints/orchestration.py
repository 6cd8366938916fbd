"""A plan's orchestration: which function is launched next, in a thread of the open block or directly, with
which robots (the part of :class:`.plan.PlanConstraint` after the functions are written).

With a world check, functions are launched in the order they were checked in; an allocation's robot lists are
the capable ones (and of those, with a team world, the ones the world allows), none of them booked into another
thread of the open block; with ``together``, a function that can join the block joins it.
"""

from __future__ import annotations

from ..decoding.grammar import Node, Ref, alt, seq
from ..decoding.protocol import Choose
from .feasibility import feasible_lists, minimal_lists, shortest_list
from .format import robot_list
from .written import WrittenFunction


class Orchestration:
    """The orchestration's choices; mixed into :class:`.plan.PlanConstraint`, whose state it reads."""

    def _unlaunched(self) -> list[str]:
        return [f.name for f in self.functions if f.name not in self.launched and f.name not in self.threads]

    def _orch_rules(self, remaining: int) -> dict[str, Node]:
        unlaunched = self._unlaunched()
        # With a world check, functions run in the order they were checked in (a block of threads runs
        # consecutive ones together); otherwise in any order.
        names = unlaunched[:1] if self.world is not None else unlaunched
        index = {f.name: k for k, f in enumerate(self.functions)}
        rules: dict[str, Node] = {}
        if not names:
            return rules
        teams = {n: self._robot_lists(self.functions[index[n]]) for n in names} if self.allocated else {}
        if self.allocated:
            for name, lists in teams.items():
                if lists is not None:
                    rules[f"team-{index[name]}"] = seq("[", lists, "]")
            # (No block is open where a function is called directly: there every function has its lists.)
            direct = [seq(n, "(", Ref(f"team-{index[n]}"), ")\n") for n in names if teams[n] is not None]
            if direct:
                rules["direct"] = alt(*direct)
        else:
            rules["direct"] = alt(*(f"{n}()\n" for n in names))
        n = len(self.threads) + 1
        budget = self.budget
        cost = budget.calls_cost(unlaunched)
        # A function whose every robot list names a robot of the open block waits for the block to end.
        targets = [t for t in names if teams.get(t, True) is not None
                   and budget.thread_len(t, n) + budget.starts_joins(n) + cost - budget.call_len(t) <= remaining]
        if targets:
            if self.allocated:
                rules["target"] = alt(*(seq(f"{t}, args=(", Ref(f"team-{index[t]}"), ",)") for t in targets))
            else:
                rules["target"] = alt(*targets)
        return rules

    def _robot_lists(self, fn: WrittenFunction) -> Node | None:
        """The robot lists a function may be run with: long enough for its robot_list[i], and, when
        the team is known, such that every step has an actor with the skill and the strength.

        In an open block of threads, only robots no thread of the block has: the threads of a block run
        at once, and a robot booked into two of them would make the executor run one after the other
        while the world check counted on the order they were launched in. None when no such list
        exists: the function waits for the block to end (a later block, or a direct call)."""
        need = self._need(fn)
        if self.team is not None:
            lists = self._checked_lists(fn, need)
            if lists or (lists is not None and self.threads):  # none that works in the block: it waits
                free = self._chosen(fn, [o for o in lists if not self.busy.intersection(o)])
                return alt(*(", ".join(f"robots[{i}]" for i in order) for order in free)) if free else None
        free_robots = [i for i in range(self.team_size) if i not in self.busy]
        if len(free_robots) < need:
            return None
        return robot_list(self.team_size, need, ", ", ordered=True, among=free_robots)

    def _chosen(self, fn: WrittenFunction, lists: list[tuple[int, ...]]) -> list[tuple[int, ...]]:
        """Of the lists a function may be run with, those of the team its coalition line chose (see
        :class:`.restated.RestatedAllocation`); all of them here."""
        return lists

    def _checked_lists(self, fn: WrittenFunction, need: int) -> list[tuple[int, ...]] | None:
        """Capable robot lists (and of those, the ones the world allows), kept for this point of the plan.

        Of those, a list adds no robot the function can do without (a robot it does not need stays free
        for another thread of its block)."""
        key = (fn.name, len(self.launched), len(self.threads))  # in a block or not: with a team world, not the same
        if key not in self._lists:
            lists = feasible_lists(self.team, self._steps(fn), need)
            self._lists[key] = minimal_lists(self._working_lists(fn, lists), need) if lists else lists
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
        elif self._unlaunched() and not self._waits(rules):
            self._cap("a thread")
        if "direct" in rules and not (self.joins and "thread" in options):
            options["direct"] = Ref("direct")
        return options

    def _waits(self, rules: dict[str, Node]) -> bool:
        """Whether no function that may come next can join the open block (its robots are all in it): a
        block ends there, not by the budget."""
        return self.allocated and bool(self.threads) and not any(k.startswith("team-") for k in rules)

    def _orch(self, remaining: int) -> Choose | None:
        options = self._orch_options(remaining)
        if not options:
            return None
        return self._choose({**self.rules, **self._orch_rules(remaining)}, options)

    def _threads(self, remaining: int) -> Choose:
        options = {k: v for k, v in self._orch_options(remaining).items() if k == "thread"}
        if not (self.joins and options):
            options["start"] = "t1.start()\n"
        return self._choose({**self.rules, **self._orch_rules(remaining)}, options)

    def _launch(self, name: str, piece: str) -> None:
        """A function was launched with the robot list of ``piece`` (nothing to do without a team world)."""
