"""What the rest of a plan costs at least, in characters (an upper bound on tokens: every token spells
at least one): the plan constraint (:mod:`.plan`) offers a line only if, after the longest text it can
hold, the cheapest completion of the state it leads to still fits what is left."""

from __future__ import annotations

from collections.abc import Callable, Sequence


class Budget:
    """The cheapest functions, calls and thread blocks of a plan with a given team and names."""

    def __init__(self, *, allocated: bool, team_size: int, fixed_names: Sequence[str], fresh_action: int,
                 body_cost: Callable[[int], int]):
        self.allocated = allocated
        self.team_size = team_size
        self.fixed_names = list(fixed_names)
        self.fresh_action = fresh_action
        self.body_cost = body_cost  # the cheapest body of the function at an index (one action, or a restated one)

    def def_cost(self, k: int) -> int:
        """The cheapest k-th function (1-based), its direct call included."""
        if self.fixed_names:
            name = self.fixed_names[k - 1]
            return len(f"def {name}(robot_list):\n") + self.body_cost(k - 1) + 1 + self.call_len(name)
        name = f"subtask{k}_a"
        return len(f"def {name}():\n") + self.fresh_action + 1 + self.call_len(name)

    def summary_after(self, k: int) -> int:
        """The cheapest completion after k summary lines: an order line, the blank, k functions."""
        return len("# x\n") + 1 + sum(self.def_cost(i) for i in range(1, k + 1))

    def calls_cost(self, names: Sequence[str]) -> int:
        return sum(self.call_len(n) for n in names)

    def call_len(self, name: str) -> int:
        """A direct call of a function: ``name()`` or ``name([robots...])`` with the longest list."""
        return len(name) + 3 + (self.robot_list_len(self.team_size) if self.allocated else 0)

    def thread_len(self, name: str, n: int) -> int:
        robots = len(", args=(,)") + self.robot_list_len(self.team_size) if self.allocated else 0
        return len(f"t{n} = threading.Thread(target=") + len(name) + robots + 2

    @staticmethod
    def robot_list_len(n: int) -> int:
        return 2 + sum(len(f"robots[{i}]") for i in range(n)) + max(0, n - 1) * 2

    @staticmethod
    def starts_joins(n: int) -> int:
        return sum(len(f"t{i}.start()\n") + len(f"t{i}.join()\n") for i in range(1, n + 1))
