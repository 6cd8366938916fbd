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

import string
from abc import ABC, abstractmethod
from dataclasses import dataclass, field
from typing import Sequence

from ..skills import SkillSet
from .grammar import Grammar, Node, Ref, alt, chars, opt, rep, seq
from .scene_context import SceneObjects

COMMENT_CHARS = frozenset(c for c in string.printable if c not in "\t\n\r\x0b\x0c")
SUMMARY_CHARS = COMMENT_CHARS - set("()")
REASON_CHARS = frozenset(string.ascii_letters + " ,.;:'-")
NAME_FIRST = frozenset(string.ascii_lowercase)
NAME_REST = frozenset(string.ascii_lowercase + string.digits + "_")
COMMENT_LEN = 80
SUMMARY_LEN = 60
ORDER_LEN = 100
REASON_LEN = 100
NAME_LEN = 30
MAX_SUBTASKS = 8
MAX_STEPS = 16
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


def robot_chains(team_size: int, separator: str) -> dict[str, Node]:
    """Rules for lists of distinct robots in increasing order, at least ``need`` long.

    ``robots-from-i-need-n`` starts with some robots[j], j >= i, and holds at
    least n robots; the rules refer only to higher indices, so they never recurse.
    """
    rules: dict[str, Node] = {}
    for i in reversed(range(team_size)):
        for need in range(0, team_size - i + 1):
            options: list[Node] = []
            for j in range(i, team_size):
                rest_need = max(0, need - 1)
                if team_size - (j + 1) < rest_need:
                    continue
                head = f"robots[{j}]"
                if j + 1 < team_size:
                    tail = Ref(f"robots-from-{j + 1}-need-{rest_need}")
                    more = seq(head, separator, tail)
                    options.append(more if rest_need else alt(head, more))
                elif rest_need == 0:
                    options.append(head)
            if options:
                rules[f"robots-from-{i}-need-{need}"] = alt(*options)
    return rules


def _text(charset: frozenset[str], length: int) -> Node:
    return rep(chars(charset), 1, length)


def _refusal() -> Node:
    return seq(REFUSAL_PREFIX, _text(COMMENT_CHARS, COMMENT_LEN), "\n")


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


def _length(node: Node, rules: dict[str, Node]) -> int:
    return Grammar({**rules, "root": node}).max_length()


@dataclass
class _Function:
    name: str
    steps: int = 0
    max_index: int = -1  # the highest robot_list[i] used; -1: none (robot_list alone counts as 0)


class PlanConstraint(Constraint):
    """Stage 1 (decomposed) and stage 3 (allocated) plans."""

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
    ):
        super().__init__()
        self.allocated = team_size is not None
        self.team_size = team_size or 0
        self.comments = comments
        self.summary = summary and not self.allocated and not function_names
        self.fixed_names = list(function_names or [])
        self.max_subtasks = len(self.fixed_names) or max_subtasks
        self.max_steps = max_steps
        self.allow_refusal = allow_refusal
        self.skill_names: list[str] = []
        self.rules = self._vocabulary(scene, skills)
        self.phase = "start"
        self.summary_lines = 0
        self.owed = len(self.fixed_names) or None  # defs still promised
        self.functions: list[_Function] = []
        self.last_was_comment = False
        self.blocks = 0
        self.threads: list[str] = []  # targets of the block being written
        self.pending = ""  # boilerplate to write next (the rest of a block's starts and joins)
        self._lengths()

    # ----------------------------------------------------------- vocabulary

    def _vocabulary(self, scene: SceneObjects, skills: SkillSet) -> dict[str, Node]:
        rules: dict[str, Node] = {}
        calls: list[Node] = []
        robot = None
        if self.allocated:
            rules["robot-arg"] = alt("robot_list", *(f"robot_list[{i}]" for i in range(self.team_size)))
            robot = Ref("robot-arg")
        for skill in skills.values():
            args: list[Node] = []
            for aff in skill.arguments:
                types = scene.types_for(aff)
                if not types:
                    break
                name = "obj-" + (aff or "any")
                rules[name] = alt(*(f"'{t}'" for t in types))
                args.append(Ref(name))
            if len(args) < skill.required:
                continue
            parts: list[Node | str] = [f"{skill.name}("]
            if robot is not None:
                parts += [robot, ", "]
            for i, arg in enumerate(args[: skill.required]):
                parts += ([", "] if i else []) + [arg]
            for arg in args[skill.required:]:
                parts.append(opt(seq(", ", arg)))
            parts.append(")")
            calls.append(seq(*parts))
            self.skill_names.append(skill.name)
        if not calls:
            raise ValueError("no skill of the vocabulary applies to any object of this scene")
        rules["call"] = alt(*calls)
        rules["step"] = alt(seq(INDENT, Ref("call"), "\n"), seq(INDENT, "time.sleep(", chars("123456789"), ")\n"))
        rules["comment"] = seq(INDENT, "# ", _text(COMMENT_CHARS, COMMENT_LEN), "\n")
        rules["refusal"] = _refusal()
        return rules

    def _header(self, k: int) -> Node:
        params = "robot_list" if self.allocated else ""
        return seq(f"def subtask{k}_", chars(NAME_FIRST), rep(chars(NAME_REST), 0, NAME_LEN - 1), f"({params}):\n")

    def _summary_line(self, k: int) -> Node:
        skill = alt(*self.skill_names)
        return seq(f"# SubTask {k}: ", _text(SUMMARY_CHARS, SUMMARY_LEN), " (skills: ", skill,
                   rep(seq(", ", skill), 0, 7), ")\n")

    def _lengths(self) -> None:
        r = self.rules
        self.step_len = _length(Ref("step"), r)
        self.comment_len = _length(Ref("comment"), r)
        self.header_len = max((len(f"def {n}(robot_list):\n") for n in self.fixed_names),
                              default=_length(self._header(self.max_subtasks), r))
        self.def_min = self.header_len + self.step_len + 1
        self.summary_len = _length(self._summary_line(9), r)
        self.order_len = len("# ") + ORDER_LEN + 1
        self.refusal_len = _length(Ref("refusal"), r)
        name_len = max((len(n) for n in self.fixed_names), default=len("subtask9_") + NAME_LEN)
        args_len = len(", args=(,)") + self._robot_list_len(self.team_size) if self.allocated else 0
        self.thread_len = len("t9 = threading.Thread(target=") + name_len + args_len + 2
        self.call_len = name_len + (self._robot_list_len(self.team_size) if self.allocated else 0) + 3

    @staticmethod
    def _robot_list_len(n: int) -> int:
        return 2 + n * len("robots[15]") + max(0, n - 1) * 2

    def minimum_budget(self) -> int:
        if self.summary:
            return self.summary_len + self.order_len + 1 + self.def_min + self.call_len + EOS
        return max(self.refusal_len, self.def_min * max(1, len(self.fixed_names)) + self.call_len + EOS)

    # ---------------------------------------------------------------- costs

    def _orch_min(self) -> int:
        return self.call_len + EOS if self.blocks == 0 else EOS

    def _body_finish(self) -> int:
        """Cost to finish after a step: the blank line, the defs still owed, the orchestration."""
        owed = max(0, (self.owed or 0) - len(self.functions))
        return 1 + owed * self.def_min + self._orch_min()

    def _starts_joins(self, n: int) -> int:
        return sum(len(f"t{i}.start()\n") + len(f"t{i}.join()\n") for i in range(1, n + 1))

    # ------------------------------------------------------------- choices

    def next(self, remaining: int) -> Forced | Choose | None:
        if self.pending:
            return Forced(self.pending)
        phase = self.phase
        if phase == "start":
            return self._start(remaining)
        if phase == "summary":
            return self._summary(remaining)
        if phase == "order-blank":
            return Forced("\n")
        if phase == "header":
            return self._header_choice(remaining)
        if phase == "body":
            return self._body(remaining)
        if phase == "orch":
            return self._orch(remaining)
        if phase == "threads":
            return self._threads(remaining)
        return None

    def _start(self, remaining: int) -> Forced | Choose:
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
        base = self.order_len + 1 + k * self.def_min + self.call_len + EOS
        if k < self.max_subtasks and self.summary_len + self.def_min + base <= remaining:
            options["summary"] = self._summary_line(k + 1)
        options["order"] = seq("# ", _text(COMMENT_CHARS, ORDER_LEN), "\n")
        return self._choose(self.rules, options)

    def _header_choice(self, remaining: int) -> Forced | Choose:
        k = len(self.functions) + 1
        if self.fixed_names:
            return Forced(f"def {self.fixed_names[k - 1]}(robot_list):\n")
        if self.owed:
            return self._choose(self.rules, {"header": self._header(k)})
        options: dict[str, Node] = {}
        if k <= self.max_subtasks and self.def_min + self.call_len + EOS <= remaining:
            options["header"] = self._header(k)
        options.update(self._orch_options(remaining))
        return self._choose({**self.rules, **self._orch_rules()}, options)

    def _body(self, remaining: int) -> Choose:
        fn = self.functions[-1]
        options: dict[str, Node] = {}
        if fn.steps < self.max_steps and self.step_len + self._body_finish() <= remaining:
            options["step"] = Ref("step")
            if self.comments and not self.last_was_comment and \
                    self.comment_len + self.step_len + self._body_finish() <= remaining:
                options["comment"] = Ref("comment")
        if self.last_was_comment:
            options["step"] = Ref("step")
        elif fn.steps >= 1:
            options["end"] = "\n"
        return self._choose(self.rules, options)

    def _orch_rules(self) -> dict[str, Node]:
        names = [f.name for f in self.functions]
        rules: dict[str, Node] = {}
        if self.allocated:
            rules.update(robot_chains(self.team_size, ", "))
            for k, fn in enumerate(self.functions):
                rules[f"team-{k}"] = seq("[", Ref(f"robots-from-0-need-{max(1, fn.max_index + 1)}"), "]")
            rules["target"] = alt(*(seq(f"{n}, args=(", Ref(f"team-{k}"), ",)") for k, n in enumerate(names)))
            rules["direct"] = alt(*(seq(n, "(", Ref(f"team-{k}"), ")\n") for k, n in enumerate(names)))
        else:
            rules["target"] = alt(*names)
            rules["direct"] = alt(*(f"{n}()\n" for n in names))
        return rules

    def _orch_options(self, remaining: int) -> dict[str, Node]:
        options: dict[str, Node] = {}
        if self.blocks < max(1, len(self.functions)):
            if self.thread_len + self._starts_joins(1) + EOS <= remaining:
                options["thread"] = seq("t1 = threading.Thread(target=", Ref("target"), ")\n")
            if self.call_len + EOS <= remaining:
                options["direct"] = Ref("direct")
        if self.blocks >= 1:
            options["end"] = ""
        return options

    def _orch(self, remaining: int) -> Choose | None:
        options = self._orch_options(remaining)
        if list(options) == ["end"]:
            return None
        return self._choose({**self.rules, **self._orch_rules()}, options)

    def _threads(self, remaining: int) -> Choose:
        n = len(self.threads)
        options: dict[str, Node] = {}
        if n < len(self.functions) and self.thread_len + self._starts_joins(n + 1) + EOS <= remaining:
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
        elif kind == "forced" and self.phase == "order-blank":
            self.phase = "header"
        elif kind == "header" or (kind == "forced" and piece.startswith("def ")):
            self.functions.append(_Function(piece[4:piece.index("(")]))
            self.last_was_comment = False
            self.phase = "body"
        elif kind == "comment":
            self.last_was_comment = True
        elif kind == "step":
            self.last_was_comment = False
            fn = self.functions[-1]
            fn.steps += 1
            for i in range(self.team_size):
                if f"robot_list[{i}]" in piece:
                    fn.max_index = max(fn.max_index, i)
        elif kind == "end" and self.phase == "body":
            done = self.owed is not None and len(self.functions) >= self.owed
            self.phase = "orch" if done else "header"
        else:
            self._advance_orchestration(kind, piece)

    def _advance_orchestration(self, kind: str, piece: str) -> None:
        if kind == "end":
            self.phase = "done"
        elif kind == "start":
            n = len(self.threads)
            self.pending = "".join(f"t{i}.start()\n" for i in range(2, n + 1))
            self.pending += "".join(f"t{i}.join()\n" for i in range(1, n + 1))
            self.threads = []
            self.blocks += 1
            self.phase = "orch"
        elif kind == "thread":
            target = piece.split("target=", 1)[1].split(",")[0].split(")")[0]
            self.threads.append(target)
            self.phase = "threads"
        elif kind == "direct":
            self.blocks += 1
            self.phase = "orch"


class CoalitionConstraint(Constraint):
    """Stage 2: one comment line per sub-task naming the robot or team of the team that does it.

    Robots are named only as ``robots[i]`` with i inside the team: the free
    text of a line admits no digits or brackets, except in a mass (``2.5 kg``).
    A line's reason is made of up to six pieces (a run of words, a robot, a
    mass); fewer when the budget left must also cover the lines still to come.
    """

    PIECE = 24  # longest piece of a reason
    MAX_PIECES = 6

    def __init__(self, function_names: Sequence[str], team_size: int, *, allow_refusal: bool = True):
        super().__init__()
        self.names = list(function_names)
        self.team_size = team_size
        self.allow_refusal = allow_refusal
        self.lines = 0
        mass = seq(rep(chars(string.digits), 1, 3), opt(seq(".", rep(chars(string.digits), 1, 2))), " kg")
        self.rules: dict[str, Node] = {
            "robot": alt(*(f"robots[{i}]" for i in range(team_size))),
            "piece": alt(_text(REASON_CHARS, self.PIECE), Ref("robot"), mass),
            **robot_chains(team_size, " and "),
            "team": Ref("robots-from-0-need-1"),
            "refusal": _refusal(),
        }
        team_len = _length(Ref("team"), self.rules)
        self.fixed = [len(self._prefix(k)) + team_len + len("; ") + 1 for k in range(len(self.names))]
        self.refusal_len = _length(Ref("refusal"), self.rules)

    def _prefix(self, k: int) -> str:
        return f"# SubTask {k + 1} ({self.names[k]}): "

    def minimum_budget(self) -> int:
        return sum(f + self.PIECE for f in self.fixed)

    def next(self, remaining: int) -> Choose | None:
        k = self.lines
        if self.refusal is not None or k == len(self.names):
            return None
        reserve = sum(f + self.PIECE for f in self.fixed[k + 1:])
        pieces = min(self.MAX_PIECES, (remaining - reserve - self.fixed[k]) // self.PIECE)
        options: dict[str, Node] = {}
        if self.allow_refusal and self.refusal_len <= remaining:
            options["refusal"] = Ref("refusal")
        options["line"] = seq(self._prefix(k), Ref("team"), "; ", rep(Ref("piece"), 1, max(1, pieces)), "\n")
        return self._choose(self.rules, options)

    def _advance(self, kind: str, piece: str) -> None:
        if kind == "line":
            self.lines += 1
