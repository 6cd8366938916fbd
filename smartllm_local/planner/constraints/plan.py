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

Its candidate calls are in :mod:`.candidates`, its costs in :mod:`.budget`. A restated
allocation (:mod:`.restated`) is a plan constraint whose bodies are the
decomposition's.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Sequence

from ...robots import Robot
from ...scene import SceneObjects
from ...scoring import Condition
from ...skills import Skill, SkillSet
from ...world.object_types import base_type
from ..decoding.grammar import Node, Ref, alt, chars, rep, seq
from ..decoding.line_ends import COMMENT_NEXT, INDENTED_NEXT
from ..decoding.protocol import REFUSAL_PREFIX, Choose, Constraint, Forced, Rewrite, longest
from .budget import Budget
from .candidates import Candidates, held_for_good, wanted_whole
from .feasibility import Step, WholeTeam
from .finish import ROOM as FINISH_ROOM
from .finish import Finish, Said
from .format import (
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
    comment_text,
    ordered_subset,
    refusal_line,
    refusal_text_len,
    text_run,
)
from .orchestration import Orchestration
from .repair import Repairer, Repairs
from .world_check import WorldCheck
from .written import CALL_LINE, WrittenFunction, robots_named

STEP_LINE = re.compile(r"^    (\w+)\((.*)\)\n$")

#: What may start the text after a line of each kind, in its last token (see :mod:`..decoding.line_ends`): a summary
#: line is followed by another or by the order line, a header and a body line by an indented line (or a blank
#: one, ending the function where it may end).
FOLLOWS: dict[str, Node] = {"summary": COMMENT_NEXT, "header": INDENTED_NEXT, "goto": INDENTED_NEXT,
                            "action": INDENTED_NEXT, "comment": INDENTED_NEXT, "sleep": INDENTED_NEXT}


def _acts(skills: Sequence[Skill]) -> bool:
    """Whether the skills make a plan: a move, and an action to take where it leads."""
    return any(s.action == "" for s in skills) and any(s.action != "" for s in skills)


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
        for_team: Sequence[Robot] | None = None,
        goals: Sequence[Condition] = (),
        said: Said = Said(),
        repairer: Repairer | None = None,
        stop: bool = True,
        repair: bool = True,
        finish: bool = False,
        together: bool = False,
        cost: Callable[[str], int] = len,
    ):
        """``team`` (or ``team_size``) makes it an allocation; ``for_team`` is the team a decomposition is written
        for: it offers only the calls that team can make (see :class:`.feasibility.WholeTeam`), and a refusal only
        for a reason the catalogue gives (:meth:`_reasons`). ``goals`` (the goal stage's, with a world check): with
        ``stop``, once they all hold in the dry run, no further sub-task is begun. ``repairer`` (a decomposition's,
        with a world check): with ``repair``, a call that fails where the function stands is offered too, and
        written after the planner's steps that enable it (see :mod:`.repair`); with ``finish`` and goals, the goals
        the plan leaves unmet are met by a last sub-task of the planner's (:mod:`.finish`, which reads what the
        instruction ``said`` of them). ``together`` (an allocation's): a function that can join the block of threads
        being written joins it (no direct call, no start, where a thread is offered), and a restated body brings in
        no robot it can do without, so the plan has as few transitions as the order of its functions allows.
        ``cost``: the tokens the planner's own text costs (its length where unknown: a token spells a character)."""
        super().__init__()
        if team is not None:
            team_size = len(team)
        self.team = list(team) if team is not None else None
        self.allocated = team_size is not None
        self.team_size = team_size or 0
        self.comments, self.stop = comments, stop
        self.summary = summary and not self.allocated and not function_names
        self.fixed_names = list(function_names or [])
        self.max_subtasks = len(self.fixed_names) or max_subtasks
        self.max_steps = max(2, max_steps)
        self.allow_refusal = allow_refusal
        self.scene, self.world, self.cost = scene, world, cost
        self.goals, self.said = (list(goals), said) if world is not None else ([], Said())
        self.held_at_start = self._all_held()  # goals the plan did not bring about are not kept from it
        self.joins = together and self.allocated
        self.ended_at_goals = False  # a sub-task was withheld: the goals held
        self.finish_made: dict[str, object] | None = None  # the planner's last sub-task (see :mod:`.finish`)
        self.repairs: Repairs | None = None  # with a repairer, once the candidate calls are known
        self.rewrite: str | None = None  # the text that replaces the line just written
        self.rewriting = False  # that text is being fed
        self.phase = "start"
        self._offer_skills(skills, for_team)
        if not self.must_refuse:
            self._start_writing(repairer if world is not None and not self.allocated else None, repair, finish)

    def _offer_skills(self, skills: SkillSet, for_team: Sequence[Robot] | None) -> None:
        """The skills the plan may call (those that act on this scene, and for a decomposition written for a
        team, those the team can make), and the refusal line: with a team, one of the reasons the catalogue
        gives (none: it cannot refuse); a team that can make no call here can only refuse."""
        scene = self.scene
        usable = [s for s in skills.values() if all(scene.types_for(a) for a in s.arguments[: s.required])]
        if not _acts(usable):
            raise ValueError("the skills cannot act on any object of this scene")
        self.lifting = skills.lifting
        self.whole = WholeTeam(for_team, scene, self.lifting) if for_team is not None else None
        self.skills = [s for s in usable if self._may_use(s)]
        self.skill_names = [s.name for s in self.skills]
        self.skill_actions = {s.name: s.action for s in self.skills}
        self.by_name = {s.name: s for s in skills.values()}
        reasons = self._reasons(usable)
        self.refusal_line = seq(REFUSAL_PREFIX, alt(*reasons), "\n") if reasons else None
        self.refusal_len = longest(self.refusal_line, {}) if self.refusal_line is not None else 0
        self.must_refuse = not _acts(self.skills)

    def _start_writing(self, repairer: Repairer | None, repair: bool, finish: bool) -> None:
        """The grammar's shared rules, the calls on offer, the budget and the empty plan being written."""
        self.rules: dict[str, Node] = {"skills": ordered_subset(self.skill_names, ", ")}
        self.robot_args = ["robot_list", *(f"robot_list[{i}]" for i in range(self.team_size))] if self.allocated else []
        self.robot_arg_len = max((len(a) + 2 for a in self.robot_args), default=0)  # with its ", "
        self.sleep_len = len(INDENT) + len("time.sleep(9)\n")
        self._lists: dict[tuple[str, int, int], list[tuple[int, ...]] | None] = {}
        self.candidates = Candidates(self.scene, self.skills, robot_arg_len=self.robot_arg_len,
                                     allocated=self.allocated, world=self.world, max_steps=self.max_steps,
                                     allows=self.whole.can if self.whole is not None else None,
                                     spared=wanted_whole(self.goals), kept=held_for_good(self.goals, self.skills))
        self.fresh_action = self.candidates.fresh_action(WrittenFunction(""))
        self._plan_with(repairer, repair, finish)
        self.budget = Budget(allocated=self.allocated, team_size=self.team_size, fixed_names=self.fixed_names,
                             fresh_action=self.fresh_action, body_cost=self._body_cost)
        self.skills_len = longest(Ref("skills"), self.rules)
        self.summary_lines = 0
        self.owed = len(self.fixed_names) or None  # defs promised (by the summary, or the decomposition)
        self.functions: list[WrittenFunction] = []
        self.launched: list[str] = []
        self.threads: list[str] = []  # targets of the block being written
        self.busy: set[int] = set()  # robots given to the threads of that block
        self.pending = ""  # boilerplate to write next (the rest of a block's starts and joins)

    def _plan_with(self, repairer: Repairer | None, repair: bool, finish: bool) -> None:
        """The planner's part in a decomposition: repairs (:mod:`.repair`) and the last sub-task (:mod:`.finish`)."""
        if repairer is not None and repair:
            self.repairs = Repairs(repairer, self.candidates, self.whole, self.max_steps, self.by_name)
        self.finish = Finish(repairer, self.candidates, self.whole, self.goals, self.max_steps, self.by_name,
                             self.said) \
            if repairer is not None and finish and self.goals and not self.summary else None
        if self.finish is not None and self.world is not None:  # a robot no sub-task used is left for it
            self.max_subtasks = min(self.max_subtasks, len(self.world.run.team) - 1)
        self.finish_room: int | None = None if self.finish is not None else 0  # and room (set from the budget)
        self.finish_text = ""  # the planner's last sub-task, once found

    def _may_use(self, skill: Skill) -> bool:
        """Whether a plan for the team may call the skill: a robot of it has the skill, and the whole team
        can make some call of it here (lift some object, get to some place)."""
        whole = self.whole
        return whole is None or skill.name in whole.skills and any(
            whole.can(skill.name, (t,)) for t in self.scene.types_for(skill.arguments[0]))

    def _reasons(self, usable: Sequence[Skill]) -> list[Node]:
        """What a decomposition for the team may give as the reason of a refusal: facts of the catalogue only
        (the skills of this scene no robot of the team has, an object heavier than the team lifts, a place
        it cannot get to), so a refusal never says what is not so. With a team that can make every call,
        none: there is no reason to refuse."""
        whole = self.whole
        if whole is None:
            return []
        missing = sorted(s.name for s in usable if s.name not in whole.skills)
        options: list[Node] = [seq("no robot of the team has ", ordered_subset(missing, ", "))] if missing else []
        options += dict.fromkeys(reason for s in usable if s.name in whole.skills
                                 for t in self.scene.types_for(s.arguments[0]) if not whole.can(s.name, (t,))
                                 for reason in whole.why_not(s.name, (t,)))
        return options

    # ---------------------------------------------------------------- costs

    def _body_cost(self, index: int) -> int:
        """The cheapest body of the function at ``index``: one action."""
        return self.fresh_action

    def _owed_cost(self) -> int:
        return sum(self.budget.def_cost(k) for k in range(len(self.functions) + 1, (self.owed or 0) + 1))

    def _closing_cost(self) -> int:
        """The cheapest completion once the current function's body is finished: its end,
        the owed functions, and a direct call for every function not launched."""
        return 1 + self._owed_cost() + self.budget.calls_cost(self._unlaunched())

    def minimum_budget(self) -> int:
        if self.must_refuse:
            return self.refusal_len
        if self.fixed_names:
            return sum(self.budget.def_cost(k) for k in range(1, len(self.fixed_names) + 1))
        if self.summary:
            return len("# SubTask 1: x (skills: )\n") + self.skills_len + self.budget.summary_after(1)
        return self.budget.def_cost(1)

    def world_counts(self) -> tuple[int, int]:
        return (self.world.tries, self.world.dead_ends) if self.world is not None else (0, 0)

    def _cap(self, what: str) -> None:
        if what not in self.capped:
            self.capped.append(what)

    # ------------------------------------------------------------- choices

    def next(self, remaining: int) -> Forced | Choose | Rewrite | None:
        if self.rewrite is not None:
            rewrite, self.rewrite = self.rewrite, None
            self.rewriting = bool(rewrite)
            return Rewrite(rewrite)
        if self.must_refuse:
            return self._choose({}, {"refusal": self.refusal_line}) if self.phase == "start" else None  # type: ignore[dict-item]
        if self.pending:
            return Forced(self.pending)
        if self.phase == "order-blank":
            return Forced("\n")
        if self.phase == "done" and self.finish is not None and self.refusal is None:
            return self._finishing(remaining)
        if self.phase == "finish":
            return Forced(self.finish_text)
        if self.finish_room is None:  # what the model's part leaves for the planner's, where the budget has it
            self.finish_room = min(FINISH_ROOM, max(0, remaining - self.minimum_budget()))
        handler = {
            "start": self._start, "summary": self._summary, "header": self._header_choice, "body": self._body,
            "orch": self._orch, "threads": self._threads,
        }.get(self.phase)
        return handler(remaining - self.finish_room) if handler else None

    def _choose(self, rules: dict[str, Node], options: dict[str, Node]) -> Choose:  # type: ignore[override]
        if self.allocated:
            rules = {**rules, "robot-arg": alt(*self.robot_args)}
        return super()._choose(rules, options, FOLLOWS)

    def _refusal(self, remaining: int) -> Node | None:
        """A refusal line that fits: for a team, one of the catalogue's reasons; without one, the model's."""
        if self.whole is not None:
            return self.refusal_line if self.refusal_line is not None and self.refusal_len <= remaining else None
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
            options["summary"] = self._summary_line(1, remaining - self.budget.summary_after(1))
        elif self.fixed_names:
            options["header"] = f"def {self.fixed_names[0]}(robot_list):\n"
        else:
            options["header"] = self._header(1, remaining)
        return self._choose(self.rules, options)

    def _summary(self, remaining: int) -> Choose:
        options: dict[str, Node] = {}
        k = self.summary_lines
        if k < self.max_subtasks:
            line = self._summary_line(k + 1, remaining - self.budget.summary_after(k + 1))
            if line is None:
                self._cap(f"sub-task {k + 1}")
            else:
                options["summary"] = line
        cap = min(ORDER_LEN, remaining - (self.budget.summary_after(k) - 1))
        options["order"] = seq("# ", text_run(ORDER_CHARS, cap), "\n")
        return self._choose(self.rules, options)

    def _header(self, k: int, remaining: int) -> Node | None:
        """A ``def subtask<k>_<name>():`` line whose name leaves room for the function and its call."""
        base = f"subtask{k}_"
        rest = self.budget.calls_cost(self._unlaunched()) + sum(
            self.budget.def_cost(i) for i in range(k + 1, (self.owed or 0) + 1))
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
        if self.owed or (k <= self.max_subtasks and not (self.stop and self._goals_held())):
            header = self._header(k, remaining)
            if header is None:
                self._cap(f"sub-task {k}")
            else:
                options["header"] = header
        if not self.owed:
            options.update(self._orch_options(remaining))
        return self._choose({**self.rules, **self._orch_rules(remaining)}, options)

    def _finishing(self, remaining: int) -> Forced | None:
        """The plan is complete: a blank line before the planner's last sub-task (sought once), if there is one."""
        finish, self.finish = self.finish, None
        assert finish is not None and self.world is not None
        calls = [(self.skill_actions.get(skill), base_type(objects[0])) for fn in self.functions
                 for _, skill, objects in fn.calls]
        acted = {thing for action, thing in calls if action}
        put = {thing for action, thing in calls if action == "PutObject"}
        text = finish.text(self.world, len(self.functions) + 1, remaining - 1, acted, put, self.cost)
        if text is None:
            return None
        self.finish_made, self.finish_text, self.phase = finish.made, text, "finish"
        return Forced("\n")

    def _goals_held(self) -> bool:
        """Whether every stated goal holds in the dry run (a sub-task begun now would be one nobody asked for)."""
        held = self._all_held()
        self.ended_at_goals = self.ended_at_goals or held
        return held

    def _body(self, remaining: int) -> Forced | Choose:
        """A body line, where the plan has brought the stated goals about (stopping at them) one that leaves them
        holding: asked to put the potato in the fridge and make sure the light is off, the 0.5B did both, then
        switched the light on again."""
        if self.world is None:
            return self._line(remaining)
        self.world.keep = self.goals if self.stop and not self.allocated and not self.held_at_start \
            and self._all_held() else ()
        try:
            return self._line(remaining)
        finally:
            self.world.keep = ()

    def _all_held(self) -> bool:
        return bool(self.goals) and self.world is not None and self.world.met(self.goals) == len(self.goals)

    def _line(self, remaining: int) -> Forced | Choose:
        """A body line. The budget is kept on the unchecked choices (the world check's preferences give
        way to it): a line is offered if the cheapest unchecked completion still fits after it, and
        when no checked line fits, the unchecked ones that do are offered (a dead end, counted)."""
        fn = self.functions[-1]
        calls = self.candidates
        options: dict[str, Node] = {}
        closing = self._closing_cost()
        unchecked = calls.of(fn)
        actions = calls.succeeding(fn, self._members(fn, None))
        room = fn.steps < self.max_steps - 1  # leave a step for the closing action
        goto_room = fn.steps < self.max_steps if calls.goto_acts else room
        # The cheapest way on to an action: one that succeeds now, or else a GoToObject and one after it.
        cheapest = min(calls.line_len(c) for c in unchecked)
        to_action = min((calls.line_len(c) + calls.hold_after(fn, c) for c in actions),
                        default=calls.goto_max + calls.action_max if self.world is not None else cheapest)
        # Going somewhere twice in a row is never useful, comment or not (on a site, a move is a step of its own).
        if goto_room and (fn.last_step != "goto" or calls.goto_acts):
            goto = calls.goto_node(fn, remaining - closing, self._members(fn, None))
            if goto is not None:
                options["goto"] = goto
            else:
                self._cap("a GoToObject step")
        if room and fn.last_call[0] == "ToggleObjectOn" and self.sleep_len + to_action + closing <= remaining:
            options["sleep"] = seq(INDENT, "time.sleep(", chars("123456789"), ")\n")  # wait for what was switched on
        if fn.steps < self.max_steps:
            action = calls.node([c for c in actions
                                 if calls.line_len(c) + calls.hold_after(fn, c) <= remaining - closing])
            if action is not None:
                options["action"] = action
            repair = calls.node(self.repairs.offered(len(self.functions) - 1, fn, actions, remaining - closing)) \
                if self.repairs is not None else None
            if repair is not None:
                options["repair"] = repair
        # With a world check a function puts down what it holds before it ends, if there is room to.
        must_release = self.world is not None and not self.allocated and fn.held and "action" in options
        step_follows = self.world is None or bool({"goto", "action"} & set(options))
        if (fn.last == "action" or (calls.goto_acts and fn.last == "goto")) and not must_release:
            options["end"] = "\n"
        elif not step_follows:
            # Nothing checked fits or succeeds (a dead end, counted): the unchecked actions that fit.
            self.world.dead_ends += 1  # type: ignore[union-attr]
            options["action"] = calls.node([c for c in unchecked if calls.line_len(c) <= remaining - closing])
        # Line-by-line comments: at most one before each step, and only where a step can follow it.
        if self.comments and step_follows and fn.last != "comment" and fn.steps < self.max_steps \
                and fn.comments <= fn.steps:
            comment_max = COMMENT_LEN if self.allocated else STEP_COMMENT_LEN
            cap = min(comment_max, remaining - to_action - closing - len(INDENT) - len("# \n"))
            if cap >= 1:
                options["comment"] = seq(INDENT, "# ", comment_text(cap), "\n")
        return self._choose(self.rules, options)

    def _repair(self, piece: str) -> None:
        """The model wrote a call that fails now: the planner's steps and the call, or the line taken back."""
        fn = self.functions[-1]
        self.text = self.text[: len(self.text) - len(piece)]
        assert self.repairs is not None  # a repair line is offered only with them
        self.rewrite = self.repairs.rewrite(len(self.functions) - 1, fn, self._members(fn, None)[0], piece)

    def _members(self, fn: WrittenFunction, slot: int | None) -> list[int]:
        """The dry run's robots for a call: the function's own (decomposition), or its robot_list slot
        (allocation; a function that names the whole list is run by the whole team)."""
        if not self.allocated:
            return [len(self.functions) - 1]
        return [slot] if slot is not None else list(range(self.team_size))

    def _mark_went(self, fn: WrittenFunction, slot: int | None) -> None:
        fn.went = True
        fn.whole = fn.whole or slot is None
        fn.together = slot is None
        fn.slots_went |= set(range(self.team_size)) if slot is None else {slot}

    def _steps(self, fn: WrittenFunction) -> list[Step]:
        return [Step(slot, skill, self.scene.masses.get(objects[0], 0.0) if skill in self.lifting else 0.0,
                     self.scene.world.call_demand(skill, objects))
                for slot, skill, objects in fn.calls]

    # --------------------------------------------------------------- feeding

    def _advance(self, kind: str, piece: str) -> None:
        if kind == "forced":
            kind = self._forced_kind(piece)
        if kind == "repair":
            self._repair(piece)
        elif kind == "finish":
            self._finished(piece)
        elif kind == "finish-blank":
            pass
        elif kind == "rewrite":
            self.rewriting = False
            for line in piece.splitlines(keepends=True):
                self._step_written(self._call_kind(line), line)
        elif kind == "refusal":
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
            self.busy = set()
            self.pending = "".join(f"t{i}.start()\n" for i in range(2, n + 1))
            self.pending += "".join(f"t{i}.join()\n" for i in range(1, n + 1))
        elif kind == "thread":
            name = piece.split("target=", 1)[1].split(",")[0].split(")")[0]
            self._launch(name, piece)
            self.threads.append(name)
            self.busy.update(robots_named(piece))
            self.phase = "threads"
        elif kind == "direct":
            self._launch(piece.split("(", 1)[0], piece)
            self.launched.append(piece.split("(", 1)[0])
            self.phase = "orch" if self._unlaunched() else "done"

    def _forced_kind(self, piece: str) -> str:
        """What a piece of forced text was, from where the plan stands."""
        if self.rewriting:
            return "rewrite"
        if self.phase == "finish":
            return "finish-blank" if piece == "\n" else "finish"
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

    def _finished(self, piece: str) -> None:
        """The planner's last sub-task was written: its steps applied in the dry run, its call made."""
        for line in piece.splitlines(keepends=True):
            if line.startswith("def "):
                self.functions.append(WrittenFunction(line[4:line.index("(")]))
            elif line.lstrip().startswith("#"):
                self._step_written("comment", line)
            elif line.startswith(INDENT):
                self._step_written(self._call_kind(line), line)
            elif line.strip():
                self.launched.append(line.split("(", 1)[0])
        self.phase = "done"

    def _call_kind(self, line: str) -> str:
        """Whether a call line the planner wrote is a go-to or an action."""
        return "goto" if line.strip().split("(")[0] in {s.name for s in self.candidates.gotos} else "action"

    def _step_written(self, kind: str, piece: str) -> None:
        fn = self.functions[-1]
        fn.written += 1
        fn.last = kind
        fn.last_step = kind if kind != "comment" else fn.last_step
        if kind == "comment":
            fn.comments += 1
            return
        fn.steps += 1
        match = CALL_LINE.match(piece.rstrip("\n"))
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
