"""Stage 2's constraint: the coalition policy, one comment line per sub-task, reasoning first.

As in the paper's coalition policy, a line analyses before it decides: what the
sub-task needs (its skills, sorted, and the mass of the heaviest thing it picks up),
then which robots have what and what is missing, and only then, after ``; so``, the
robot or team. One line, shown here broken in two::

    # SubTask 1 (subtask1_book_to_bed): needs GoToObject, PickupObject, PutObject, lifting 0.5 kg;
      robots[0] and robots[1] both have these skills and lift 100 kg, so one is enough; so robots[0]

Where one team is left, the planner writes the analysis too: the fact that leaves it (``only robots[0] can do it``).
"""

from __future__ import annotations

import re
import string
from collections.abc import Collection, Sequence

from ...robots import Robot
from ..decoding.grammar import Node, Ref, alt, chars, opt, rep, seq
from ..decoding.line_ends import COMMENT_NEXT
from ..decoding.protocol import REFUSAL_PREFIX, Choose, Constraint, Forced, longest
from .feasibility import Need, feasible_teams, minimal_teams, shortfall
from .format import REASON_CHARS, refusal_line, robot_list, text_run
from .written import robots_named

# A word of free text: letters and punctuation, never the ";" that ends a part of the line.
WORD_CHARS = REASON_CHARS - {" ", ";"}
#: A coalition line's shape (for text written without the grammar): prefix, needs, analysis, team.
#: The team a written line ends with.
_TEAM = re.compile(r"; so (robots\[\d+\](?: and robots\[\d+\])*)\n?$")
LINE = re.compile(r"^(# SubTask \d+ \(\w+\): )needs ([^;\n]+); ([^;\n]+); so (robots\[\d+\](?: and robots\[\d+\])*)$",
                  re.M)
_NAME = re.compile(r"\((\w+)\)")


def chosen_teams(coalition: str) -> dict[str, frozenset[int]]:
    """The team each sub-task's line chose, by function name (none for a refusal or free text that is no line)."""
    return {_NAME.search(m.group(1)).group(1): frozenset(robots_named(m.group(4)))  # type: ignore[union-attr]
            for m in LINE.finditer(coalition)}


def needs_clause(need: Need) -> str:
    """What a sub-task needs, as the line states it (the examples' coalitions follow it): its skills, the
    mass it lifts, and on a site what it pools and the places only some robot kinds reach."""
    mass = f", lifting {need.mass:g} kg" if need.mass > 0 else ""
    demands = sorted(need.demands, key=lambda d: (d.place.name, d.skill))
    pooled = [f", pooling {d.amount:g} {d.capacity}" for d in demands if d.capacity and d.capacity != "camera_range"]
    reach = dict.fromkeys(f", reaching {d.place.name} ({' or '.join(sorted(d.place.reach))} robots only)"
                          for d in demands if d.place.reach is not None)
    return f"needs {', '.join(sorted(need.skills))}{mass}{''.join(pooled)}{''.join(reach)};"


class CoalitionConstraint(Constraint):
    """Stage 2: per sub-task, ``needs <skills and mass>; <analysis>; so <team>``.

    The team comes last: nothing before ``; so`` can name it, since the needs
    name no robot and no word of free text holds a ``;``. Robots are named only
    as ``robots[i]`` with i inside the team: free text admits no digits or
    brackets, except in a mass (``2.5 kg``). With the sub-tasks' needs known,
    the constraint writes each needs clause itself (the catalogue's facts), a
    line admits only teams that can do the sub-task, and when some sub-task has
    none the only answer is a refusal that says which and what it lacks (the
    catalogue's reason, not the model's); ``free=True`` leaves the needs, the
    team and refusing to the model.

    Free text is words (a run of letters and punctuation, a robot or a mass)
    separated by single spaces, so a line parses one way only. The analysis
    runs to MAX_WORDS words (the needs the model writes, to MAX_NEED_WORDS),
    fewer when the budget left must also cover the lines still to come.
    """

    WORD = 16  # longest run of letters and punctuation in a word ("DropHandObject," is 15)
    MAX_WORDS = 40
    MAX_NEED_WORDS = 12

    def __init__(self, function_names: Sequence[str], team: Sequence[Robot] | int, *,
                 needs: Sequence[Need] | None = None, free: bool = False, allow_refusal: bool = True,
                 blocks: Sequence[Collection[int]] = ()):
        """``blocks``: the sub-tasks (by index) the plan starts at once, each block's teams kept apart where they
        can be (:meth:`_apart`)."""
        super().__init__()
        self.names = list(function_names)
        self.team_size = team if isinstance(team, int) else len(team)
        self.allow_refusal = allow_refusal
        self.lines = 0
        self.head_written = False
        teams: list[list[tuple[int, ...]] | None] = [None] * len(self.names)
        known = needs is not None and not free and not isinstance(team, int)
        if known:
            teams = [minimal_teams(feasible_teams(team, need)) for need in needs]  # type: ignore[arg-type, union-attr]
        self.teams, self.blocks = teams, [set(b) for b in blocks]
        self.chosen: dict[int, frozenset[int]] = {}
        # The model states the needs unless every sub-task's teams are known.
        self.free = any(t is None for t in teams)
        # With the needs known, whether some sub-task has no team is known too, and why (the refusal says
        # so, not the model); otherwise the model decides on refusing.
        self.why = refusal_reason(self.names, team, needs) if known else ""  # type: ignore[arg-type]
        self.model_refuses = allow_refusal and not known
        self.must_refuse = allow_refusal and bool(self.why)
        clauses = ["needs "] * len(self.names) if self.free else [needs_clause(n) for n in needs or ()]
        self.heads = [self._prefix(k) + clauses[k] for k in range(len(self.names))]
        # A robot or a mass may be followed by punctuation or a possessive: "2.1 kg," "robots[1]'s".
        suffix = opt(alt(",", ".", ":", "'s"))
        mass = seq(rep(chars(string.digits), 1, 3), opt(seq(".", rep(chars(string.digits), 1, 3))), " kg", suffix)
        self.rules: dict[str, Node] = {
            "robot": alt(*(f"robots[{i}]" for i in range(self.team_size))),
            "need-word": alt(text_run(WORD_CHARS, self.WORD), mass),
            "word": alt(text_run(WORD_CHARS, self.WORD), seq(Ref("robot"), suffix), mass),
            "refusal": f"{REFUSAL_PREFIX}{self.why}\n" if self.why else refusal_line(),
        }
        for k, allowed in enumerate(teams):
            if allowed:
                self.rules[f"team-{k}"] = alt(*map(_named, allowed))
            else:
                self.rules[f"team-{k}"] = robot_list(self.team_size, 1, " and ")
        self.word_len = longest(Ref("word"), self.rules) + 1  # a word and the space before it
        # A line's length but for its words, and the fewest words it can have.
        self.fixed = [len(self.heads[k]) + len(";" if self.free else "") + len(" ; so ")
                      + longest(Ref(f"team-{k}"), self.rules) + len("\n") for k in range(len(self.names))]
        self.min_words = 2 if self.free else 1
        self.refusal_len = longest(Ref("refusal"), self.rules)

    def _prefix(self, k: int) -> str:
        return f"# SubTask {k + 1} ({self.names[k]}): "

    def _shortest_line(self, k: int) -> int:
        return self.fixed[k] + self.min_words * self.word_len

    def minimum_budget(self) -> int:
        if self.must_refuse:
            return self.refusal_len
        return sum(self._shortest_line(k) for k in range(len(self.names)))

    def next(self, remaining: int) -> Forced | Choose | None:
        k = self.lines
        if self.refusal is not None or k == len(self.names):
            return None
        if self.must_refuse:
            return self._choose(self.rules, {"refusal": Ref("refusal")})
        if not self.free and not self.head_written:
            return Forced(self.heads[k])
        reserve = sum(self._shortest_line(j) for j in range(k + 1, len(self.names)))
        spent = len(self.heads[k]) if self.head_written else 0
        # The reserves keep this at least min_words; the max keeps the grammar valid regardless.
        words = max(self.min_words, (remaining - reserve - (self.fixed[k] - spent)) // self.word_len)
        options: dict[str, Node] = {}
        if self.model_refuses and self.refusal_len <= remaining:
            options["refusal"] = Ref("refusal")
        # The model's needs, when it writes them, take at most a quarter of the words.
        need_words = min(self.MAX_NEED_WORDS, max(1, words // 4)) if self.free else 0
        tail = (" ", _words(Ref("word"), min(self.MAX_WORDS, words - need_words)), "; so ", Ref(f"team-{k}"), "\n")
        apart = self._apart(k)
        sole = self._sole_tail(k, apart)
        if sole is not None and len(sole) <= remaining - reserve:
            options["line"] = seq(sole)  # one way to write it: the writer carries it, as forced text
        elif self.free:
            options["line"] = seq(self.heads[k], _words(Ref("need-word"), need_words), ";", *tail)
        else:
            options["line"] = seq(*tail)
        rules = {**self.rules, f"team-{k}": alt(*map(_named, apart))} if apart else self.rules
        # Another line follows (its "# SubTask"), or the output ends.
        return self._choose(rules, options, {"line": COMMENT_NEXT} if k + 1 < len(self.names) else {})

    def _sole_tail(self, k: int, apart: list[tuple[int, ...]]) -> str | None:
        """Where one team is left for sub-task ``k``, the rest of its line: the fact that leaves it, then the team
        (None where the model has a team to choose). Words about a choice there is none of cost a chosen token
        each (the 1.5B spent ~30 on "robots[0] and robots[1] both have these skills..." and then named the one
        team the line admitted); the planner states the fact in one batch."""
        teams = apart or self.teams[k]
        if self.free or teams is None or len(teams) != 1:
            return None
        team = teams[0]
        named = _named(team)
        if apart and len(self.teams[k] or ()) > 1:
            fact = f"only {named} can do it while the sub-tasks beside it run"
        elif len(team) == 1:
            fact = f"only {named} can do it"
        else:
            fact = f"no robot can do it alone, but {named} together can"
        return f" {fact}; so {named}\n"

    def _apart(self, k: int) -> list[tuple[int, ...]]:
        """Sub-task ``k``'s teams that leave the others its block starts at once a team each, no robot in two, with
        the teams chosen before (none where there are no such teams, or no block: every team of it is offered).
        Asked to put a 1 kg statue and an alarm clock on the bed with robots of 0.9 and 0.4 kg and one that only
        helps lift, the 1.5B gave the statue the two that pick up, and the clock's sub-task waited for them (RU 0;
        dev7-c3): robots 8 and 24 lift the statue while robot 28 carries the clock."""
        block = next((b for b in self.blocks if k in b), None)
        teams = self.teams
        if block is None or any(teams[j] is None for j in block):
            return []
        taken = frozenset().union(*(self.chosen.get(j, frozenset()) for j in block))
        later = [teams[j] for j in sorted(block) if j > k]

        def fits(used: frozenset[int], rest: list) -> bool:
            return not rest or any(not used & set(t) and fits(used | set(t), rest[1:]) for t in rest[0])

        return [t for t in teams[k] or () if not taken & set(t) and fits(taken | set(t), later)]

    def _advance(self, kind: str, piece: str) -> None:
        if kind == "forced":
            self.head_written = True
        elif kind == "line":
            team = _TEAM.search(piece)
            if team is not None:
                self.chosen[self.lines] = frozenset(int(i) for i in re.findall(r"\d+", team.group(1)))
            self.lines += 1
            self.head_written = False


def refusal_reason(names: Sequence[str], team: Sequence[Robot], needs: Sequence[Need]) -> str:
    """Why no robot or team can do the plan, from the catalogue: each sub-task that even the whole team
    cannot do, and what it lacks (see :func:`.feasibility.shortfall`); "" when every sub-task has a team."""
    parts = [f"SubTask {k} ({name}): {' and '.join(reasons)}"
             for k, (name, need) in enumerate(zip(names, needs), start=1) if (reasons := shortfall(team, need))]
    return "; ".join(parts)


def _named(team: Sequence[int]) -> str:
    """A team as a line names it: ``robots[1] and robots[2]``."""
    return " and ".join(f"robots[{i}]" for i in team)


def _words(word: Node, most: int) -> Node:
    return seq(word, rep(seq(" ", word), 0, most - 1))
