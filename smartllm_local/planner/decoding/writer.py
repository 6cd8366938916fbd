"""Driving a stage's constraint: each offered line goes to a writer (the model, or an adversary in tests) as a
grammar, until the constraint says the output is complete.

Text the constraint forces is not put into the context on its own: it is carried into the next line the
writer writes, which begins with it (a backend writes it in its own tokens up to the last one, and the model
picks that last one under the grammar: token healing, so ``# SubTask 1:`` is followed by the model's own
`` put``). So is a line offered with one way to write it (an allocation's step whose robot the team leaves no
choice of): asked of the model, it would cost an evaluation of its own for the one token healing leaves it.
A line's end is opened (:mod:`.line_ends`): the writer's last token may run past the newline into
blank lines or the start of the next line, which is then checked against what the constraint offers next
and goes on from there. A writer that ends the sequence before the output is complete has it completed by
the constraint's shortest way, and the count of lines so completed is reported.

A line that would begin a third copy in a row of a block of lines (a ``guard``'s rule: see
:class:`~.repetition.LoopGuard`) is taken back from the writer, and the constraint's shortest way out
of the block is written instead: its shortest lines (a blank line where one ends something, none that begins
the copy) up to the next blank line, which in a plan ends the function; the model goes on from there.

Every cost is in tokens, and the constraint counts characters, an upper bound: text carried and not yet
written is counted at its length until it is. What a line's opened end adds beyond the characters the
constraint counts (spaces before a newline, blank lines read as none) is paid from a slack held back from the
constraint; ends are opened only while the slack can pay for the most a line end can add, so a writer that
pays a token a character keeps within the budget too.
"""

from __future__ import annotations

import random
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Protocol

from ...errors import SmartLLMError
from .grammar import Grammar, alt, seq
from .line_ends import MOST_ADDED, opened, split_spill
from .matcher import Matcher
from .protocol import Choose, Constraint, Forced, Rewrite

#: The kind of line a constraint may take back after it is written (see :class:`~.protocol.Rewrite`): offered only
#: where all of the line can be taken back (no forced text before it, nothing but spaces of it already written).
REWRITTEN = "repair"
#: Tokens held back from the constraint for what opened line ends add (see above).
SLACK = 64


def exact_budget(longest: int) -> int:
    """The budget of an output whose longest is known to the character (a restated allocation's): that, and the
    slack a writer holds back for what the line ends a model opens add. Where the planner writes every line (all
    carried, counted at their length), the constraint still has room for the longest output."""
    return longest + SLACK


#: Writes one line for an offered grammar; returns the text and the tokens it cost (the line-by-line writers
#: of tests and of ``accepts``: a complete line, nothing past its newline).
LineWriter = Callable[[Choose, int], tuple[str, int]]
#: Puts text into the context; returns the tokens it cost.
Forcer = Callable[[str], int]


class CycleGuard(Protocol):
    """A rule for loops of whole lines (:class:`~.repetition.LoopGuard` is one)."""

    def cycles(self, lines: Sequence[str]) -> bool:
        """Whether the last of ``lines`` (an output's lines so far) begins a loop."""


class BudgetError(Exception):
    """The output budget cannot hold even the shortest complete output."""


class GuaranteeError(SmartLLMError):
    """A stage's output broke a guarantee its constraint gives (a bug in the planner)."""


@dataclass(frozen=True)
class Line:
    """What a writer is asked to write: ``carry`` (text the constraint forced, not yet in the context), then the
    line ``choose`` offers, as ``grammar`` admits it (its end opened). It stops after the token that writes the
    ``lines``-th newline. ``ahead`` is text already in the context that the line begins with (it is not written
    again, and ``grammar`` admits what follows it)."""

    choose: Choose
    grammar: Grammar
    carry: str = ""
    ahead: str = ""

    @property
    def lines(self) -> int:
        return self.carry.count("\n") + 1


@dataclass
class Written:
    """A writer's answer: its text (the carry, the line, maybe the start of the next in the same token), what it
    cost, and whether the model ended the sequence instead of completing the line (``text`` is then a
    beginning of it)."""

    text: str
    cost: int
    ended: bool = False


@dataclass
class Report:
    """What happened at line ends: lines the planner completed after the model ended the sequence, tokens that
    ran past a line's end, and blank lines read as none."""

    completed_lines: int = 0
    spilled: int = 0
    ignored_blank_lines: int = 0
    cycles_ended: int = 0  # lines taken back because they began a third copy of a block of lines
    rewritten: int = 0  # lines the constraint took back to write something else in their place (a repair)
    notes: list[str] = field(default_factory=list)


class TokenWriter:
    """A writer of whole answers (see :class:`Line`); ``force`` puts text into the context as it is."""

    def write(self, line: Line, remaining: int) -> Written:  # pragma: no cover - protocol
        raise NotImplementedError

    def force(self, text: str) -> int:  # pragma: no cover - protocol
        raise NotImplementedError

    def take_back(self, written: Written) -> None:
        """Remove what ``written`` put into the context (it began a loop of lines); nothing to do for a writer
        that keeps no context."""


class _ByLines(TokenWriter):
    """A line-by-line writer as a token writer: the carry forced, then one complete line."""

    def __init__(self, write: LineWriter, force: Forcer):
        self._write, self._force = write, force

    def write(self, line: Line, remaining: int) -> Written:
        cost = self._force(line.carry) if line.carry else 0
        text, spent = self._write(line.choose, remaining - cost)
        return Written(line.carry + text, cost + spent)

    def force(self, text: str) -> int:
        return self._force(text)


def run_constraint(constraint: Constraint, write: LineWriter, force: Forcer, budget: int, *,
                   guard: CycleGuard | None = None) -> str:
    """Produce a stage's output within ``budget`` tokens, a line at a time (each a complete line)."""
    return run_tokens(constraint, _ByLines(write, force), budget, guard=guard)


def run_tokens(constraint: Constraint, writer: TokenWriter, budget: int, report: Report | None = None, *,
               open_ends: bool = True, guard: CycleGuard | None = None) -> str:
    """Produce a stage's output within ``budget`` tokens, with a writer that writes as a model does (each line's
    end opened, unless ``open_ends`` is off: to measure what opening them changes), loops of lines ended where
    ``guard`` finds them."""
    if constraint.minimum_budget() > budget:
        raise BudgetError(
            f"{budget} output tokens cannot hold the shortest complete output "
            f"({constraint.minimum_budget()} characters); raise the output budget or --n-ctx"
        )
    return _Driver(constraint, writer, budget, report or Report(), open_ends, guard).run()


class _Driver:
    def __init__(self, constraint: Constraint, writer: TokenWriter, budget: int, report: Report, opens: bool,
                 guard: CycleGuard | None = None):
        self.constraint, self.writer, self.budget, self.report, self.opens = constraint, writer, budget, report, opens
        self.guard = guard
        self.used = 0
        self.carry = ""  # fed to the constraint, not yet written
        self.pending = ""  # written (in the context), not yet fed: blank lines, then the start of a line
        self.ended = False  # the model ended the sequence: the planner completes the output
        self.cutting = False  # a loop of lines was found: the planner writes the way out of its block
        self.slack = max(0, min(SLACK, budget - constraint.minimum_budget())) if opens else 0
        self.last: tuple[Written, str, str] | None = None  # the last line written, its carry and the text ahead

    def held(self) -> int:
        """The slack left: what is held back, less the tokens spent beyond the characters fed (a carry counted
        at its length, as the constraint counts it)."""
        return max(0, self.slack - max(0, self.used + len(self.carry) - len(self.constraint.text)))

    def run(self) -> str:
        while (step := self.constraint.next(self.budget - self.used - len(self.carry) - self.held())) is not None:
            if isinstance(step, Rewrite):
                self._rewrite(step)
            elif self.ended:
                self._complete(step)
            elif isinstance(step, Forced):
                self._forced(step.text)
            elif self.cutting:
                self._way_out(step)
            elif not self._pending_fed(step):
                if (line := _only_line(step)) is not None:
                    self._forced(line)  # nothing to choose: carried into the next line's batch, as forced text is
                else:
                    self._write(step)
            self.cutting = self.cutting and not self.constraint.text.endswith("\n\n")
            self._check()
        if self.carry:
            self._spend(self.writer.force(self.carry))
            self.carry = ""
            self._check()
        if self.pending.strip():
            raise GuaranteeError(f"{self.pending!r} was written after the output's end: {self.constraint.text!r}")
        return self.constraint.text

    def _spend(self, cost: int) -> None:
        self.used += cost

    def _check(self) -> None:
        if self.used > self.budget:  # the constraint's bookkeeping failed: a bug, reported, never a plan
            raise GuaranteeError(f"the output used {self.used} tokens of a budget of {self.budget}: "
                                 f"{self.constraint.text!r}")

    def _forced(self, text: str) -> None:
        """Forced text: fed now, written with the next line (or matched against what is already written)."""
        self.last = None
        while self.pending.startswith("\n") and not text.startswith("\n"):
            self._ignore_blank()
        if text.startswith("\n") and not self.pending.strip(" "):
            self.pending = ""  # spaces before a newline: a blank line's, which Python ignores
        self.constraint.feed(text)
        if self.pending.startswith(text):
            self.pending = self.pending[len(text):]
        elif text.startswith(self.pending):
            self.carry += text[len(self.pending):]
            self.pending = ""
        else:
            raise GuaranteeError(f"{self.pending!r} was written where the plan goes on with {text!r}")

    def _ignore_blank(self) -> None:
        self.pending = self.pending[1:]
        self.report.ignored_blank_lines += 1

    def _pending_fed(self, step: Choose) -> bool:
        """Feed a blank line already written, if it is one the step offers (ending a function); drop it if not
        (Python ignores it). True if something was fed (the constraint then offers its next step)."""
        if not self.pending.startswith("\n"):
            return False
        if step.kind_of("\n"):
            self.pending = self.pending[1:]
            self.constraint.feed("\n")
            return True
        while self.pending.startswith("\n"):
            self._ignore_blank()
        return False

    def _write(self, step: Choose) -> None:
        self.last = None
        ahead, self.pending = self.pending, ""
        kinds = {k: g.rules["root"] for k, g in step.options.items()
                 if k != REWRITTEN or not (self.carry or ahead.strip())}  # else not all of it could be taken back
        if self.opens and self.held() >= MOST_ADDED:
            kinds = opened(kinds, step.grammar.rules, step.follows)
        elif ahead and step.kind_of("\n") and not Matcher(step.grammar).advance(ahead):
            kinds[step.kind_of("\n")] = alt(kinds[step.kind_of("\n")], seq(ahead, "\n"))  # a blank line's spaces
        rules = step.grammar.rules
        wire = Grammar({**rules, "root": seq(self.carry, alt(*kinds.values()))})
        if ahead:
            if not Matcher(wire).advance(ahead):
                raise GuaranteeError(f"{ahead!r} was written where the plan goes on with a line it does not begin")
            wire = wire.after(ahead)
        line = Line(step, wire, self.carry, ahead)
        written = self.writer.write(line, self.budget - self.used)
        self._spend(written.cost)
        text = written.text
        self.last = (written, self.carry, ahead)
        if written.ended:
            rest = _rest_of_line({k: Grammar({**rules, "root": seq(self.carry, v)}) for k, v in kinds.items()},
                                 ahead, text)
            cost = self.writer.force(rest) if rest else 0
            self._spend(cost)
            text += rest
            self.last = (Written(text, written.cost + cost, ended=True), self.carry, ahead)
            self.ended = True
            self.report.completed_lines += 1
            self.report.notes.append(f"the model ended the sequence after {self.constraint.text + ahead + text!r}")
        if not text.startswith(self.carry):
            raise GuaranteeError(f"the writer wrote {text!r} for a line that begins with {self.carry!r}")
        body = ahead + text[len(self.carry):]
        if "\n" not in body:  # a line writer's empty answer: the model ended where the grammar may end
            self.carry = ""
            self.constraint.feed(body)
            return
        raw, _, spill = body.partition("\n")
        line = _as_offered(step, raw)
        if not written.ended and self._loops(line):
            self.writer.take_back(written)  # the line is not the model's to keep: the block's way out is written
            self.used -= written.cost
            self.pending = ahead
            self.report.cycles_ended += 1
            self.cutting = True
            self._way_out(step)
            return
        self.carry = ""
        self.constraint.feed(line)
        if spill:
            self.report.spilled += 1
            blanks, rest = split_spill(spill)
            self.pending = "\n" * blanks + rest

    def _rewrite(self, step: Rewrite) -> None:
        """The constraint takes back the line just written (and what ran past its end) and writes ``step.text``
        in its place, or has the model write another line where the text is empty."""
        if self.last is None:
            raise GuaranteeError(f"a rewrite with no line written before it: {self.constraint.text!r}")
        written, carry, ahead = self.last
        self.last = None
        self.writer.take_back(written)
        self.used -= written.cost
        self.carry, self.pending = carry, ahead
        self.report.rewritten += 1
        if not step.text:
            return
        if self.ended:  # the planner writes on: the text goes into the context now
            self.constraint.feed(step.text)
            self._spend(self.writer.force(self.carry + step.text[len(ahead):]))
            self.carry = self.pending = ""
        else:
            self._forced(step.text)

    def _loops(self, line: str) -> bool:
        """Whether ``line``, written next, would begin a loop of lines (see :class:`CycleGuard`)."""
        return self.guard is not None and self.guard.cycles(self.constraint.text.split("\n")[:-1] + [line[:-1]])

    def _way_out(self, step: Choose) -> None:
        """Write the constraint's shortest line for ``step`` that begins no loop (after what is already written
        of it: a carry to write, or text ahead in the context; spaces ahead stay before a blank line's newline)."""
        self.last = None
        ahead, self.pending = self.pending, ""
        blank = not ahead.strip(" ") and bool(step.kind_of("\n"))
        ways = [(False, "\n")] if blank else []
        for kind, grammar in step.options.items():
            if kind != REWRITTEN and Matcher(grammar).advance(ahead):
                ways.append((kind in _ASIDES, ahead + grammar.after(ahead).sample(_PLAIN, "shortest")))  # type: ignore[arg-type]
        lines = [line for _, line in sorted(ways, key=lambda way: (way[0], len(way[1])))]
        line = next((t for t in lines if not self._loops(t)), lines[0])
        self._spend(self.writer.force(self.carry + ("\n" if blank and line == "\n" else line[len(ahead):])))
        self.carry = ""
        self.constraint.feed(line)

    def _complete(self, step: Forced | Choose) -> None:
        """The model ended the sequence: the output goes on by its shortest way (see :func:`shortest_line`)."""
        self.last = None
        text = step.text if isinstance(step, Forced) else shortest_line(step)
        self.constraint.feed(text)
        self._spend(self.writer.force(text))
        if isinstance(step, Choose):
            self.report.completed_lines += 1


#: Kinds of line a completion does not write where it has another: asides (they take an output nowhere), a
#: refusal (the model did not refuse; it ended), and a new sub-task's header (it ended: the plan ends where it may,
#: rather than grow by the shortest sub-tasks the grammar offers).
_ASIDES = ("comment", "sleep", "refusal", "header")


def _rest_of_line(kinds: dict[str, Grammar], ahead: str, text: str) -> str:
    """How a line the model left unfinished is finished: the shortest way, among the kinds of line it may still
    be, those a completion writes first (:data:`_ASIDES`)."""
    ways = {}
    for kind, grammar in kinds.items():
        follow = Matcher(grammar)
        if follow.advance(ahead + text):
            ways[kind] = grammar.after(ahead + text).sample(_PLAIN, "shortest")  # type: ignore[arg-type]
    chosen = [w for k, w in ways.items() if k not in _ASIDES] or list(ways.values())
    return min(chosen, key=len)


def shortest_line(step: Choose) -> str:
    """The line a completion writes: a blank line where one ends something, else the shortest line of a kind
    that takes the output on (no comment, no sleep, no refusal), spelled plainly (letters where it may
    choose), the same every time."""
    kinds = [k for k in step.options if k not in _ASIDES and k != REWRITTEN] or \
        [k for k in step.options if k != REWRITTEN]
    if step.kind_of("\n") in kinds:
        return "\n"
    lines = [step.options[k].sample(_PLAIN, "shortest") for k in kinds]  # type: ignore[arg-type]
    return min(lines, key=len)


class _Plain:
    """Grammar.sample's choices made plainly: the first option, the fewest repetitions, a letter where a
    character may be one."""

    @staticmethod
    def choice(options):
        return next((o for o in options if isinstance(o, str) and o.isalpha() and o.islower()), options[0])

    @staticmethod
    def randint(low: int, high: int) -> int:
        return low


_PLAIN = _Plain()


def _only_line(step: Choose) -> str | None:
    """The line a step leaves no choice in (one kind of line, spelled one way), or None."""
    if len(step.options) != 1 or REWRITTEN in step.options:
        return None
    line = step.grammar.only()
    return line if line and line.endswith("\n") else None


def _as_offered(step: Choose, raw: str) -> str:
    """A written line as the constraint offered it: without the spaces it ended with (those of them the line's
    own text does not hold)."""
    for cut in range(len(raw) - len(raw.rstrip(" ")), -1, -1):
        line = raw[: len(raw) - cut] + "\n"
        if step.kind_of(line):
            return line
    raise GuaranteeError(f"the line {raw!r} is not one the grammar offered")


def sample_output(constraint: Constraint, rng: random.Random, budget: int = 10_000) -> str:
    """A random output of a stage's grammar (every line sampled from the grammar offered)."""
    def write(choose: Choose, remaining: int) -> tuple[str, int]:
        text = choose.grammar.sample(rng)
        return text, len(text) + (1 if text == "" else 0)

    return run_constraint(constraint, write, len, budget)


def accepts(constraint: Constraint, text: str, budget: int = 100_000) -> bool:
    """Whether ``text`` is an output of the stage's grammar."""
    rest = text

    def write(choose: Choose, remaining: int) -> tuple[str, int]:
        nonlocal rest
        if rest == "":
            line = ""
        else:
            cut = rest.find("\n")
            line = rest if cut < 0 else rest[: cut + 1]
        if not choose.grammar.matches(line):
            raise _Rejected
        rest = rest[len(line):]
        return line, len(line) + 1

    def force(forced: str) -> int:
        nonlocal rest
        if not rest.startswith(forced):
            raise _Rejected
        rest = rest[len(forced):]
        return len(forced)

    try:
        run_constraint(constraint, write, force, budget)
    except (_Rejected, BudgetError):
        return False
    return rest == ""


class _Rejected(Exception):
    pass
