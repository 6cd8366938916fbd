"""Stage 1 (decomposed) and stage 3 (allocated) plans, written line by line under a grammar.

Beyond syntax, the constraint keeps a plan's shape sensible: a function ends
with an action (not a bare GoToObject), a summary lists distinct skills in the
vocabulary's order, bodies respect simple preconditions, and the orchestration
launches every function exactly once, in threads or directly, then stops.

The budget is kept by construction. Every state has a cheapest completion (an
order line of one character, the owed functions with one short action each,
a direct call for every function not yet launched), and a line is offered only
if, after the longest text that line can hold, the cheapest completion of the
state it leads to still fits what is left. Free text (names, comments, summary
and order lines) is cut to the room there is; object choices too long for it are
left out. Since the cheapest completion of the state reached is always offered,
generation can always go on and ends by completing the plan. Costs are counted
in characters, an upper bound on tokens (every token spells at least one).
Whatever the budget kept from being offered is recorded in ``capped``.

With a world check (:mod:`.world_check`), a body offers only the calls that
succeed from the state the steps so far produce: a function acts after it has
gone somewhere, goes only where one of its next calls succeeds, and puts down what
it picked up before it ends; functions are launched in the order they were
checked in. The budget is kept on the unchecked choices, so the check never costs
a plan its ending: where no checked line fits, the unchecked ones that do are
offered (a dead end, counted).

The orchestration's lines and costs are in :mod:`.orchestration`. A restated
allocation (:mod:`.restated`) is a plan constraint whose bodies are the
decomposition's.
"""

from __future__ import annotations

import re
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field, replace

from ..robots import Robot
from ..skills import Skill, SkillSet
from .constraints import (
    COMMENT_LEN,
    INDENT,
    MAX_STEPS,
    MAX_SUBTASKS,
    NAME_FIRST,
    NAME_LEN,
    NAME_REST,
    ORDER_CHARS,
    ORDER_LEN,
    STEP_COMMENT_LEN,
    SUMMARY_CHARS,
    SUMMARY_LEN,
    Choose,
    Constraint,
    Forced,
    comment_text,
    longest,
    ordered_subset,
    refusal_line,
    refusal_text_len,
    text_run,
)
from .feasibility import Step, call_demand
from .grammar import Node, Ref, alt, chars, rep, seq
from .line_ends import COMMENT_NEXT, INDENTED_NEXT
from .orchestration import Orchestration
from .scene_context import SceneObjects
from .world_check import Call, WorldCheck

KNIVES = frozenset({"Knife", "ButterKnife"})
# Actions that set a state, and the action that undoes each.
_STATE_ACTIONS = {"OpenObject": "CloseObject", "CloseObject": "OpenObject",
                  "ToggleObjectOn": "ToggleObjectOff", "ToggleObjectOff": "ToggleObjectOn"}
_CALL = re.compile(r"^\s+(\w+)\((?:robot_list(?:\[(\d+)\])?, )?'([^']+)'(?:, '([^']+)')?\)$")
STEP_LINE = re.compile(r"^    (\w+)\((.*)\)\n$")
_RELEASE = ("PutObject", "DropHandObject", "ThrowObject")

Candidate = tuple[Skill, tuple[str, ...]]
#: What may start the text after a line of each kind, in its last token (see :mod:`.line_ends`): a summary
#: line is followed by another or by the order line, a header and a body line by an indented line (or a blank
#: one, ending the function where it may end).
FOLLOWS: dict[str, Node] = {"summary": COMMENT_NEXT, "header": INDENTED_NEXT, "goto": INDENTED_NEXT,
                            "action": INDENTED_NEXT, "comment": INDENTED_NEXT, "sleep": INDENTED_NEXT}


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
        match = _CALL.match(line.rstrip("\n"))
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
        elif action in _RELEASE:
            self.held.discard(first)
        elif action in _STATE_ACTIONS:
            self.states[first] = action


def _args_text(objects: Sequence[str]) -> str:
    return ", ".join(f"'{t}'" for t in objects)


class PlanConstraint(Orchestration, Constraint):
    """A decomposed plan (no team) or an allocated one (``team_size`` or ``team`` given)."""

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
        world: WorldCheck | None = None,
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
        self.scene = scene
        self.skills = [s for s in skills.values() if all(scene.types_for(a) for a in s.arguments[: s.required])]
        self.skill_names = [s.name for s in self.skills]
        self.skill_actions = {s.name: s.action for s in self.skills}
        self.by_name = {s.name: s for s in skills.values()}
        goto = [s for s in self.skills if s.action == ""]
        if not goto or len(goto) == len(self.skills):
            raise ValueError("the skills cannot act on any object of this scene")
        self.rules: dict[str, Node] = {"refusal": refusal_line(), "skills": ordered_subset(self.skill_names, ", ")}
        self.robot_args = ["robot_list", *(f"robot_list[{i}]" for i in range(self.team_size))] if self.allocated else []
        self.robot_arg_len = max((len(a) + 2 for a in self.robot_args), default=0)  # with its ", "
        self.gotos = goto
        # On a site, a move is an end in itself (back to base): a function may end with one, or make two.
        self.goto_acts = scene.site is not None
        self.sleep_len = len(INDENT) + len("time.sleep(9)\n")
        self._candidate_cache: dict[tuple, list[Candidate]] = {}
        self.world = world
        self._lists: dict[tuple[str, int], list[tuple[int, ...]]] = {}
        self.action_max = max(self._line_len(c) for c in self._filtered(None))
        releases = [c for c in self._filtered(None) if c[0].action == "DropHandObject"] or \
            [c for c in self._filtered(None) if c[0].action in _RELEASE]
        self.release_max = max((self._line_len(c) for c in releases), default=self.action_max)
        self.goto_max = max(self._line_len(c) for c in self._goto_candidates())
        # A new function's cheapest body: one action; with a world check, the cheapest GoToObject and
        # an action where it went (what is picked up put down again), so that each sub-task promised
        # keeps room for a go-to and an action there (the budget is kept all the same).
        fresh = WrittenFunction("")
        self.fresh_action = min(self._line_len(c) for c in self._candidates(fresh)) if world is None else min(
            self._line_len(goto) + min((self._line_len(c) + self._hold_after(fresh, c) for c in self._candidates(fresh)
                                        if self._acts_on(c) in (goto[1][0], None)), default=self.action_max * 2)
            for goto in self._goto_candidates())
        self.skills_len = longest(Ref("skills"), self.rules)
        self.phase = "start"
        self.summary_lines = 0
        self.owed = len(self.fixed_names) or None  # defs promised (by the summary, or the decomposition)
        self.functions: list[WrittenFunction] = []
        self.launched: list[str] = []
        self.threads: list[str] = []  # targets of the block being written
        self.pending = ""  # boilerplate to write next (the rest of a block's starts and joins)

    # ------------------------------------------------------------ line text

    def _line_len(self, candidate: Candidate) -> int:
        """The longest text of a candidate's line (its longest robot argument included)."""
        skill, objects = candidate
        return len(INDENT) + len(skill.name) + 3 + len(_args_text(objects)) + self.robot_arg_len

    def _candidates(self, fn: WrittenFunction) -> list[Candidate]:
        """The action calls whose preconditions the function's own steps do not rule out.

        Put, drop and throw only what the function holds; pick up what it does not hold, and act
        otherwise only on what it does not hold (in a team, the holder would need that skill too);
        slice only with a knife in hand; do not switch on what it switched on (or open
        what it opened), and do not undo the step just taken. If nothing is left, any action.
        """
        key = (frozenset(fn.held), tuple(sorted(fn.states.items())), fn.last_call)
        if key not in self._candidate_cache:
            found = list(self._filtered(fn)) or list(self._filtered(None))
            self._candidate_cache[key] = found
        return self._candidate_cache[key]

    def _filtered(self, fn: WrittenFunction | None) -> Iterator[Candidate]:
        for skill in self.skills:
            if skill.action == "":
                continue
            types = [list(self.scene.types_for(a)) for a in skill.arguments]
            if fn is not None:
                if skill.action in _RELEASE:
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
                if skill.action not in _RELEASE and skill.action != "PickupObject":
                    # Not on what it holds: in a team, the holder would need this skill too.
                    types[0] = [t for t in types[0] if t not in fn.held]
            for first in types[0]:
                if len(types) == 1:
                    yield skill, (first,)
                    continue
                if skill.required == 1:
                    yield skill, (first,)
                for second in types[1]:
                    yield skill, (first, second)


    def _node(self, candidates: Sequence[Candidate]) -> Node | None:
        """Call lines for candidates, grouped by skill; None for none."""
        groups: dict[str, list[str]] = {}
        for skill, objects in candidates:
            groups.setdefault(skill.name, []).append(_args_text(objects))
        if not groups:
            return None
        robot = [Ref("robot-arg"), ", "] if self.allocated else []
        return alt(*(seq(f"{INDENT}{name}(", *robot, alt(*args), ")\n") for name, args in groups.items()))

    def _goto_candidates(self) -> list[Candidate]:
        return [(s, (t,)) for s in self.gotos for t in self.scene.types_for(s.arguments[0])]

    def _goto_node(self, fn: WrittenFunction, room: int) -> Node | None:
        """The GoToObject lines that leave room for an action after them within ``room`` characters;
        with a world check, only those to a place where one of the function's next calls that fits
        succeeds."""
        if self.goto_acts:  # a move is a step in itself: anywhere else it gets to
            here = self._place(fn)
            members = self._members(fn, None)
            return self._node([c for c in self._goto_candidates() if c[1][0] != here and self._line_len(c) <= room
                               and (self.world is None or self.world.succeeds(members, c[0].name, c[1]))])
        if self.world is None:
            cheapest = min(self._line_len(c) for c in self._candidates(fn))
            return self._node([c for c in self._goto_candidates() if self._line_len(c) + cheapest <= room])
        members = self._members(fn, None)
        then = self._candidates(replace(fn, last_call=("", ""), went=True))
        if fn.steps + 1 >= self.max_steps - 1:  # the step after the go-to is the last: as _succeeding
            then = [c for c in then if c[0].action != "PickupObject" and (not fn.held or c[0].action in _RELEASE)]
        gotos = []
        for skill, (target,) in self._goto_candidates():
            left = room - self._line_len((skill, (target,)))
            fitting = [(c.name, objs) for c, objs in then if self._acts_on((c, objs)) in (target, None)
                       and self._line_len((c, objs)) + self._hold_after(fn, (c, objs)) <= left]
            if fitting and self.world.leads_somewhere(members, skill.name, target, fitting):
                gotos.append((skill, (target,)))
        return self._node(gotos)

    def _members(self, fn: WrittenFunction, slot: int | None) -> list[int]:
        """The dry run's robots for a call: the function's own (decomposition), or its robot_list slot
        (allocation; a function that names the whole list is run by the whole team)."""
        if not self.allocated:
            return [len(self.functions) - 1]
        return [slot] if slot is not None else list(range(self.team_size))

    def _succeeding(self, fn: WrittenFunction) -> list[Candidate]:
        """The function's allowed calls; with a world check, those that succeed from the state now."""
        candidates = self._candidates(fn)
        if self.world is None:
            return candidates
        if not fn.went:
            return []
        if fn.steps >= self.max_steps - 1:  # the last step cannot pick up (nothing would put it down)
            candidates = [c for c in candidates if c[0].action != "PickupObject"]
            if fn.held:
                candidates = [c for c in candidates if c[0].action in _RELEASE]
        place = self._place(fn)
        candidates = [c for c in candidates if self._acts_on(c) in (place, None)]
        members = self._members(fn, None)
        return [c for c in candidates if self.world.succeeds(members, c[0].name, c[1])]

    def _place(self, fn: WrittenFunction, slot: int | None = None) -> str | None:
        """What the function (or its robot_list slot) last went to."""
        gotos = {s.name for s in self.gotos}
        return next((objects[0] for went, skill, objects in reversed(fn.calls)
                     if skill in gotos and went in (slot, None)), None)

    @staticmethod
    def _acts_on(candidate: Candidate) -> str | None:
        """Where a call acts: its object, a put's receptacle; None for dropping or throwing what is held.
        With a world check a call acts only on what the function last went to: where exactly a robot
        stands depends on where the others stand, and only the object gone to is surely within reach."""
        skill, objects = candidate
        if skill.action == "PutObject":
            return objects[1]
        return None if skill.action in ("DropHandObject", "ThrowObject") else objects[0]

    def _hold_after(self, fn: WrittenFunction, candidate: Candidate) -> int:
        """With a world check a function ends with empty hands (its robot may do the next function):
        the reserve for putting down what is held after ``candidate``."""
        if self.world is None or self.allocated:
            return 0
        action = candidate[0].action
        holding = (fn.held and action not in _RELEASE) or action == "PickupObject"
        return self.release_max if holding else 0

    # ---------------------------------------------------------------- costs

    def _def_cost(self, k: int) -> int:
        """The cheapest k-th function (1-based), its direct call included."""
        if self.fixed_names:
            name = self.fixed_names[k - 1]
            return len(f"def {name}(robot_list):\n") + self._body_cost(k - 1) + 1 + self._call_len(name)
        name = f"subtask{k}_a"
        return len(f"def {name}():\n") + self.fresh_action + 1 + self._call_len(name)

    def _body_cost(self, index: int) -> int:
        """The cheapest body of the function at ``index``: one action."""
        return self.fresh_action

    def _owed_cost(self) -> int:
        return sum(self._def_cost(k) for k in range(len(self.functions) + 1, (self.owed or 0) + 1))

    def _closing_cost(self) -> int:
        """The cheapest completion once the current function's body is finished: its end,
        the owed functions, and a direct call for every function not launched."""
        return 1 + self._owed_cost() + self._calls_cost(self._unlaunched())

    def _summary_after(self, k: int) -> int:
        """The cheapest completion after k summary lines: an order line, the blank, k functions."""
        return len("# x\n") + 1 + sum(self._def_cost(i) for i in range(1, k + 1))

    def minimum_budget(self) -> int:
        if self.fixed_names:
            return sum(self._def_cost(k) for k in range(1, len(self.fixed_names) + 1))
        if self.summary:
            return len("# SubTask 1: x (skills: )\n") + self.skills_len + self._summary_after(1)
        return self._def_cost(1)

    def world_counts(self) -> tuple[int, int]:
        return (self.world.tries, self.world.dead_ends) if self.world is not None else (0, 0)

    def _cap(self, what: str) -> None:
        if what not in self.capped:
            self.capped.append(what)

    # ------------------------------------------------------------- choices

    def next(self, remaining: int) -> Forced | Choose | None:
        if self.pending:
            return Forced(self.pending)
        if self.phase == "order-blank":
            return Forced("\n")
        handler = {
            "start": self._start, "summary": self._summary, "header": self._header_choice, "body": self._body,
            "orch": self._orch, "threads": self._threads,
        }.get(self.phase)
        return handler(remaining) if handler else None

    def _choose(self, rules: dict[str, Node], options: dict[str, Node]) -> Choose:  # type: ignore[override]
        if self.allocated:
            rules = {**rules, "robot-arg": alt(*self.robot_args)}
        return super()._choose(rules, options, FOLLOWS)

    def _refusal(self, remaining: int) -> Node | None:
        cap = min(refusal_text_len(), remaining - len("# INFEASIBLE: \n"))
        return refusal_line(cap) if cap >= 1 else None

    def _summary_line(self, k: int, room: int) -> Node | None:
        fixed = len(f"# SubTask {k}:  (skills: )\n") + self.skills_len
        cap = min(SUMMARY_LEN, room - fixed)
        if cap < 1:
            return None
        return seq(f"# SubTask {k}: ", text_run(SUMMARY_CHARS, cap), " (skills: ", Ref("skills"), ")\n")

    def _start(self, remaining: int) -> Choose:
        options: dict[str, Node] = {}
        refusal = self._refusal(remaining) if self.allow_refusal else None
        if refusal is not None:
            options["refusal"] = refusal
        if self.summary:
            options["summary"] = self._summary_line(1, remaining - self._summary_after(1))
        elif self.fixed_names:
            options["header"] = f"def {self.fixed_names[0]}(robot_list):\n"
        else:
            options["header"] = self._header(1, remaining)
        return self._choose(self.rules, options)

    def _summary(self, remaining: int) -> Choose:
        options: dict[str, Node] = {}
        k = self.summary_lines
        if k < self.max_subtasks:
            line = self._summary_line(k + 1, remaining - self._summary_after(k + 1))
            if line is None:
                self._cap(f"sub-task {k + 1}")
            else:
                options["summary"] = line
        cap = min(ORDER_LEN, remaining - (self._summary_after(k) - 1))
        options["order"] = seq("# ", text_run(ORDER_CHARS, cap), "\n")
        return self._choose(self.rules, options)

    def _header(self, k: int, remaining: int) -> Node | None:
        """A ``def subtask<k>_<name>():`` line whose name leaves room for the function and its call."""
        base = f"subtask{k}_"
        rest = self._calls_cost(self._unlaunched()) + sum(
            self._def_cost(i) for i in range(k + 1, (self.owed or 0) + 1))
        fixed = len(f"def {base}():\n") + self.fresh_action + 1 + len(base) + 3
        cap = min(NAME_LEN, (remaining - rest - fixed) // 2)
        if cap < 1:
            return None
        return seq(f"def {base}", chars(NAME_FIRST), rep(chars(NAME_REST), 0, cap - 1), "():\n")

    def _header_choice(self, remaining: int) -> Forced | Choose | None:
        k = len(self.functions) + 1
        if self.fixed_names:
            return Forced(f"def {self.fixed_names[k - 1]}(robot_list):\n")
        options: dict[str, Node] = {}
        if self.owed or k <= self.max_subtasks:
            header = self._header(k, remaining)
            if header is None:
                self._cap(f"sub-task {k}")
            else:
                options["header"] = header
        if not self.owed:
            options.update(self._orch_options(remaining))
        return self._choose({**self.rules, **self._orch_rules(remaining)}, options)

    def _body(self, remaining: int) -> Forced | Choose:
        """A body line. The budget is kept on the unchecked choices (the world check's preferences give
        way to it): a line is offered if the cheapest unchecked completion still fits after it, and
        when no checked line fits, the unchecked ones that do are offered (a dead end, counted)."""
        fn = self.functions[-1]
        options: dict[str, Node] = {}
        closing = self._closing_cost()
        unchecked = self._candidates(fn)
        actions = self._succeeding(fn)
        room = fn.steps < self.max_steps - 1  # leave a step for the closing action
        goto_room = fn.steps < self.max_steps if self.goto_acts else room
        # The cheapest way on to an action: one that succeeds now, or else a GoToObject and one after it.
        cheapest = min(self._line_len(c) for c in unchecked)
        to_action = min((self._line_len(c) for c in actions),
                        default=self.goto_max + self.action_max if self.world is not None else cheapest)
        # Going somewhere twice in a row is never useful, comment or not (on a site, a move is a step of its own).
        if goto_room and (fn.last_step != "goto" or self.goto_acts):
            goto = self._goto_node(fn, remaining - closing)
            if goto is not None:
                options["goto"] = goto
            else:
                self._cap("a GoToObject step")
        if room and fn.last_call[0] == "ToggleObjectOn" and self.sleep_len + cheapest + closing <= remaining:
            options["sleep"] = seq(INDENT, "time.sleep(", chars("123456789"), ")\n")  # wait for what was switched on
        if fn.steps < self.max_steps:
            action = self._node([c for c in actions
                                 if self._line_len(c) + self._hold_after(fn, c) <= remaining - closing])
            if action is not None:
                options["action"] = action
        # With a world check a function puts down what it holds before it ends, if there is room to.
        must_release = self.world is not None and not self.allocated and fn.held and "action" in options
        step_follows = self.world is None or bool({"goto", "action"} & set(options))
        if (fn.last == "action" or (self.goto_acts and fn.last == "goto")) and not must_release:
            options["end"] = "\n"
        elif not step_follows:
            # Nothing checked fits or succeeds (a dead end, counted): the unchecked actions that fit.
            self.world.dead_ends += 1  # type: ignore[union-attr]
            options["action"] = self._node([c for c in unchecked if self._line_len(c) <= remaining - closing])
        # Line-by-line comments: at most one before each step, and only where a step can follow it.
        if self.comments and step_follows and fn.last != "comment" and fn.steps < self.max_steps \
                and fn.comments <= fn.steps:
            comment_max = COMMENT_LEN if self.allocated else STEP_COMMENT_LEN
            cap = min(comment_max, remaining - to_action - closing - len(INDENT) - len("# \n"))
            if cap >= 1:
                options["comment"] = seq(INDENT, "# ", comment_text(cap), "\n")
        return self._choose(self.rules, options)

    def _mark_went(self, fn: WrittenFunction, slot: int | None) -> None:
        fn.went = True
        fn.whole = fn.whole or slot is None
        fn.together = slot is None
        fn.slots_went |= set(range(self.team_size)) if slot is None else {slot}

    def _steps(self, fn: WrittenFunction) -> list[Step]:
        pickups = {s.name for s in self.skills if s.action == "PickupObject"}
        return [Step(slot, skill, self.scene.masses.get(objects[0], 0.0) if skill in pickups else 0.0,
                     call_demand(self.scene, skill, objects))
                for slot, skill, objects in fn.calls]

    # --------------------------------------------------------------- feeding

    def _advance(self, kind: str, piece: str) -> None:
        if kind == "forced":
            kind = self._forced_kind(piece)
        if kind == "refusal":
            self.phase = "done"
        elif kind == "summary":
            self.summary_lines += 1
            self.owed = self.summary_lines
            self.phase = "summary"
        elif kind == "order":
            self.phase = "order-blank"
        elif kind == "blank":
            self.phase = "header"
        elif kind == "pending":
            self.pending = ""
            self.phase = "orch" if self._unlaunched() else "done"
        elif kind == "header":
            self.functions.append(WrittenFunction(piece[4:piece.index("(")]))
            self.phase = "body"
        elif kind in ("goto", "sleep", "action", "comment"):
            self._step_written(kind, piece)
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
            name = piece.split("target=", 1)[1].split(",")[0].split(")")[0]
            self._launch(name, piece)
            self.threads.append(name)
            self.phase = "threads"
        elif kind == "direct":
            self._launch(piece.split("(", 1)[0], piece)
            self.launched.append(piece.split("(", 1)[0])
            self.phase = "orch" if self._unlaunched() else "done"

    def _forced_kind(self, piece: str) -> str:
        """What a piece of forced text was, from where the plan stands."""
        if self.pending:
            return "pending"
        if self.phase == "order-blank":
            return "blank"
        if piece.startswith("def "):
            return "header"
        if piece == "\n":
            return "end"
        if piece.lstrip().startswith("#"):
            return "comment"
        return "sleep"

    def _step_written(self, kind: str, piece: str) -> None:
        fn = self.functions[-1]
        fn.written += 1
        fn.last = kind
        fn.last_step = kind if kind != "comment" else fn.last_step
        if kind == "comment":
            fn.comments += 1
            return
        fn.steps += 1
        match = _CALL.match(piece.rstrip("\n"))
        if match and self.world is not None:
            slot = int(match.group(2)) if match.group(2) is not None else None
            fn.whole = fn.whole or (self.allocated and slot is None)
            objects = [o for o in match.group(3, 4) if o is not None]
            self.world.apply(self._members(fn, slot), match.group(1), objects)
        if kind == "action":
            fn.track(piece, self.skill_actions)
        else:
            fn.last_call = ("", "")
            if kind == "goto":
                self._mark_went(fn, int(match.group(2)) if match and match.group(2) is not None else None)
            if match:
                fn.calls.append((int(match.group(2)) if match.group(2) else None, match.group(1),
                                 tuple(o for o in match.group(3, 4) if o is not None)))
        for i in range(self.team_size):
            if f"robot_list[{i}]" in piece:
                fn.max_index = max(fn.max_index, i)
