"""Prompt assembly, ablations, the context budget and the stage plumbing (with a fake model)."""

from __future__ import annotations

import re

import pytest

from smartllm_local.domain import load_domain
from smartllm_local.errors import UserError
from smartllm_local.planner.pipeline import OWN_PART, Planner, PlannerConfig, write_artifacts
from smartllm_local.planner.prompting.prompts import (
    STAGES,
    PromptOptions,
    coalition_decisions,
    examples_for,
    load_examples,
    strip_comments,
    strip_summary,
)
from smartllm_local.planner.result import PlanResult, StageRecord
from smartllm_local.worlds import scene_objects
from tests.planner.fakes import FakeBackend

INSTRUCTION = "Put the apple in the fridge and turn off the light."


@pytest.fixture
def catalogue():
    return load_domain().catalogue


def plan_with(backend, catalogue, **options):
    planner = Planner(backend, catalogue, PlannerConfig(prompts=PromptOptions(**options)))
    return planner.plan(INSTRUCTION, 6, [29, 24, 25])


def test_the_three_prompts_have_their_parts(catalogue):
    result = plan_with(FakeBackend(), catalogue)
    decomposition, coalition, allocation = (result.stage(name).prompt for name in STAGES)
    assert decomposition.startswith("import threading\nimport time\n")
    own_task = decomposition.split("# Your task")[1]
    assert f"\nfrom skills import {', '.join(catalogue.skills)}\n# Task Description: {INSTRUCTION}\n" in own_task, \
        "robot 29 has every skill"
    examples = load_examples()
    in_stage = {stage: len(examples_for(stage, examples, PromptOptions())) for stage in STAGES}
    assert len(re.findall(r"^# Example \d$", decomposition, re.M)) == in_stage["decomposition"] == 5
    assert "{'name': 'Apple', 'mass': 0.2}" in decomposition and "{'name': 'Fridge'" in decomposition
    assert decomposition.endswith(f"# Task Description: {INSTRUCTION}\n")
    assert len(re.findall(r"^# Example \d$", coalition, re.M)) == in_stage["coalition"]
    own = coalition.split("# Your plan")[1]
    called = set(re.findall(r"^    (\w+)\(", result.stage("decomposition").output, re.M))
    for i, robot in enumerate(catalogue.robots[r] for r in (29, 24, 25)):
        skills = sorted(robot.skills & called)
        assert f"'name': 'robots[{i}]', 'id': {robot.id}, 'skills': {skills!r}, 'mass_capacity': 100}}" in own, \
            "each robot with the skills the plan calls"
    assert any(catalogue.robots[r].skills - called for r in (29, 24, 25)), "some robot has skills left out"
    assert "'id': 24, 'skills': ['GoToObject', 'SwitchOn']" in coalition, "an example's robots, by its own plan"
    assert coalition.endswith("# Coalition:\n")
    assert coalition.startswith("from skills import GoToObject, OpenObject, CloseObject")
    examples_part = coalition.split("# Your plan")[0]
    assert len(re.findall(r"^# Allocated plan:\ndef subtask1_", examples_part, re.M)) == in_stage["allocation"], \
        "each feasible example's coalition is followed by its allocated plan"
    assert "# INFEASIBLE: SubTask 1 (subtask1_coffee_machine_on): no robot of the team has SwitchOn;" \
        in examples_part
    assert strip_comments(result.stage("decomposition").output) in coalition and "    # " not in own
    assert allocation == coalition + result.stage("coalition").output + "# Allocated plan:\n", \
        "the allocation goes on in the coalition's context"
    assert result.stage("allocation").shared_tokens == result.stage("coalition").shared_tokens > 0


def test_a_context_too_short_for_the_shared_prompt_gets_the_papers_two_prompts(catalogue):
    """Where the shared prompt's examples, both budgets and a task's own part do not fit (a 4,096-token
    Llama-2), the coalition has a prompt without allocations and the allocation one of its own, which
    shows each example's coalition cut to its decisions, then the task's."""
    shared = plan_with(FakeBackend(), catalogue).stage("coalition").shared_tokens
    need = shared + 896 + 1280 + OWN_PART
    two = plan_with(FakeBackend(n_ctx=need - 1), catalogue)
    coalition, allocation = two.stage("coalition"), two.stage("allocation")
    assert "# Allocated plan:" not in coalition.prompt and coalition.prompt.endswith("# Coalition:\n")
    examples = load_examples()
    assert coalition.shared_tokens < shared and len(re.findall(r"^# Example \d$", coalition.prompt, re.M)) \
        == sum("coalition" in e.stages for e in examples)
    assert len(re.findall(r"^# Example \d$", allocation.prompt, re.M)) \
        == sum("allocation" in e.stages for e in examples)
    assert allocation.prompt.endswith(f"# Coalition:\n{coalition_decisions(coalition.output)}# Allocated plan:\n")
    assert "# Coalition:\n# SubTask 1 (subtask1_slice_bread): robots[0]\n# SubTask 2 (subtask2_toast_slice): " \
        "robots[1] and robots[2]\n# Allocated plan:" in allocation.prompt, "the examples' coalitions without reasoning"
    # At exactly that context the two share a prompt (it may keep fewer examples where this task's own part,
    # the fake model's random plan, is longer than OWN_PART).
    one = plan_with(FakeBackend(n_ctx=need), catalogue)
    coalition, allocation = one.stage("coalition"), one.stage("allocation")
    assert allocation.prompt.startswith(coalition.prompt) and "# Allocated plan:" in coalition.prompt


def test_ablations_change_the_prompts(catalogue):
    full = plan_with(FakeBackend(), catalogue)
    bare = plan_with(FakeBackend(), catalogue, comments=False, summary=False, coalition=False)
    assert list(bare.stages) == ["decomposition", "allocation"]
    examples_part = bare.stage("decomposition").prompt.split("# Your task")[0]
    full_prompt = full.stage("decomposition").prompt
    assert "# SubTask 1:" not in examples_part and "# SubTask 1:" in full_prompt
    assert not re.search(r"^    #", examples_part, re.M) and re.search(r"^    #", full_prompt, re.M)
    allocation = bare.stage("allocation").prompt
    assert "# Coalition:" not in allocation
    assert "robots = [" in allocation
    assert len(re.findall(r"^# Example \d$", allocation, re.M)) == sum(
        "allocation" in e.stages for e in load_examples()), "the allocation's own examples"
    assert allocation.endswith("# Allocated plan:\n")


def test_strip_helpers():
    code = "# SubTask 1: x (skills: GoToObject)\n# order\n\ndef subtask1_x():\n    # go\n    GoToObject('Apple')\n"
    assert strip_summary(code) == "def subtask1_x():\n    # go\n    GoToObject('Apple')\n"
    assert strip_comments(code) == ("# SubTask 1: x (skills: GoToObject)\n# order\n\n"
                                    "def subtask1_x():\n    GoToObject('Apple')\n")


def test_examples_are_dropped_from_the_last_when_the_context_is_short(catalogue):
    """So the examples kept are the first of the file, and their text begins every prompt that keeps as many."""
    full = plan_with(FakeBackend(), catalogue)
    squeezed = plan_with(FakeBackend(n_ctx=full.stage("decomposition").prompt_tokens + 1024 - 300), catalogue)
    first = squeezed.stage("decomposition")
    assert first.dropped and first.examples + first.dropped == full.stage("decomposition").examples
    assert "dropped example(s)" in squeezed.notices[0]
    with pytest.raises(UserError, match="raise --n-ctx"):
        plan_with(FakeBackend(n_ctx=1500), catalogue)


def test_output_budgets_follow_the_task(catalogue):
    """A restated allocation's budget is its longest output, to the character; a freely rewritten
    one's is estimated from the decomposition."""
    budgets = {"decomposition": 1024, "coalition": 512, "allocation": 9000}
    free = Planner(FakeBackend(n_ctx=16384), catalogue, PlannerConfig(budgets=budgets, restate=False))
    planned = free.plan(INSTRUCTION, 6, [29, 24, 25])
    decomposition, allocation = planned.stage("decomposition"), planned.stage("allocation")
    written = decomposition.generated_tokens + decomposition.forced_tokens
    functions = len(decomposition.plan.functions)
    assert written and functions
    assert allocation.output_budget == 2 * written + 64 * functions + 128 < 9000
    assert decomposition.output_budget == 1024
    assert allocation.generated_tokens + allocation.forced_tokens <= allocation.output_budget

    restated = Planner(FakeBackend(n_ctx=16384), catalogue, PlannerConfig(budgets=budgets))
    planned = restated.plan(INSTRUCTION, 6, [29, 24, 25])
    decomposition, allocation = planned.stage("decomposition"), planned.stage("allocation")
    assert len(allocation.output) <= allocation.output_budget < len(allocation.output) + 64 * functions + 400


def test_a_decomposition_for_goals_the_team_can_meet_offers_no_refusal(catalogue):
    """Robots 24 and 25 lack skills the scene has, but not one the stated goal needs (the goal check found the
    team can meet it): a model that would refuse writes a plan (the 1.5B refused for PutObject to switch a lamp off
    and open the blinds, dev15-s5). Without stated goals it may still refuse."""
    goal = StageRecord("goal", output="LightSwitch off\n")
    result = PlanResult(INSTRUCTION, "FloorPlan6", [24, 25], stages={"goal": goal})
    record = Planner(FakeBackend(refuse=True), catalogue).decompose(result)
    assert not record.output.startswith("# INFEASIBLE") and record.plan is not None and not record.plan.is_refusal
    alone = Planner(FakeBackend(refuse=True), catalogue).decompose(PlanResult(INSTRUCTION, "FloorPlan6", [24, 25]))
    assert alone.output.startswith("# INFEASIBLE: no robot of the team has ")


def test_a_refusal_stops_the_pipeline_and_becomes_the_plan(catalogue, tmp_path):
    """Robots 24 and 25 switch, and carry, and do nothing else: a decomposition for them may refuse, and its
    reason names skills neither has."""
    result = Planner(FakeBackend(refuse=True), catalogue).plan(INSTRUCTION, 6, [24, 25])
    assert result.refusal and list(result.stages) == ["decomposition"]
    assert result.refused_by == "model"
    lacking = result.refusal.removeprefix("no robot of the team has ").split(", ")
    assert lacking and not set(lacking) & (catalogue.robots[24].skills | catalogue.robots[25].skills)
    assert result.allocated.startswith("# INFEASIBLE: ") and result.plan.is_refusal
    write_artifacts(result, tmp_path)
    assert (tmp_path / "allocated.py").read_text().startswith("# INFEASIBLE")


def test_artifacts_hold_every_stage(catalogue, tmp_path):
    result = plan_with(FakeBackend(), catalogue)
    write_artifacts(result, tmp_path, {"model": "fake"})
    for stage in ("decomposition", "coalition", "allocation"):
        for name in ("prompt.txt", "grammar.gbnf", "raw_output.txt", "timings.json"):
            assert (tmp_path / stage / name).stat().st_size > 0, (stage, name)
    assert (tmp_path / "decomposed.py").read_text() == result.stage("decomposition").output
    assert (tmp_path / "coalition.txt").read_text() == result.stage("coalition").output
    assert (tmp_path / "allocated.py").read_text() == result.allocated
    assert "root ::=" in (tmp_path / "allocation" / "grammar.gbnf").read_text()


def _record(stage, output, grammars=("root ::= x",)):
    from smartllm_local.planner.result import StageRecord

    return StageRecord(stage=stage, prompt=f"{stage} prompt", grammars=list(grammars), raw=output, output=output)


def _stages(*records):
    """A result's stages: the records by name."""
    return {record.stage: record for record in records}


def test_artifacts_of_stages_not_run_again_are_removed(tmp_path):
    from smartllm_local.planner.result import PlanResult

    first = PlanResult("Put the apple in the fridge", "FloorPlan6", [1, 2], stages=_stages(
        _record("decomposition", "def f():\n    pass\n"), _record("coalition", "# SubTask 1 (f): robots[0]\n"),
        _record("allocation", "f(robots[0])\n")), allocated="f(robots[0])\n")
    write_artifacts(first, tmp_path)
    assert (tmp_path / "coalition.txt").is_file() and (tmp_path / "coalition" / "prompt.txt").is_file()
    (tmp_path / "notes.txt").write_text("mine")  # the user's own files are never touched
    (tmp_path / "coalition" / "mine.txt").write_text("mine")
    (tmp_path / "allocation" / "mine").mkdir()

    # the same folder again, with --no-coalition and no grammar for the decomposition
    second = PlanResult("Put the apple in the fridge", "FloorPlan6", [1, 2], stages=_stages(
        _record("decomposition", "def g():\n    pass\n", grammars=()), _record("allocation", "g(robots[1])\n")),
        allocated="g(robots[1])\n")
    write_artifacts(second, tmp_path)
    assert not (tmp_path / "coalition.txt").exists()
    assert sorted(p.name for p in (tmp_path / "coalition").iterdir()) == ["mine.txt"]
    assert not (tmp_path / "decomposition" / "grammar.gbnf").exists()
    assert (tmp_path / "decomposed.py").read_text() == "def g():\n    pass\n"
    assert (tmp_path / "allocated.py").read_text() == "g(robots[1])\n"
    assert (tmp_path / "allocation" / "grammar.gbnf").is_file() and (tmp_path / "allocation" / "mine").is_dir()
    assert (tmp_path / "notes.txt").read_text() == "mine"

    # a refusal at the decomposition: only its stage, the refusal as the plan, and result.json
    (tmp_path / "coalition" / "mine.txt").unlink()
    refusal = PlanResult("Lift the fridge", "FloorPlan6", [1],
                         stages=_stages(_record("decomposition", "# INFEASIBLE: x\n")),
                         allocated="# INFEASIBLE: x\n", refusal="x")
    write_artifacts(refusal, tmp_path)
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        "allocated.py", "allocation", "decomposed.py", "decomposition", "notes.txt", "result.json"]
    assert [p.name for p in (tmp_path / "allocation").iterdir()] == ["mine"]
    assert (tmp_path / "allocated.py").read_text() == "# INFEASIBLE: x\n"

    # no plan at all (a failed decomposition): no allocated.py left from before
    failed = PlanResult("x", "FloorPlan6", [1], stages=_stages(_record("decomposition", "")),
                        error="decomposition: bad")
    write_artifacts(failed, tmp_path)
    assert not (tmp_path / "allocated.py").exists() and (tmp_path / "decomposed.py").read_text() == ""


def test_each_decomposition_imports_the_skills_of_its_own_team(catalogue):
    """The examples and the task each import the skills their robots have, not all skills, after the scene's
    objects (so the examples and each floor plan's objects stay prefixes that tasks share)."""
    prompt = Planner(FakeBackend(), catalogue).decomposition_prompt(INSTRUCTION, scene_objects(6),
                                                                    catalogue.team([24, 25])).text
    imports = re.findall(r"^objects = .*\nfrom skills import (.*)\n# Task Description: ", prompt, re.M)
    examples = examples_for("decomposition", load_examples(), PromptOptions())
    teams = [[catalogue.robots[i] for i in ex.robots] for ex in examples] + [catalogue.team([24, 25])]
    assert len(imports) == len(teams)
    for names, team in zip(imports, teams):
        assert names.split(", ") == [s for s in catalogue.skills if any(s in r.skills for r in team)]
    assert imports[-1] == "GoToObject, SwitchOn, SwitchOff, PickupObject, PutObject"
    assert "OpenObject" not in prompt.split("# Your task")[1]
