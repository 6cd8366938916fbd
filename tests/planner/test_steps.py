"""The one loop that takes a task from stage to stage (planner/steps.py), and the planner's own list of steps."""

from __future__ import annotations

import pytest

from smartllm_local.domain import load_domain
from smartllm_local.planner.pipeline import Planner, PlannerConfig
from smartllm_local.planner.prompting.prompts import PromptOptions
from smartllm_local.planner.result import PlanResult, StageRecord
from smartllm_local.planner.steps import Step, run_steps

from .fakes import FakeBackend


def _result() -> PlanResult:
    return PlanResult("Put the apple in the fridge", "FloorPlan6", [1])


def _writes(ran: list[str], name: str, **fields):
    """A step that notes it ran and adds its record (with ``fields``: a refusal, an error)."""
    def run(result: PlanResult) -> None:
        ran.append(name)
        record = StageRecord(name, output=f"{name}\n", **fields)
        result.add(record)
        result.refusal = result.refusal or record.refusal
        result.error = result.error or record.error
    return run


def test_steps_run_in_order_and_each_record_is_handed_on():
    ran: list[str] = []
    seen: list[str] = []
    result = _result()
    run_steps([Step(n, _writes(ran, n)) for n in ("goal", "decomposition", "allocation")], result,
              starting=lambda step: seen.append(f"start {step.name}"),
              finished=lambda record: seen.append(f"done {record.stage}"))
    assert ran == list(result.stages) == ["goal", "decomposition", "allocation"]
    assert seen == ["start goal", "done goal", "start decomposition", "done decomposition", "start allocation",
                    "done allocation"]
    assert result.stage("decomposition").output == "decomposition\n"


@pytest.mark.parametrize("fields", [{"refusal": "no robot can slice"}, {"error": "not a valid plan"}])
def test_a_refusal_or_an_error_stops_the_task_there(fields):
    ran: list[str] = []
    result = _result()
    run_steps([Step("decomposition", _writes(ran, "decomposition", **fields)), Step("allocation", _writes(ran, "x"))],
              result)
    assert ran == ["decomposition"] and not result.goes_on


def test_a_stage_the_result_holds_already_is_passed_over():
    """As a resumed run finds it: the saved stage is not run again, the next one is."""
    ran: list[str] = []
    result = _result()
    result.add(StageRecord("decomposition", output="saved\n"))
    run_steps([Step("decomposition", _writes(ran, "decomposition")), Step("allocation", _writes(ran, "allocation"))],
              result)
    assert ran == ["allocation"] and result.stage("decomposition").output == "saved\n"


def test_a_failing_step_stops_the_task_and_its_exception_goes_to_failed_or_up():
    def broken(result: PlanResult) -> None:
        raise RuntimeError("llama_decode returned -3")

    ran: list[str] = []
    failures: list[tuple[str, str]] = []
    steps = [Step("decomposition", broken), Step("allocation", _writes(ran, "allocation"))]
    run_steps(steps, _result(), failed=lambda step, exc: failures.append((step.name, str(exc))))
    assert failures == [("decomposition", "llama_decode returned -3")] and ran == []
    with pytest.raises(RuntimeError, match="llama_decode"):
        run_steps(steps, _result())


def test_a_stage_runs_once_for_a_task():
    result = _result()
    result.add(StageRecord("goal"))
    with pytest.raises(ValueError, match="'goal' has already run"):
        result.add(StageRecord("goal"))
    with pytest.raises(KeyError, match="'coalition' has not run"):
        result.stage("coalition")


@pytest.mark.parametrize(("config", "names", "follows"), [
    (PlannerConfig(), ["decomposition", "coalition", "allocation"], True),
    (PlannerConfig(prompts=PromptOptions(coalition=False)), ["decomposition", "allocation"], False),
    (PlannerConfig(goal_check=True), ["goal", "decomposition", "coalition", "allocation"], True),
    (PlannerConfig(goal_check=True, grammar=False), ["decomposition", "coalition", "allocation"], True),
])
def test_the_planners_steps_follow_its_configuration(config, names, follows):
    """SMART-LLM's stages, said once: the goal stage only with the goal check (and the grammar), the allocation
    going on in the coalition's context where there is one."""
    steps = Planner(FakeBackend(), load_domain().catalogue, config).steps()
    assert [s.name for s in steps] == names
    assert steps[-1].follows is follows and not any(s.follows for s in steps[:-1])


def test_plan_runs_the_planners_steps():
    """The plan command's way through the stages is the steps' (a step swapped in is the one that runs)."""
    planner = Planner(FakeBackend(), load_domain().catalogue)
    ran: list[str] = []
    planner.steps = lambda: [Step("decomposition", _writes(ran, "decomposition", refusal="none of it"))]
    result = planner.plan("Put the apple in the fridge", 6, [1])
    assert ran == ["decomposition"] and result.allocated == "# INFEASIBLE: none of it\n"
