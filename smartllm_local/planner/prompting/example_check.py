"""A domain's prompt examples, checked as the planner will use them.

The constraints force the parts of a stage's output that are facts (a coalition line's needs, an
allocation's restated steps), so an example that states them otherwise teaches the model text it can
never write. Each example must be in its stage's grammar for its own team, and an allocated one must
reach SR 1 in its world (its floor plan in AI2-THOR, or the domain's site).
"""

from __future__ import annotations

from ...domain import Domain
from ...errors import SmartLLMError
from ...goal_language import parse_goal_statement
from ...plan_language import parse_plan
from ...scoring import parse_goals, score_execution
from ...worlds import world_of
from ..asked import outnamed
from ..constraints.coalition import CoalitionConstraint
from ..constraints.feasibility import function_needs
from ..constraints.goal import GoalConstraint, goal_vocabulary
from ..constraints.plan import PlanConstraint
from ..constraints.restated import RestatedAllocation, restated_bodies
from ..constraints.world_check import WorldCheck
from ..decoding.protocol import REFUSAL_PREFIX
from ..decoding.writer import accepts
from ..in_turn import started_together
from .asked_words import ASKED_STATES, load_state_words, placements_asked, states_asked
from .goal_prompt import GOAL_FOLDER, load_goal_examples
from .prompts import STAGES, load_examples


def check_examples(domain: Domain) -> tuple[int, list[str]]:
    """How many examples the domain's three stages have, and every problem with them and with its goal examples
    (each naming the example's file)."""
    folder = domain.prompts_dir()
    try:
        examples = load_examples(folder)
    except (SmartLLMError, KeyError, TypeError) as exc:
        return 0, [f"{folder}/examples.json: {exc}; each stage needs worked examples (see `domain new`)"]
    problems = check_goal_examples(domain)[1]
    missing = [stage for stage in STAGES if not any(stage in e.stages for e in examples)]
    if missing:
        problems.append(f"{folder}/examples.json: no example for the {', '.join(missing)} stage(s)")
    skills = domain.catalogue.skills
    world = world_of(domain)
    for ex in examples:
        where = f"{folder}/decomposition/{ex.name}.py"
        try:
            scene = world.scene(ex.floor_plan)
            team = domain.catalogue.team(ex.robots)
            plan = parse_plan(ex.decomposition, form="decomposed", skills=skills, scene_types=scene.types, name=where)
        except SmartLLMError as exc:
            problems.append(f"{where}: {exc}")
            continue
        check = WorldCheck(scene, skills, 8)
        # A decomposition example is written for its team; a coalition example's decomposition is only what
        # its coalition weighs (the infeasible one's calls a skill the team lacks).
        for_team = team if "decomposition" in ex.stages else None
        if not accepts(PlanConstraint(scene, skills, world=check, for_team=for_team), ex.decomposition):
            problems.append(f"{where}: not in the decomposition grammar for its team (a skill no robot of the team "
                            "has, a step that fails on the site, a comment too long, a bare move that ends nothing?)")
        names = [f.name for f in plan.functions]
        if ex.coalition is not None:
            needs = function_needs(plan, scene, skills.lifting)
            coalition = CoalitionConstraint(names, team, needs=[needs[n] for n in names],
                                            blocks=started_together(ex.decomposition))
            if not accepts(coalition, ex.coalition):
                problems.append(f"{folder}/coalition/{ex.name}.txt: not in the coalition grammar; each line states "
                                f"its needs as the planner does (e.g. `# SubTask 1 ({names[0]}): {coalition.heads[0]}"
                                "...`), reasons in words, and names a team that can do it")
        if ex.allocation is not None:
            where = f"{folder}/allocation/{ex.name}.py"
            restated = RestatedAllocation(scene, skills, team=team, function_names=names,
                                          bodies=restated_bodies(ex.decomposition, names),
                                          world=WorldCheck(scene, skills, len(team)))
            if not accepts(restated, ex.allocation):
                problems.append(f"{where}: not in the allocation grammar (its steps and comments must be the "
                                "decomposition's, with robots that can do them)")
                continue
            allocated = parse_plan(ex.allocation, form="allocated", skills=skills, team_size=len(team), name=where)
            scores = score_execution(world.run(allocated, ex.floor_plan, team, skills=skills),
                                     parse_goals(list(ex.goals), states=world.task_rules().goal_states), trans=ex.trans,
                                     max_trans=ex.max_trans)
            if scores.SR != 1.0:
                problems.append(f"{where}: scores SR {scores.SR}; an example must reach SR 1")
    return len(examples), problems


def check_goal_examples(domain: Domain) -> tuple[int, list[str]]:
    """The goal examples (a domain without a goal/ folder has none: the goal stage then says so), each in the
    goal grammar of its own scene."""
    folder = domain.prompts_dir() / GOAL_FOLDER
    if not folder.is_dir():
        return 0, []
    try:
        examples = load_goal_examples(domain.prompts_dir())
        words = load_state_words(domain.prompts_dir())
    except SmartLLMError as exc:
        return 0, [str(exc)]
    problems = []
    world = world_of(domain)
    for ex in examples:
        where = f"{folder}/{ex.name}.txt"
        try:
            scene = world.scene(ex.floor_plan)
        except SmartLLMError as exc:
            problems.append(f"{where}: {exc}")
            continue
        # As the stage writes it: the refusal line alone, or the conditions and the blank line that ends them.
        written = ex.statement.rstrip("\n") + ("\n" if ex.statement.startswith(REFUSAL_PREFIX) else "\n\n")
        vocabulary, owed = goal_vocabulary(scene), states_asked(ex.instruction, words.asked, words.verbs)
        withheld = set(words.only_where_asked) - set(states_asked(ex.instruction, words.only_where_asked))
        placed = placements_asked(ex.instruction, vocabulary.less(outnamed(ex.instruction, vocabulary.types)), words)
        if not accepts(GoalConstraint(vocabulary), written):
            problems.append(f"{where}: not in the goal grammar of {scene.floor_plan} (one `<Object> <state>` or "
                            "`<Object> in <Receptacle>` a line, naming the scene's objects in states the world can "
                            "give them, each once; or one `# INFEASIBLE: <why>` line)")
        elif not accepts(GoalConstraint(vocabulary, asked={s: [] for s in owed}), written):
            problems.append(f"{where}: states no thing in a state its instruction asks for in so many words "
                            f"({', '.join(owed)}: {folder}/{ASKED_STATES}); an example shows the model what to state")
        elif not accepts(GoalConstraint(vocabulary, placed=placed), written):
            problems.append(f"{where}: does not put in {', '.join(placed)} what its instruction asks into it in so "
                            f"many words ([placements] and [put] of {folder}/{ASKED_STATES})")
        elif not accepts(GoalConstraint(vocabulary, withheld=withheld), written):
            stated = parse_goal_statement(written, types=vocabulary.types).conditions
            said = sorted(withheld & {c.state for c in stated})
            problems.append(f"{where}: states {', '.join(said)}, which the goal stage offers only where "
                            f"the instruction asks for it ([only_where_asked] of {folder}/{ASKED_STATES}) and this "
                            "one does not")
    return len(examples), problems
