"""Each stage's output, written one line at a time, every line drawn from a grammar.

A plan has cross-references a context-free grammar cannot express (the
orchestration names functions defined earlier; a thread's robot list must be
long enough for the indices its function uses). So a stage's constraint is a
small state machine: at each point it offers a GBNF grammar for the next line
(built from the scene's object types by affordance, the skills, the team and
what was written so far), or writes boilerplate itself (forced text). The
grammar of a stage is the composition of these line grammars.

Every line grammar is bounded, and before offering a line the constraint
checks that, after the longest such line, the plan can still be completed
within the remaining token budget (a token is at least one ASCII character,
so characters bound tokens). Generation therefore always ends by completing
the plan, never by running out of tokens mid-statement, for any model and any
sampling settings.

Output formats (the prompt examples under prompts/ follow them):

- decomposition: summary lines ``# SubTask k: <what> (skills: A, B)``, an
  order line ``# <how they are ordered>``, a blank line, functions
  ``def subtask<k>_<name>():`` with indented skill calls and comments, then
  the orchestration (threads started and joined together, or direct calls);
- coalition: one line per sub-task, ``# SubTask k (<function>): robots[i] and
  robots[j]; <why>``;
- allocation: the decomposition's functions again, each taking
  ``robot_list`` and naming robots in every call, then the orchestration
  with ``args=([robots[i], ...],)``.

A stage may instead answer with one line ``# INFEASIBLE: <reason>``.
"""

from __future__ import annotations

import re
import string
from abc import ABC, abstractmethod
from itertools import combinations, permutations
from dataclasses import dataclass, field
from typing import Sequence

from ..robots import Robot
from ..skills import SkillSet
from .feasibility import Step, feasible_lists
from .grammar import Grammar, Node, Ref, alt, chars, opt, rep, seq
from .scene_context import SceneObjects

COMMENT_CHARS = frozenset(c for c in string.printable if c not in "\t\n\r\x0b\x0c")
SUMMARY_CHARS = COMMENT_CHARS - set("()")
ORDER_CHARS = COMMENT_CHARS - set(":")  # so the order line cannot pass for one more "# SubTask k: ..."
REASON_CHARS = frozenset(string.ascii_letters + " ,.;:'-")
NAME_FIRST = frozenset(string.ascii_lowercase)
NAME_REST = frozenset(string.ascii_lowercase + string.digits + "_")
COMMENT_LEN = 80
SUMMARY_LEN = 60
ORDER_LEN = 100
REASON_LEN = 100
NAME_LEN = 30
MAX_SUBTASKS = 8
MAX_STEPS = 12
INDENT = "    "
REFUSAL_PREFIX = "# INFEASIBLE: "
EOS = 1  # the end-of-sequence token that closes a stage


@dataclass(frozen=True)
class Forced:
    """Text the constraint writes itself."""

    text: str


@dataclass(frozen=True)
class Choose:
    """The model writes the next line; ``grammar`` admits exactly the allowed lines."""

    grammar: Grammar
    options: dict[str, Grammar]  # the kinds of line allowed, in order of precedence

    def kind_of(self, line: str) -> str:
        """Which kind of line the model wrote (the first whose grammar admits it)."""
        return next((name for name, g in self.options.items() if g.matches(line)), "")


def ordered_subset(items: Sequence[str], separator: str) -> Node:
    """One or more of ``items``, each at most once, in the given order.

    Written as a choice of the first item followed by optional later ones, so
    the grammar (and its regex) grows with the square of the items, not 2^n.
    """
    return alt(*(seq(items[k], *(opt(seq(separator, item)) for item in items[k + 1:])) for k in range(len(items))))


def robot_list(team_size: int, need: int, separator: str, *, ordered: bool = False) -> Node:
    """A list of at least ``need`` distinct robots of the team, written robots[i].

    A set (``ordered=False``) is listed in increasing order; an ordered list
    (where position matters, as robot_list[i] does) may come in any order.
    Teams too big to enumerate (over 6 robots, 5 when ordered) get lists of
    any robots of the right length.
    """
    names = [f"robots[{i}]" for i in range(team_size)]
    if team_size <= (5 if ordered else 6):
        pick = permutations if ordered else combinations
        return alt(*(separator.join(c) for n in range(max(1, need), team_size + 1) for c in pick(names, n)))
    robot = alt(*names)
    return seq(robot, rep(seq(separator, robot), max(0, need - 1), team_size - 1))


def text_run(charset: frozenset[str], length: int) -> Node:
    return rep(chars(charset), 1, length)


def refusal_line() -> Node:
    return seq(REFUSAL_PREFIX, text_run(COMMENT_CHARS, COMMENT_LEN), "\n")


class Constraint(ABC):
    """A stage's output as a sequence of forced text and grammar-chosen lines."""

    def __init__(self) -> None:
        self.text = ""
        self.refusal: str | None = None
        self.grammars: list[str] = []
        self._offered: Choose | None = None

    @abstractmethod
    def next(self, remaining: int) -> Forced | Choose | None:
        """What comes next, given ``remaining`` tokens of budget; None when the output is complete."""

    def feed(self, piece: str) -> None:
        """Record what was written (forced text, or the model's line; "" means it ended the output)."""
        offered, self._offered = self._offered, None
        kind = "forced" if offered is None else offered.kind_of(piece)
        if offered is not None and not kind:
            raise ValueError(f"the line {piece!r} is not one the grammar offered")
        self.text += piece
        if kind == "refusal":
            self.refusal = piece[len(REFUSAL_PREFIX):].strip()
        self._advance(kind, piece)

    @abstractmethod
    def _advance(self, kind: str, piece: str) -> None:
        """Move the state machine on after a line of a given kind."""

    @abstractmethod
    def minimum_budget(self) -> int:
        """The fewest tokens that always suffice to complete an output from the start."""

    def _choose(self, rules: dict[str, Node], options: dict[str, Node]) -> Choose:
        grammar = Grammar({**rules, "root": alt(*options.values())})
        text = grammar.to_gbnf()
        if not self.grammars or self.grammars[-1] != text:
            self.grammars.append(text)
        self._offered = Choose(grammar, {k: Grammar({**rules, "root": v}) for k, v in options.items()})
        return self._offered


def longest(node: Node, rules: dict[str, Node]) -> int:
    return Grammar({**rules, "root": node}).max_length()


KNIVES = frozenset({"Knife", "ButterKnife"})
# Actions that set a state, and the action that undoes each.
_STATE_ACTIONS = {"OpenObject": "CloseObject", "CloseObject": "OpenObject",
                  "ToggleObjectOn": "ToggleObjectOff", "ToggleObjectOff": "ToggleObjectOn"}
_CALL = re.compile(r"^\s+(\w+)\((?:robot_list(?:\[(\d+)\])?, )?'([^']+)'(?:, '([^']+)')?\)$")


@dataclass
class _Function:
    name: str
    steps: int = 0
    max_index: int = -1  # the highest robot_list[i] used; -1: none (robot_list alone counts as 0)
    last: str = ""  # the kind of the last line: "action", "goto", "sleep" or "comment"
    comments: int = 0
    held: set[str] = field(default_factory=set)  # object types picked up and not yet put down
    states: dict[str, str] = field(default_factory=dict)  # type -> the last state action on it
    last_call: tuple[str, str] = ("", "")  # (AI2-THOR action, object) of the last step
    calls: list[tuple[int | None, str, str]] = field(default_factory=list)  # (robot_list slot, skill, object)

    def track(self, line: str, actions: dict[str, str]) -> None:
        match = _CALL.match(line.rstrip("\n"))
        if not match:
            self.last_call = ("", "")
            return
        skill, first = match.group(1), match.group(3)
        slot = int(match.group(2)) if match.group(2) is not None else None
        self.calls.append((slot, skill, first))
        action = actions.get(skill, "")
        self.last_call = (action, first)
        if action == "PickupObject":
            self.held.add(first)
        elif action in ("PutObject", "DropHandObject", "ThrowObject"):
            self.held.discard(first)
        elif action in _STATE_ACTIONS:
            self.states[first] = action


class PlanConstraint(Constraint):
    """Stage 1 (decomposed) and stage 3 (allocated) plans.

    Beyond syntax, the constraint keeps the plan's shape sensible: a function
    ends with an action (not a bare GoToObject), a summary lists distinct
    skills in the vocabulary's order, and the orchestration launches every
    function exactly once, in threads or directly, then stops.
    """

    def __init__(
        self,
        scene: SceneObjects,
        skills: SkillSet,
        *,
        team_size: int | None = None,
        comments: bool = True,
        summary: bool = True,
        function_names: Sequence[str] | None = None,
        max_subtasks: int = MAX_SUBTASKS,
        max_steps: int = MAX_STEPS,
        allow_refusal: bool = True,
        team: Sequence[Robot] | None = None,
    ):
        super().__init__()
        if team is not None:
            team_size = len(team)
        self.team = list(team) if team is not None else None
        self.allocated = team_size is not None
        self.team_size = team_size or 0
        self.comments = comments
        self.summary = summary and not self.allocated and not function_names
        self.fixed_names = list(function_names or [])
        self.max_subtasks = len(self.fixed_names) or max_subtasks
        self.max_steps = max(2, max_steps)
        self.allow_refusal = allow_refusal
        self.rules: dict[str, Node] = {}
        self.rules = self._vocabulary(scene, skills)
        self.phase = "start"
        self.summary_lines = 0
        self.owed = len(self.fixed_names) or None  # defs promised (by the summary, or the decomposition)
        self.functions: list[_Function] = []
        self.launched: list[str] = []
        self.threads: list[str] = []  # targets of the block being written
        self.pending = ""  # boilerplate to write next (the rest of a block's starts and joins)
        self._lengths()

    # ----------------------------------------------------------- vocabulary

    def _vocabulary(self, scene: SceneObjects, skills: SkillSet) -> dict[str, Node]:
        rules: dict[str, Node] = {}
        self.scene = scene
        self.skills = [s for s in skills.values()
                       if all(scene.types_for(a) for a in s.arguments[: s.required])]
        self.skill_names = [s.name for s in self.skills]
        self.skill_actions = {s.name: s.action for s in self.skills}
        if self.allocated:
            rules["robot-arg"] = alt("robot_list", *(f"robot_list[{i}]" for i in range(self.team_size)))
        goto = [s for s in self.skills if s.action == ""]
        if not goto or len(goto) == len(self.skills):
            raise ValueError("the skills cannot act on any object of this scene")
        rules["goto"] = alt(*(self._call(s, [scene.types_for(a) for a in s.arguments]) for s in goto))
        rules["action"] = self._actions(_Function(""))
        rules["sleep"] = seq(INDENT, "time.sleep(", chars("123456789"), ")\n")
        rules["comment"] = seq(INDENT, "# ", text_run(COMMENT_CHARS, COMMENT_LEN), "\n")
        rules["refusal"] = refusal_line()
        rules["skills"] = ordered_subset(self.skill_names, ", ")
        return rules

    def _call(self, skill, arg_types: Sequence[Sequence[str]]) -> Node:
        """One skill call line with each object argument drawn from its list of types."""
        parts: list[Node | str] = [INDENT, f"{skill.name}("]
        if self.allocated:
            parts += [Ref("robot-arg"), ", "]
        for i, types in enumerate(arg_types):
            arg = alt(*(f"'{t}'" for t in types))
            if i < skill.required:
                parts += ([", "] if i else []) + [arg]
            else:
                parts.append(opt(seq(", ", arg)))
        parts.append(")\n")
        return seq(*parts)

    def _actions(self, fn: "_Function") -> Node:
        """The action lines whose preconditions the function's own steps do not rule out.

        Put, drop and throw only what the function holds; pick up what it does not
        hold; slice only with a knife in hand; do not switch on what it switched on
        (or open what it opened), and do not undo the step just taken.
        """
        lines = []
        for skill in self.skills:
            if skill.action == "":
                continue
            types = [list(self.scene.types_for(a)) for a in skill.arguments]
            if skill.action in ("PutObject", "DropHandObject", "ThrowObject"):
                types[0] = [t for t in types[0] if t in fn.held]
                if len(types) > 1:
                    types[1] = [t for t in types[1] if t not in fn.held]
            elif skill.action == "PickupObject":
                types[0] = [t for t in types[0] if t not in fn.held]
            elif skill.action == "SliceObject" and not fn.held & KNIVES:
                continue
            elif skill.action in _STATE_ACTIONS:
                types[0] = [t for t in types[0] if fn.states.get(t) != skill.action
                            and fn.last_call != (_STATE_ACTIONS[skill.action], t)]
            if all(types[: skill.required]):
                lines.append(self._call(skill, [t for t in types if t]))
        if not lines:  # nothing the state allows: any action (still a valid plan)
            return self.rules["action"]
        return alt(*lines)

    def _header(self, k: int) -> Node:
        params = "robot_list" if self.allocated else ""
        return seq(f"def subtask{k}_", chars(NAME_FIRST), rep(chars(NAME_REST), 0, NAME_LEN - 1), f"({params}):\n")

    def _summary_line(self, k: int) -> Node:
        return seq(f"# SubTask {k}: ", text_run(SUMMARY_CHARS, SUMMARY_LEN), " (skills: ", Ref("skills"), ")\n")

    def _lengths(self) -> None:
        r = self.rules
        self.action_len = longest(Ref("action"), r)
        self.goto_len = max(longest(Ref("goto"), r), longest(Ref("sleep"), r))
        self.comment_len = longest(Ref("comment"), r)
        name_len = max((len(n) for n in self.fixed_names), default=len("subtask9_") + NAME_LEN)
        robots_len = self._robot_list_len(self.team_size) if self.allocated else 0
        self.thread_len = len("t9 = threading.Thread(target=") + name_len + len(", args=(,)") * self.allocated \
            + robots_len + 2
        self.call_len = name_len + robots_len + 3
        self.header_len = max((len(f"def {n}(robot_list):\n") for n in self.fixed_names),
                              default=longest(self._header(self.max_subtasks), r))
        self.def_min = self.header_len + self.action_len + 1 + self.call_len  # a def with one action, launched
        self.summary_len = longest(self._summary_line(9), r)
        self.order_len = len("# ") + ORDER_LEN + 1
        self.refusal_len = longest(Ref("refusal"), r)

    @staticmethod
    def _robot_list_len(n: int) -> int:
        return 2 + n * len("robots[15]") + max(0, n - 1) * 2

    def minimum_budget(self) -> int:
        if self.summary:
            return self.summary_len + self.order_len + 1 + self.def_min
        return max(self.refusal_len, self.def_min * max(1, len(self.fixed_names)))

    # ---------------------------------------------------------------- costs

    def _unlaunched(self) -> list[str]:
        return [f.name for f in self.functions if f.name not in self.launched and f.name not in self.threads]

    def _owed_defs(self) -> int:
        return max(0, (self.owed or 0) - len(self.functions))

    def _finish(self, after_action: bool) -> int:
        """Worst-case cost to complete from inside a body: an action if due, the blank line,
        the defs still owed, and a direct call for every function not launched yet."""
        return (0 if after_action else self.action_len) + 1 + self._owed_defs() * self.def_min \
            + len(self._unlaunched()) * self.call_len

    @staticmethod
    def _starts_joins(n: int) -> int:
        return sum(len(f"t{i}.start()\n") + len(f"t{i}.join()\n") for i in range(1, n + 1))

    # ------------------------------------------------------------- choices

    def next(self, remaining: int) -> Forced | Choose | None:
        if self.pending:
            return Forced(self.pending)
        handler = {
            "start": self._start, "summary": self._summary, "header": self._header_choice, "body": self._body,
            "orch": self._orch, "threads": self._threads,
        }.get(self.phase)
        if self.phase == "order-blank":
            return Forced("\n")
        return handler(remaining) if handler else None

    def _start(self, remaining: int) -> Choose:
        options: dict[str, Node] = {}
        if self.allow_refusal:
            options["refusal"] = Ref("refusal")
        if self.summary:
            options["summary"] = self._summary_line(1)
        elif self.fixed_names:
            options["header"] = f"def {self.fixed_names[0]}(robot_list):\n"
        else:
            options["header"] = self._header(1)
        return self._choose(self.rules, options)

    def _summary(self, remaining: int) -> Choose:
        options: dict[str, Node] = {}
        k = self.summary_lines
        after = self.order_len + 1 + (k + 1) * self.def_min
        if k < self.max_subtasks and self.summary_len + after <= remaining:
            options["summary"] = self._summary_line(k + 1)
        options["order"] = seq("# ", text_run(ORDER_CHARS, ORDER_LEN), "\n")
        return self._choose(self.rules, options)

    def _header_choice(self, remaining: int) -> Forced | Choose | None:
        k = len(self.functions) + 1
        if self.fixed_names:
            return Forced(f"def {self.fixed_names[k - 1]}(robot_list):\n")
        if self.owed:
            return self._choose(self.rules, {"header": self._header(k)})
        options: dict[str, Node] = {}
        if k <= self.max_subtasks and self.def_min + len(self._unlaunched()) * self.call_len <= remaining:
            options["header"] = self._header(k)
        options.update(self._orch_options(remaining))
        return self._choose({**self.rules, **self._orch_rules()}, options)

    def _body(self, remaining: int) -> Choose:
        fn = self.functions[-1]
        options: dict[str, Node] = {}
        room = fn.steps < self.max_steps - 1  # leave a step for the closing action
        if room and self.goto_len + self._finish(False) <= remaining:
            if fn.last != "goto":  # going somewhere twice in a row is never useful
                options["goto"] = Ref("goto")
            if fn.last_call[0] == "ToggleObjectOn":  # waiting only makes sense for something just switched on
                options["sleep"] = Ref("sleep")
        if fn.steps < self.max_steps and self.action_len + self._finish(True) <= remaining:
            options["action"] = self._actions(fn)
        # Line-by-line comments: at most one before each step.
        if self.comments and fn.last != "comment" and fn.steps < self.max_steps and fn.comments <= fn.steps and \
                self.comment_len + self.action_len + self._finish(True) <= remaining:
            options["comment"] = Ref("comment")
        if fn.last == "action":
            options["end"] = "\n"
        if not options:
            options["action"] = self._actions(fn)  # budget invariants make this unreachable; stay valid anyway
        return self._choose(self.rules, options)

    def _orch_rules(self) -> dict[str, Node]:
        names = self._unlaunched()
        index = {f.name: k for k, f in enumerate(self.functions)}
        rules: dict[str, Node] = {}
        if not names:
            return rules
        if self.allocated:
            for name in names:
                rules[f"team-{index[name]}"] = seq("[", self._robot_lists(self.functions[index[name]]), "]")
            rules["target"] = alt(*(seq(f"{n}, args=(", Ref(f"team-{index[n]}"), ",)") for n in names))
            rules["direct"] = alt(*(seq(n, "(", Ref(f"team-{index[n]}"), ")\n") for n in names))
        else:
            rules["target"] = alt(*names)
            rules["direct"] = alt(*(f"{n}()\n" for n in names))
        return rules

    def _robot_lists(self, fn: _Function) -> Node:
        """The robot lists a function may be run with: long enough for its robot_list[i], and, when
        the team is known, such that every step has an actor with the skill and the strength."""
        need = max(1, fn.max_index + 1)
        if self.team is not None:
            pickups = {s.name for s in self.skills if s.action == "PickupObject"}
            steps = [Step(slot, skill, self.scene.masses.get(obj, 0.0) if skill in pickups else 0.0)
                     for slot, skill, obj in fn.calls]
            lists = feasible_lists(self.team, steps, need)
            if lists:
                return alt(*(", ".join(f"robots[{i}]" for i in order) for order in lists))
        return robot_list(self.team_size, need, ", ", ordered=True)

    def _orch_options(self, remaining: int) -> dict[str, Node]:
        left = len(self._unlaunched())
        options: dict[str, Node] = {}
        if left and self.thread_len + self._starts_joins(1) + (left - 1) * self.call_len <= remaining:
            options["thread"] = seq("t1 = threading.Thread(target=", Ref("target"), ")\n")
        if left:
            options["direct"] = Ref("direct")
        return options

    def _orch(self, remaining: int) -> Choose | None:
        options = self._orch_options(remaining)
        if not options:
            return None
        return self._choose({**self.rules, **self._orch_rules()}, options)

    def _threads(self, remaining: int) -> Choose:
        n = len(self.threads)
        left = len(self._unlaunched())
        options: dict[str, Node] = {}
        if left and self.thread_len + self._starts_joins(n + 1) + (left - 1) * self.call_len <= remaining:
            options["thread"] = seq(f"t{n + 1} = threading.Thread(target=", Ref("target"), ")\n")
        options["start"] = "t1.start()\n"
        return self._choose({**self.rules, **self._orch_rules()}, options)

    # --------------------------------------------------------------- feeding

    def _advance(self, kind: str, piece: str) -> None:
        if kind == "refusal":
            self.phase = "done"
        elif kind == "summary":
            self.summary_lines += 1
            self.owed = self.summary_lines
            self.phase = "summary"
        elif kind == "order":
            self.phase = "order-blank"
        elif kind == "forced" and self.pending:
            self.pending = ""
            self.phase = "orch" if self._unlaunched() else "done"
        elif kind == "forced" and self.phase == "order-blank":
            self.phase = "header"
        elif kind == "header" or (kind == "forced" and piece.startswith("def ")):
            self.functions.append(_Function(piece[4:piece.index("(")]))
            self.phase = "body"
        elif kind in ("goto", "sleep", "action", "comment"):
            fn = self.functions[-1]
            fn.last = kind
            if kind != "comment":
                fn.steps += 1
            else:
                fn.comments += 1
            if kind == "action":
                fn.track(piece, self.skill_actions)
            elif kind in ("goto", "sleep"):
                fn.last_call = ("", "")
                match = _CALL.match(piece.rstrip("\n"))
                if match:
                    fn.calls.append((int(match.group(2)) if match.group(2) else None, match.group(1), match.group(3)))
            for i in range(self.team_size):
                if f"robot_list[{i}]" in piece:
                    fn.max_index = max(fn.max_index, i)
        elif kind == "end":
            done = self.owed is not None and len(self.functions) >= self.owed
            self.phase = "orch" if done else "header"
        elif kind == "start":
            n = len(self.threads)
            self.launched += self.threads
            self.threads = []
            self.pending = "".join(f"t{i}.start()\n" for i in range(2, n + 1))
            self.pending += "".join(f"t{i}.join()\n" for i in range(1, n + 1))
        elif kind == "thread":
            self.threads.append(piece.split("target=", 1)[1].split(",")[0].split(")")[0])
            self.phase = "threads"
        elif kind == "direct":
            self.launched.append(piece.split("(", 1)[0])
            self.phase = "orch" if self._unlaunched() else "done"
