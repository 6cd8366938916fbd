"""Plans for the team that was given: a decomposition offers only the calls its team can make (robots
lifting together included), and a refusal gives the catalogue's reason, never one the model made up."""

from __future__ import annotations

import random
import re

import pytest

from smartllm_local.domain import load_domain
from smartllm_local.plan_language import parse_plan
from smartllm_local.planner.constraints.coalition import CoalitionConstraint
from smartllm_local.planner.constraints.feasibility import Need, feasible_teams, function_needs
from smartllm_local.planner.constraints.format import MAX_SUBTASKS
from smartllm_local.planner.constraints.plan import PlanConstraint
from smartllm_local.planner.constraints.world_check import WorldCheck
from smartllm_local.planner.decoding.writer import accepts, run_constraint, run_tokens
from smartllm_local.planner.pipeline import Planner
from smartllm_local.planner.result import PlanResult, StageRecord
from smartllm_local.robots import Robot, team_skills
from smartllm_local.worlds import scene_objects
from tests.planner.fakes import FakeBackend
from tests.planner.writers import WRITERS, TokenAdversary, writer

CATALOGUE = load_domain().catalogue
SKILLS = CATALOGUE.skills
CALL = re.compile(r"^    (\w+)\(", re.M)
REASON = re.compile(r"^# INFEASIBLE: no robot of the team has ((?:\w+, )*\w+)\n$")


def decomposer(floor_plan: int, ids, **kwargs) -> PlanConstraint:
    scene = scene_objects(floor_plan)
    team = CATALOGUE.team(ids) if ids is not None else None
    return PlanConstraint(scene, SKILLS, for_team=team, world=WorldCheck(scene, SKILLS, MAX_SUBTASKS),
                          **kwargs)


def _plans(ids, kind: str, count: int) -> list[str]:
    """Decompositions of FloorPlan1 (a fridge, a microwave, drawers and cabinets to open) by an adversarial
    writer that never refuses, at budgets from small to large; every one parses."""
    rng = random.Random(f"team-{kind}")
    plans = []
    for k in range(count):
        budget = (400, 900, 1600)[k % 3]
        if k % 2:
            text = run_tokens(decomposer(1, ids), TokenAdversary(kind, rng, refusals=0.0), budget)
        else:
            text = run_constraint(decomposer(1, ids), writer(kind, rng, refusals=0.0), len, budget)
        parse_plan(text, form="decomposed", skills=SKILLS, scene_types=scene_objects(1).types)
        plans.append(text)
    return plans


@pytest.mark.parametrize("kind", WRITERS)
def test_a_team_without_open_never_gets_an_open_step(kind):
    """Robots 25 and 13 cannot open or close (25 carries; 13 carries and switches): no writer gets an OpenObject
    or CloseObject step, or any skill neither has, out of their grammar, while for robot 1, which has them, the
    random writer does."""
    team = CATALOGUE.team([25, 13])
    assert not {"OpenObject", "CloseObject"} & team_skills(team)
    called = set()
    for text in _plans([25, 13], kind, 12):
        called |= set(CALL.findall(text))
        assert not re.search(r"\b(OpenObject|CloseObject|SliceObject)\b", text), text
    assert called <= team_skills(team)
    if kind == "random":
        assert any("OpenObject(" in text for text in _plans([1], kind, 12))


FRIDGE = """\
# SubTask 1: put the apple in the fridge (skills: GoToObject, OpenObject, CloseObject, PickupObject, PutObject)
# One sub-task.

def subtask1_apple_to_fridge():
    GoToObject('Apple')
    PickupObject('Apple')
    GoToObject('Fridge')
    OpenObject('Fridge')
    PutObject('Apple', 'Fridge')
    CloseObject('Fridge')

subtask1_apple_to_fridge()
"""


def test_a_plan_calling_a_skill_the_team_lacks_is_not_in_its_grammar():
    assert accepts(decomposer(1, [1]), FRIDGE) and accepts(decomposer(1, [25, 23]), FRIDGE)  # 23 opens, 25 carries
    assert not accepts(decomposer(1, [25, 13]), FRIDGE)
    summary_only = FRIDGE.replace("OpenObject, CloseObject, ", "")
    assert not accepts(decomposer(1, [25, 13]), summary_only), "the open and close steps"
    assert not accepts(decomposer(1, [25, 13]), FRIDGE.replace("    OpenObject('Fridge')\n", "")
                       .replace("    CloseObject('Fridge')\n", "")), "the summary's skills"


LAPTOP = """\
# SubTask 1: move the laptop onto the sofa (skills: GoToObject, PickupObject, PutObject)
# One sub-task.

def subtask1_laptop_to_sofa():
    GoToObject('Laptop')
    PickupObject('Laptop')
    GoToObject('Sofa')
    PutObject('Laptop', 'Sofa')

subtask1_laptop_to_sofa()
"""


def test_a_step_only_robots_lifting_together_can_do_stays_possible():
    """The 2.3 kg laptop: robot 5 lifts 1 kg and robot 6 2.1 kg, so neither alone but both together. Their
    decomposition may lift it, and its coalition is the two of them; robot 5's alone may not, and may refuse
    for that reason."""
    assert accepts(decomposer(203, [5, 6]), LAPTOP)
    plan = parse_plan(LAPTOP, form="decomposed")
    need = function_needs(plan, scene_objects(203))["subtask1_laptop_to_sofa"]
    assert need.mass == pytest.approx(2.3) and feasible_teams(CATALOGUE.team([5, 6]), need) == [(0, 1)]
    assert not accepts(decomposer(203, [5]), LAPTOP)
    assert accepts(decomposer(203, [5]), LAPTOP.replace("'Laptop'", "'Book'").replace("the laptop", "the book"))
    assert accepts(decomposer(203, [5]),
                   "# INFEASIBLE: the Laptop weighs 2.3 kg, more than the team lifts together (1 kg)\n")
    assert not accepts(decomposer(203, [5, 6]),
                       "# INFEASIBLE: the Laptop weighs 2.3 kg, more than the team lifts together (3.1 kg)\n")


def test_a_decomposition_refuses_only_for_what_the_team_lacks():
    """kitchen-inf-02's team (robots 25 and 23: carrying, opening, closing) cannot slice. Its decomposition may
    refuse saying so, and every refusal its grammar admits names only skills neither robot has; a reason that
    is not so, or one in the model's own words, is not admitted."""
    team = CATALOGUE.team([25, 23])
    assert accepts(decomposer(6, [25, 23]), "# INFEASIBLE: no robot of the team has SliceObject\n")
    assert accepts(decomposer(6, [25, 23]), "# INFEASIBLE: no robot of the team has SliceObject, SwitchOn\n")
    for false in ("no robot of the team has PickupObject", "no robot of the team has SliceObject, PutObject",
                  "the robots cannot cut potatoes", "nobody has a knife"):
        assert not accepts(decomposer(6, [25, 23]), f"# INFEASIBLE: {false}\n"), false
    rng = random.Random(0)
    for _ in range(200):
        refusal = decomposer(6, [25, 23]).next(2000).options["refusal"].sample(rng)
        named = REASON.match(refusal)
        assert named and not set(named.group(1).split(", ")) & team_skills(team), refusal


def test_a_team_that_can_make_every_call_cannot_refuse():
    """Robot 29 has every skill and lifts 100 kg: the catalogue gives no reason to refuse, so there is none to
    write (without a team the model may still give its own)."""
    assert "refusal" not in decomposer(6, [29]).next(2000).options
    assert "refusal" in decomposer(6, None).next(2000).options


def test_a_team_that_can_make_no_call_here_can_only_refuse():
    walker = Robot(id=99, name="walker", skills=frozenset({"GoToObject"}), mass_capacity=10.0)
    scene = scene_objects(6)
    constraint = PlanConstraint(scene, SKILLS, for_team=[walker])
    assert constraint.must_refuse and constraint.minimum_budget() < 300
    text = run_constraint(constraint, writer("random", random.Random(0)), len, constraint.minimum_budget())
    named = REASON.match(text)
    assert named and set(named.group(1).split(", ")) <= set(SKILLS) - {"GoToObject"}, text
    assert constraint.refusal == text[len("# INFEASIBLE: "):].strip()


@pytest.mark.parametrize("kind", WRITERS)
def test_a_coalition_refusal_gives_the_catalogues_reason(kind):
    """Where some sub-task has no team, every writer writes the same refusal: which sub-task, and what the whole
    team lacks (a skill no robot has, or more mass than all lift together), and nothing of its own."""
    switch = Need(frozenset({"GoToObject", "SwitchOn"}), 0.0)
    carry = Need(frozenset({"GoToObject", "PickupObject", "PutObject"}), 0.2)
    rng = random.Random(kind)
    constraint = CoalitionConstraint(["f", "g"], CATALOGUE.team([25, 23]), needs=[carry, switch])
    assert run_constraint(constraint, writer(kind, rng), len, 2000) == \
        "# INFEASIBLE: SubTask 2 (g): no robot of the team has SwitchOn\n"
    assert constraint.refusal == "SubTask 2 (g): no robot of the team has SwitchOn"
    heavy = Need(frozenset({"GoToObject", "PickupObject", "SliceObject"}), 500.0)
    constraint = CoalitionConstraint(["f"], CATALOGUE.team([25, 23]), needs=[heavy])  # 100 + 100 kg
    assert run_constraint(constraint, writer(kind, rng), len, 2000) == \
        "# INFEASIBLE: SubTask 1 (f): no robot of the team has SliceObject and what it picks up weighs 500 kg, " \
        "more than the team lifts together (200 kg)\n"
    heavy = Need(frozenset({"GoToObject", "PickupObject", "SliceObject"}), 5.0)
    constraint = CoalitionConstraint(["f"], CATALOGUE.team([7, 8]), needs=[heavy])  # 0.08 + 0.4 kg
    assert run_constraint(constraint, writer(kind, rng), len, 2000) == \
        "# INFEASIBLE: SubTask 1 (f): what it picks up weighs 5 kg, more than the team lifts together (0.48 kg)\n"


def test_the_planner_records_the_catalogues_reason_for_a_coalition_refusal():
    """A decomposition written without the team's grammar (here, by hand) that slices for a team that cannot:
    the recorded refusal names the sub-task and SliceObject, the grammar refused, and the model wrote none of
    it (its writer offers nothing but that line)."""
    task_robots = [25, 23]
    decomposed = ("# SubTask 1: slice the potato (skills: GoToObject, PickupObject, SliceObject, PutObject)\n"
                  "# Alone.\n\ndef subtask1_slice():\n    GoToObject('Knife')\n    PickupObject('Knife')\n"
                  "    GoToObject('Potato')\n    SliceObject('Potato')\n    GoToObject('CounterTop')\n"
                  "    PutObject('Knife', 'CounterTop')\n\nsubtask1_slice()\n")
    plan = parse_plan(decomposed, form="decomposed")
    result = PlanResult("Cut the potato into slices.", "FloorPlan6", task_robots,
                        stages={"decomposition": StageRecord("decomposition", output=decomposed, plan=plan)})
    Planner(FakeBackend(refuse=True), CATALOGUE).form_coalition(result)
    assert result.refusal == "SubTask 1 (subtask1_slice): no robot of the team has SliceObject"
    assert result.refused_by == "grammar"
