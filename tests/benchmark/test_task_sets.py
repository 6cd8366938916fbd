"""The household's task sets beside the benchmark, in the paper's style, with teams of few skills, in scenes no
benchmark task, no worked example and no other set uses: the held-out tasks (``heldout/tasks.jsonl``), never used to
choose anything, only to measure; and the extra development tasks (``development/tasks.jsonl``, then
``development-3/tasks.jsonl`` to ``development-13/tasks.jsonl``), each written to choose on once the set before it
was spent (the ninth to thirteenth in earlier development sets' scenes: every floor plan was in use). Here: that
they are what the docs say; the heavy suite proves every feasible one reachable and every infeasible one refused (the
planner, given the tasks' goals)."""

from __future__ import annotations

import json
from collections import Counter
from pathlib import Path

import pytest

from smartllm_local.benchmark.tasks import load_tasks
from smartllm_local.domain import load_domain
from smartllm_local.scoring import condition_holds
from smartllm_local.world.scenes import load_scene
from tests.conftest import HOUSEHOLD_SETS, benchmark_run

from .test_dataset import MINIMUM, SMARTLLM_SKILLS, needed_skills

ROOT = Path(__file__).parents[2]
SETS = {name: load_domain().folder / name / "tasks.jsonl" for name in HOUSEHOLD_SETS if name != "benchmark"}
#: Sets written once every floor plan was in use: they reuse earlier development sets' scenes.
REUSING = frozenset({"development-9", "development-10", "development-11", "development-12",
                     "development-13", "development-14", "development-15"})


@pytest.fixture(scope="module", params=sorted(SETS))
def name(request):
    return request.param


@pytest.fixture(scope="module")
def heldout(name):
    return load_tasks([SETS[name]])


def _example_floor_plans() -> set[int]:
    """Every floor plan a worked example of any stage of the household prompts is set in."""
    found = set()
    for path in load_domain().prompts_dir().rglob("examples.json"):
        found |= {e["floor_plan"] for e in json.loads(path.read_text()).get("examples", []) if "floor_plan" in e}
    return found


def test_six_feasible_tasks_a_category_and_infeasible_ones(heldout):
    counts = Counter(t.category for t in heldout if t.feasible)
    assert counts == {category: 6 for category in MINIMUM}
    assert sum(not t.feasible for t in heldout) >= 3


def test_their_scenes_are_new_to_the_benchmark_the_examples_and_each_other(name, heldout, all_tasks):
    """Scenes shared with no benchmark task, worked example or other set; a set written once every floor plan was in
    use (:data:`REUSING`) shares scenes with earlier development sets alone, never with the held-out set."""
    used, examples = {t.floor_plan for t in heldout}, _example_floor_plans()
    assert examples and not used & examples
    assert not used & {t.floor_plan for t in all_tasks}
    assert not {t.instruction.lower() for t in heldout} & {t.instruction.lower() for t in all_tasks}
    others = {other: load_tasks([path]) for other, path in SETS.items() if other != name}
    assert not {t.instruction.lower() for t in heldout} & {t.instruction.lower() for ts in others.values() for t in ts}
    apart = [other for other in others if other == "heldout" or name not in REUSING and other not in REUSING]
    assert not used & {t.floor_plan for other in apart for t in others[other]}


def test_every_team_lacks_skills_or_strength_as_the_papers_do(heldout, catalogue):
    for task in heldout:
        team = catalogue.team(task.robots)
        lacking = any(SMARTLLM_SKILLS - r.skills for r in team)  # a robot of few skills
        weak = all(r.mass_capacity < 5 for r in team if "PickupObject" in r.skills)  # the lifters are weak
        assert lacking or weak, task.id


def test_no_goal_holds_at_the_start_and_infeasible_teams_lack_what_the_goals_need(heldout, catalogue):
    for task in heldout:
        objects = load_scene(task.floor_plan)
        assert not any(condition_holds(c, objects) for goal in task.goals for c in goal.conditions()), task.id
        have = frozenset().union(*(r.skills for r in catalogue.team(task.robots)))
        assert bool(needed_skills(task) - have) == (not task.feasible), task.id


@pytest.mark.heavy
def test_the_planner_given_their_goals_reaches_every_feasible_one_and_refuses_the_rest(name, heldout, tmp_path):
    benchmark_run(tmp_path / "oracle", "--method", "goal-planner-oracle", "--tasks", str(SETS[name]))
    lines = [json.loads(line) for line in (tmp_path / "oracle" / "results.jsonl").read_text().splitlines()]
    assert len(lines) == len(heldout)
    for line in lines:
        if line["feasible"]:
            assert line["SR"] == 1.0 and line["Exe"] == 1.0, line["id"]
        else:
            assert line["refused"] and line["refused_by"] == "planner", line["id"]


def test_the_file_is_where_the_docs_say(name):
    assert str(SETS[name].relative_to(ROOT)) in (ROOT / "docs" / "benchmark.md").read_text()
