"""The goal stage: from the instruction and the scene alone, the model states what must hold when the task is done.

It reads nothing else (no team, no task file, no ground truth), so the goals it states can be used to
choose among plans, or handed to a classical planner, without the benchmark's goals leaking into
planning. Its output is a :class:`~smartllm_local.goal_language.GoalStatement`, whose goals the scorer
scores as it scores a task's. It runs on demand (``Planner.goals``, ``plan --goals``); ``plan`` itself
does not run it.
"""

from __future__ import annotations

import time
from collections.abc import Collection, Mapping, Sequence
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any

from ..errors import PlanError
from ..goal_language import GoalStatement, condition_line, parse_goal_statement
from ..robots import Robot
from ..scene import GoalVocabulary, SceneObjects
from ..scoring import Condition, condition_holds, containment
from ..skills import SkillSet
from ..world.object_types import base_type
from .asked import (
    GIVES,
    as_goal,
    brought_by_model,
    coverage,
    gives_nothing_asked,
    invented,
    named_apart,
    named_in_full,
    names,
    placed_by_model,
    present_yet_refused,
    unasked,
)
from .backends.base import Backend
from .candidates import mean_logprob, write_all
from .constraints.finish import Said
from .constraints.goal import GoalConstraint, goal_vocabulary
from .owed import Asked, asked_of, reading_vocabulary
from .progress import SILENT
from .prompting.asked_words import (
    load_state_words,
    placements_asked,
    states_asked,
)
from .prompting.goal_prompt import GoalExample, goal_prompt, load_goal_examples
from .result import PlanResult, StageRecord
from .stages import Fitted, fit_prompt, run_stage

if TYPE_CHECKING:
    from .pipeline import Planner

STAGE = "goal"
#: Who refused a task whose stated goals its team cannot meet.
GOAL_CHECK = "goal check"
GOAL_BUDGET = 384  # tokens: MAX_GOALS of the longest conditions (some 40 characters) fit


@dataclass
class StatedGoals:
    """The goal stage's run (written to --out as other stages are) and what it stated: the goals, the
    refusal, or, without the grammar, an error where the output is not a statement."""

    record: StageRecord
    statement: GoalStatement | None

    @property
    def refusal(self) -> str | None:
        return self.record.refusal

    @property
    def error(self) -> str:
        return self.record.error

    def summary(self) -> dict[str, Any]:
        """What a run's JSON keeps: the stated conditions (as lines), the refusal and who refused, the error."""
        stated = self.statement.text().splitlines() if self.statement and self.statement.refusal is None else []
        return {"stated": stated, "refusal": self.refusal, "refused_by": self.record.refused_by or None,
                "error": self.error or None}

    def report(self) -> str:
        """The goals as the plan command prints them, after the plan."""
        if self.statement is None:
            return f"# Goals: none stated ({self.error})\n"
        return "# Goals:\n" + self.statement.text()


def goal_examples(planner: Planner) -> list[GoalExample]:
    """The goal examples of the planner's world (beside its plans' worked examples)."""
    return load_goal_examples(planner.world.examples_dir())


def state_goals(planner: Planner, instruction: str, floor_plan: str | int, *, refusals: bool = True) -> StatedGoals:
    """Run the goal stage for one instruction in one scene; without ``refusals`` the model must state goals
    (the grammar offers no refusal unless the scene gives it nothing to state). A refusal for something the
    instruction names and the scene has is the model's mistake: the stage is run again without refusals."""
    stated = _state_goals(planner, instruction, floor_plan, refusals=refusals)
    if stated.refusal is None or stated.record.refused_by != "model" or not planner.config.grammar:
        return stated  # (without the grammar, nothing would keep the model from refusing again)
    present = present_yet_refused(stated.refusal, instruction, planner.scene(floor_plan).types)
    if present is None:
        return stated
    again = _state_goals(planner, instruction, floor_plan, refusals=False)
    again.record.overturned = f"{stated.refusal} (the scene has a {present})"
    again.record.seconds += stated.record.seconds
    again.record.generated_tokens += stated.record.generated_tokens
    return again


def _state_goals(planner: Planner, instruction: str, floor_plan: str | int, *, refusals: bool) -> StatedGoals:
    """The statement, or with several goal candidates the one :func:`choose_statement` keeps (the others in its
    record's ``candidates``)."""
    scene = planner.scene(floor_plan)
    words = load_state_words(planner.world.examples_dir())
    vocabulary = goal_vocabulary(scene)
    if planner.config.grammar:
        vocabulary = reading_vocabulary(instruction, vocabulary, words)
    prompt = fit_prompt(lambda ex: goal_prompt(instruction, scene, ex), goal_examples(planner), planner.backend,
                        GOAL_BUDGET, planner.chat)
    count = planner.config.goal_candidates
    objects = scene.world.dry_run(scene.floor_plan, planner.catalogue.skills).objects if planner.config.grammar else []
    there = placed_now(objects, vocabulary)
    asked = asked_of(instruction, vocabulary, words, objects)

    def write(backend: Backend, k: int) -> StatedGoals:
        return _candidate(planner, backend, k, prompt, scene, vocabulary, instruction, asked, refusals=refusals)

    if count == 1:
        chosen = write(planner.backend, 0)
    else:
        started = time.perf_counter()
        chosen = choose_statement(instruction, vocabulary.types, write_all(planner.backend, count, write))
        chosen.record.seconds = time.perf_counter() - started
    chosen = _without_placed(chosen, there)
    return _without_unasked(chosen, instruction, asked) if planner.config.grammar else chosen


def placed_now(objects: Sequence[Mapping[str, Any]], vocabulary: GoalVocabulary) -> frozenset[Condition]:
    """The ``<Item> in <Receptacle>`` conditions ``vocabulary`` can say that hold among ``objects`` (a scene's, as
    its world's dry run begins, before any call): where each thing is."""
    inside = containment(objects)
    sayable = [Condition(holder, item=kind) for kind, holders in vocabulary.holders.items() for holder in holders]
    return frozenset(c for c in sayable if condition_holds(c, objects, inside))


def _without_unasked(stated: StatedGoals, instruction: str, asked: Asked) -> StatedGoals:
    """The statement less its lines nobody asked for (:func:`.asked.unasked`: no thing of them named, none in a
    line that is), where a line asked for is left; a state or a holder asked for in so many words stays ("boil
    some water": ``Pot hot``). A switch's verb names nothing (``Asked.naming``: "switch off the lamp" names no
    LightSwitch). Every goal condition of the household benchmark, held-out tasks included, is asked for so; the
    small models add a light switched on to moving a laptop, a tomato warmed to boiling water. Where the instruction
    asks for nothing moved (``Asked.moves``), a thing put in a holder it neither names nor asks into, and that gives
    the thing no state, is left out too (:func:`.asked.placed_by_model`), as is one put in a holder that gives only
    states nobody asked for (:func:`.asked.gives_nothing_asked`: "open the fridge and cut the apple"), and a thing it
    does not name, put in a holder nobody asks things into that gives it no state (:func:`.asked.brought_by_model`:
    asked to lift the loo seat, the 1.5B put the toilet paper in the toilet, and the goal check refused). So
    is a thing put in a holder the instruction asks other things into, by words that do not name it
    (:meth:`Asked.put_elsewhere`: asked to cut the bread and put the apple in the microwave, the 0.5B put the bread
    in it too), and a thing's
    pieces beside the whole thing where nobody asked it cut (:func:`piece_beside_whole`), unless owed, and the whole
    thing put where its piece is owed (:meth:`Asked.whole_of_piece_owed`)."""
    statement = stated.statement
    if statement is None or statement.refusal is not None:
        return stated
    out = {c for c in unasked(asked.naming or instruction, statement.conditions, asked.placements)
           if c.state not in asked.states and c.subject not in asked.placements}
    out |= {c for c in statement.conditions if asked.put_elsewhere(c) or asked.whole_of_piece_owed(c)
            or piece_beside_whole(c, statement.conditions, asked.states.get("SLICED", ())) and not asked.owes(c)}
    if not asked.moves:  # nothing asked moved: a holder nobody named, or one for a state nobody asked, is the model's
        out |= {c for c in statement.conditions if placed_by_model(instruction, c, asked.placements)
                or gives_nothing_asked(instruction, c, asked.states, asked.placements)
                or brought_by_model(instruction, c, asked.placements)}
    return _leave_out(stated, out, "unasked")


def piece_beside_whole(condition: Condition, stated: Collection[Condition], cut: Collection[str]) -> bool:
    """Whether the condition is about a thing's pieces, the thing not asked cut (``cut``), beside the same condition
    of the whole thing, or, putting them somewhere, beside a line putting the whole thing somewhere: the scorer counts
    a slice in the microwave as the apple, so the pieces' line asks for nothing but a cut. Asked to put the apple, the
    egg and the potato in the microwave, the 0.5B stated `AppleSliced in Microwave` beside `Apple in Microwave`, for
    a team that cannot slice, and no plan met either (dev6-s1); asked to take the tomato out of the fridge and leave
    it on the counter, the 1.5B stated `TomatoSliced in Fridge` beside `Tomato in CounterTop` (dev7-e1)."""
    whole = Condition(base_type(condition.subject), state=condition.state,
                      item=None if condition.item is None else base_type(condition.item))
    if whole == condition or {whole.subject, whole.item} & set(cut):
        return False
    return whole in stated or condition.item is not None and whole.item != condition.item and \
        any(c.item == whole.item for c in stated)


def _without_placed(stated: StatedGoals, placed: Collection[Condition]) -> StatedGoals:
    """The statement less its lines that put a thing where it is as the scene begins (``placed``), where some line
    is left: they ask the team for nothing, and a small model states where a thing is now beside where it must go
    ("take the cloth out of the bathtub and leave it on the counter": ``Cloth in BathtubBasin`` and ``Cloth in
    CounterTop``, which no plan meets). No household goal puts a thing where its scene has it already. Kept from
    writing such a line, the models wrote worse in its place (the statue moved off the side table), so it is
    written, and left out here. A state is kept, though it hold already: a plan may undo it on the way (a fridge
    opened, a patrol's robots away from their base)."""
    return _leave_out(stated, placed, "placed_already")


def _leave_out(stated: StatedGoals, out: Collection[Condition], field: str) -> StatedGoals:
    """The statement less its goals all of whose conditions are ``out``, where some goal is left; those left out
    in the record's ``field``."""
    statement = stated.statement
    if statement is None or statement.refusal is not None:
        return stated
    kept = tuple(g for g in statement.goals if not all(c in out for c in g.conditions()))
    if len(kept) in (0, len(statement.goals)):
        return stated
    setattr(stated.record, field, [condition_line(c) for c in statement.conditions if c in out])
    statement = replace(statement, goals=kept)
    stated.record.output = statement.text() + "\n"
    return StatedGoals(stated.record, statement)


def checked_against_team(record: StageRecord, instruction: str, scene: SceneObjects, conditions: Sequence[Condition],
                         team: Sequence[Robot], skills: SkillSet) -> dict[Condition, list[str]]:
    """Each stated condition with why no plan of ``team`` can meet it (empty where one can), less those out of
    reach that nobody asked for (:func:`.asked.invented`), which leave the record's output for its
    ``dropped_goals``: a task is refused for what it asks, not for the model's invention. A state the instruction
    has no words for, of a thing it puts somewhere or of the holder it puts things in, is the model's: asked to put
    three things on the bed, the 0.5B stated `Bed clean` too, for a team that cannot clean. So is one of any thing
    where the words ask for other states: asked to switch the desk lamp off before bed, the 0.5B stated `Bed clean`
    too, for a robot that only switches (dev7-e2); "freshen up the bed" asks for no state in so many words, and its
    bed's `clean` is asked. Such a state within reach goes too, where another goal is left: asked to put the
    racket and the bat on the bed, the 0.5B stated `Bed clean`, and a robot cleaned the bed (dev7-s2); not one of
    a holder that gives a state the words ask for (toasted, `Toaster on` is the means). A liquid named is a thing
    filled ("boil some water in the pot")."""
    problems = {c: scene.world.unattainable([as_goal(c)], team, skills, scene.floor_plan) for c in conditions}
    words = load_state_words(scene.world.examples_dir())
    placed = placements_asked(instruction, goal_vocabulary(scene), words)
    not_said = words.unsaid(instruction) - set(words.filled_by(instruction))
    unsaid = {(kind, state) for holder, things in placed.items() for kind in (holder, *things) for state in not_said}
    asked = set(states_asked(instruction, words.asked, words.verbs))
    if asked:  # words ask for states: the others are the model's
        unsaid |= {(base_type(c.subject), c.state) for c in conditions if c.state in not_said}
    dropped = invented(instruction, [c for c, why in problems.items() if why], conditions, list(placed), unsaid)
    within = [c for c in conditions if c not in dropped and (base_type(c.subject), c.state) in unsaid
              and not GIVES.get(base_type(c.subject), frozenset()) & asked]
    if any(c not in within and c not in dropped for c in conditions):
        dropped += within
    if dropped:
        record.dropped_goals = [condition_line(c) for c in dropped]
        record.output = "".join(line for line in record.output.splitlines(keepends=True)
                                if line.rstrip("\n") not in record.dropped_goals)
    return {c: why for c, why in problems.items() if c not in dropped}


def holders_asked(instruction: str, scene: SceneObjects) -> list[str]:
    """The scene's holders the instruction asks things into in so many words ("throw the newspaper out": the
    GarbageCan), in its world's ``[placements]`` and ``[put]``."""
    words = load_state_words(scene.world.examples_dir())
    return list(placements_asked(instruction, goal_vocabulary(scene), words))


def said_of(instruction: str, scene: SceneObjects, goals: Sequence[Condition],
            objects: Sequence[Mapping[str, Any]] = ()) -> Said:
    """What the instruction says of the stated ``goals``, for the planner's last sub-task: those whose thing it
    names; those its words ask for, read as the goal stage reads them (:func:`asked_of`, with where the scene's
    ``objects`` stand as it begins): a state asked, of a thing they name or, naming none, of any; a thing put in a
    holder they name, where they name no thing or name it; the holders it names (not by a word of another thing's
    name) or asks things into, each with the things asked into it."""
    vocabulary = goal_vocabulary(scene)
    asked = asked_of(instruction, vocabulary, load_state_words(scene.world.examples_dir()), objects)
    holders = {t: tuple(asked.placements.get(t, ())) for t in scene.types_for("receptacle")
               if t in asked.placements or named_apart(instruction, t, vocabulary.types)}

    def owed(c: Condition) -> bool:
        if c.item is not None:
            things = asked.placements.get(c.subject)
            return things is not None and (not things or base_type(c.item) in things or c.item in things)
        things = asked.states.get(c.state or "")
        return things is not None and (not things or c.subject in things)

    return Said(asked=tuple(c for c in goals if names(instruction, c.item or c.subject)),
                owed=tuple(c for c in goals if owed(c)), holders=holders)


def _candidate(planner: Planner, backend: Backend, k: int, prompt: Fitted, scene: SceneObjects,
               vocabulary: GoalVocabulary, instruction: str, asked: Asked, *, refusals: bool) -> StatedGoals:
    """Goal candidate ``k`` (the planner's sampling for the first, the candidates' for the others) on ``backend``,
    owing what the instruction ``asked`` for in so many words."""
    record = StageRecord(STAGE, chat_template=planner.chat_status)
    constraint = GoalConstraint(vocabulary, allow_refusal=refusals, asked=asked.states, withheld=asked.withheld,
                                placed=asked.placements, each=asked.each) if planner.config.grammar else None
    # No team: the goal is what the instruction asks, whoever reaches it.
    task = PlanResult(instruction=instruction, floor_plan=scene.floor_plan, robots=[])
    rng = planner.stage_rng(task, STAGE if k == 0 else f"{STAGE} candidate {k}")
    run_stage(record, backend, prompt, constraint, output_budget=GOAL_BUDGET,
              sampling=planner.config.candidates.sampling(planner.config.sampling, k), rng=rng,
              progress=planner.progress if k == 0 else SILENT)
    if constraint is not None and constraint.must_refuse:
        record.refused_by = "grammar"
    elif record.refusal is not None:
        record.refused_by = "model"
    statement = None
    try:
        statement = parse_goal_statement(record.output, where="<goal output>", types=vocabulary.types)
    except PlanError as exc:
        record.error = f"goal output is not a goal statement: {exc}"
    if statement is not None and statement.refusal is not None:
        record.refusal = statement.refusal
        record.refused_by = record.refused_by or "model"
    elif statement is not None:
        if constraint is not None and constraint.owed:  # asked for in so many words: the surest goals, first
            statement = replace(statement, goals=tuple(sorted(statement.goals, key=lambda g: not any(
                c in constraint.owed for c in g.conditions()))))
        record.output = statement.text() + "\n"  # each type by its name, each holder "in"; raw_output as written
    return StatedGoals(record, statement)


def choose_statement(instruction: str, types: Sequence[str], stated: Sequence[StatedGoals]) -> StatedGoals:
    """Keep a refusal where most candidates refuse (the likeliest of them); otherwise the statement that says
    something of the most things the instruction names in full (:func:`.asked.named_in_full`: "the bar of soap"
    is the SoapBar), the likeliest among those. Measured on the development half: docs/measurements.md."""
    named = named_in_full(instruction, types)
    covered = {k: coverage(named, s.statement.conditions) for k, s in enumerate(stated)
               if s.refusal is None and s.statement is not None}
    refused = [k for k, s in enumerate(stated) if s.refusal is not None]
    pool = (refused or range(len(stated))) if len(refused) * 2 > len(stated) or not covered else covered
    best = max(pool, key=lambda k: (covered.get(k, 0.0), _mean(stated[k]), -k))
    stated[best].record.candidates = [{"candidate": k, "output": s.record.output, "refusal": s.refusal,
                                       "error": s.error or None, "mean_logprob": round(_mean(s), 4),
                                       "coverage": round(covered[k], 4) if k in covered else None,
                                       "chosen": k == best} for k, s in enumerate(stated)]
    return stated[best]


def _mean(stated: StatedGoals) -> float:
    return mean_logprob(stated.record.logprob, stated.record.choices)


def restated_goals(record: StageRecord, scene: SceneObjects) -> StatedGoals:
    """The statement a goal stage's ``record`` holds (none where it wrote none)."""
    try:
        return StatedGoals(record, parse_goal_statement(record.output, types=goal_vocabulary(scene).types))
    except PlanError:
        return StatedGoals(record, None)


def stated_conditions(result: PlanResult, scene: SceneObjects, record: StageRecord | None = None) -> list[Condition]:
    """The conditions the goal stage stated for a task (its ``record``, or the one in ``result``); none where it
    did not run, refused or wrote no statement."""
    record = record or result.stages.get(STAGE)
    if record is None or record.error or not record.output.strip():
        return []
    try:
        statement = parse_goal_statement(record.output, types=goal_vocabulary(scene).types)
    except PlanError:
        return []
    return statement.conditions if statement.refusal is None else []
