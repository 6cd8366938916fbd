"""Sub-tasks that could only run in turn, joined into one, so that the later costs no transition.

The paper's RU counts each time one group of robots finishes and another takes over. Asked to switch off the desk
lamp and the ceiling light, with one robot of two that switches, the 1.5B wrote a sub-task for each: both need
that robot, so they ran one after the other, a transition the reference plan (one sub-task for both) does not make
(RU 0). Asked to put the dumbbell and the baseball bat on the bed, with two robots that lift the dumbbell only
together, the same. So, in the order written, a sub-task that cannot have a team apart from those of the
sub-tasks before it (:func:`.in_turn.apart`: a team has every skill its sub-task uses and lifts what it lifts) is
written at the end of one of them, the latest that then leaves every sub-task a team apart, where the dry run (a
notional robot per sub-task, in the order written) ends the same: no call fails that did not, and the world ends
alike as the goals see it (:func:`~smartllm_local.scoring.as_scored`), or, where the text met stated goals, it
still meets each: a robot that has carried the watering can to the coffee table and goes on to "the statue" takes
the one nearest it, not the one the other sub-task's robot took, and the coffee table ends as asked (dev6-c3). A
call of the joined sub-task that then fails where it did not on a robot of its own is taken out: asked to slice the
apple and the lettuce, the 1.5B had each sub-task pick up a knife, and the robot holding the first cannot pick up
the second (dev10-s2). A sub-task that joins none starts the sub-tasks after it afresh.

Teams apart are not all a block needs: its sub-tasks must also run at once. Asked to put the apple, the tomato and
the lettuce in the fridge with three robots, the 1.5B wrote a sub-task for each, each opening and closing the
fridge: run at once, the second robot's opening fails where the first's succeeded, so the allocation ran them in
turn, two transitions the reference plan does not make (RU 0 for a plan that met every goal; dev9-c1, the wine
bottle and the salt shaker, the same). So a sub-task with a team apart is joined too where the sub-tasks from the
block's first to it, started together as the executor interleaves them (a notional robot each, a step or a second
of sleep a tick, after the sub-tasks before them ran in turn), fail a call that run in turn succeeds; it is written
at the end of the latest one before it whose joined block then runs at once. Only the model's plan, its stated
goals and the team are read.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace

from ..robots import Robot
from ..scene import SceneObjects
from ..scoring import Condition, as_scored
from ..skills import SkillSet
from .constraints.feasibility import EXACT_COALITIONS
from .constraints.format import INDENT, MAX_SUBTASKS
from .constraints.world_check import Call, WorldCheck
from .constraints.written import sleep_ticks
from .idle_steps import Step, body_end, dry_run, function_lines, function_name, gotos_before, skill_steps
from .in_turn import apart


def join_in_turn(text: str, scene: SceneObjects, skills: SkillSet, team: Sequence[Robot],
                 goals: Sequence[Condition] = ()) -> tuple[str, list[str]]:
    """The decomposition with each sub-task that would wait for the robots of one before it written at the end of
    that one, and what was joined ("<later> into <earlier>"); the text as it was and none where nothing is."""
    joined: list[str] = []
    if not 1 <= len(team) <= EXACT_COALITIONS:
        return text, joined
    while (join := _next_join(text.splitlines(keepends=True), scene, skills, team, goals)) is not None:
        text, later, earlier = join
        joined.append(f"{later} into {earlier}")
    return text, joined


def _next_join(lines: list[str], scene: SceneObjects, skills: SkillSet, team: Sequence[Robot],
               goals: Sequence[Condition]) -> tuple[str, str, str] | None:
    """The first join the rule makes: the text after it, and the later and the earlier sub-task's names."""
    steps = skill_steps(lines, skills)
    if not steps:
        return None
    actions = {name: s.action for name, s in skills.items()}
    defs = [n for n, line in enumerate(lines) if line.startswith("def ")]
    base = None  # the text's dry run, made once a join is tried
    start = 0  # the first sub-task of those the next must have a team apart from
    for later in range(len(defs)):
        teams_apart = apart(range(start, later + 1), steps, (), actions, team, scene)
        if teams_apart and at_once(lines, steps, start, later, scene, skills):
            continue
        for earlier in range(later - 1, start - 1, -1):
            moved = [replace(s, function=earlier) if s.function == later else s for s in steps]
            if not apart(range(start, later), moved, (), actions, team, scene):
                continue
            base = base or _outcome(steps, scene, skills, goals)
            after, joined_steps, taken = _less_failing(_joined(lines, defs, earlier, later),
                                                       body_end(lines, defs[earlier]), skills, scene, base[0])
            if teams_apart and not (joined_steps and at_once(after, joined_steps, start, later - 1, scene, skills)):
                continue  # joined there, the block would still run in turn
            if _ends_well(base, joined_steps, scene, skills, goals):
                what = f" ({', '.join(taken)} taken out)" if taken else ""
                return "".join(after), function_name(lines[defs[later]]), function_name(lines[defs[earlier]]) + what
        start = later
    return None


def at_once(lines: Sequence[str], steps: Sequence[Step], first: int, last: int, scene: SceneObjects,
            skills: SkillSet) -> bool:
    """Whether the sub-tasks ``first`` to ``last`` (by order written) of the text's ``lines`` (its skill calls:
    ``steps``), started together after those before them ran in turn, succeed in every call that they succeed in
    run in turn: a notional robot each, a step or a second of sleep a tick, as the executor interleaves threads."""
    timelines = _timelines(lines, steps)
    world = WorldCheck(scene, skills, MAX_SUBTASKS)
    robot = [[min(f, MAX_SUBTASKS - 1)] for f in range(len(timelines))]
    for f in range(first):
        world.perform([c for c in timelines[f] if c is not None], robot[f])
    if world.runs_together([(timelines[f], robot[f]) for f in range(first, last + 1)]):
        return True
    return not all([world.perform([c for c in timelines[f] if c is not None], robot[f])
                    for f in range(first, last + 1)])


def _timelines(lines: Sequence[str], steps: Sequence[Step]) -> list[list[Call | None]]:
    """Each function's body as the executor runs it: its skill calls (for the whole robot list), and a second of
    nothing for each second it sleeps."""
    at = {s.line: s for s in steps}
    timelines: list[list[Call | None]] = []
    for n, line in enumerate(lines):
        if line.startswith("def "):
            timelines.append([])
        elif n in at:
            timelines[-1].append((None, at[n].skill, at[n].objects))
        elif timelines:
            timelines[-1] += [None] * sleep_ticks(line)
    return timelines


def _less_failing(lines: list[str], moved: int, skills: SkillSet, scene: SceneObjects,
                  failing: int) -> tuple[list[str], list[Step] | None, list[str]]:
    """The joined ``lines`` less the calls of the body moved (from line ``moved``, its comment) that fail in the dry
    run where the text before the join failed ``failing`` calls (with the walk to each call's object that led there,
    :func:`.idle_steps.gotos_before`), their skill calls, and the calls taken out: a robot that cut the apple with the
    butter knife it holds cuts the lettuce with it too, where the lettuce's own sub-task had its robot pick up the
    knife (dev10-s2)."""
    actions = {name: s.action for name, s in skills.items()}
    taken: list[str] = []
    while (steps := skill_steps(lines, skills)) is not None:
        failed, _ = dry_run(steps, (), scene, skills)
        out = {n for n in failed if n > moved}
        if len(failed) <= failing or not out:
            break
        taken += [lines[n].strip() for n in sorted(out)]
        at = {s.line: s for s in steps}
        out |= {n for call in out for n in gotos_before(steps, {call}, actions)
                if at[n].objects[:1] == at[call].objects[:1]}
        lines = [line for n, line in enumerate(lines) if n not in out]
    return lines, steps, taken


def _outcome(steps: Sequence[Step], scene: SceneObjects, skills: SkillSet,
             goals: Sequence[Condition]) -> tuple[int, list[str], list[Condition]]:
    """How many calls fail in the dry run, its end as the goals see it, and the stated goals met."""
    failed, world = dry_run(steps, (), scene, skills)
    return len(failed), as_scored(world.objects()), [c for c in goals if world.met([c])]


def _ends_well(base: tuple[int, list[str], list[Condition]], steps: Sequence[Step] | None, scene: SceneObjects,
               skills: SkillSet, goals: Sequence[Condition]) -> bool:
    """Whether the joined text's ``steps`` fail no more calls than the text's (``base``: its :func:`_outcome`) and
    end alike, or meet every stated goal it met (where it met any)."""
    if steps is None:
        return False
    failed, end, met = _outcome(steps, scene, skills, goals)
    return failed <= base[0] and (end == base[1] or bool(base[2]) and all(c in met for c in base[2]))


def _joined(lines: list[str], defs: Sequence[int], earlier: int, later: int) -> list[str]:
    """The lines with the ``later``-th sub-task's body written at the end of the ``earlier``-th's (after a comment
    naming it), and its definition and the orchestration that ran it gone."""
    head = defs[later]
    body = [line for line in lines[head + 1:body_end(lines, head)] if line.strip()]
    comment = f"{INDENT}# then: {function_name(lines[head])}\n"
    end = body_end(lines, defs[earlier])
    gone = function_lines(lines, later)
    return [line for n, line in enumerate(lines[:end]) if n not in gone] + [comment, *body] + \
        [line for n, line in enumerate(lines[end:], end) if n not in gone]
