"""The benchmark summary table: what counts as 0 and what is left out of a mean."""

from __future__ import annotations

from smartllm_local.benchmark.results import summary_table, variability_table
from smartllm_local.benchmark.run import TaskOutcome
from smartllm_local.benchmark.tasks import Task
from smartllm_local.scoring import Scores


def _task(task_id: str, category: str = "uncategorized", feasible: bool = True) -> Task:
    return Task(id=task_id, category=category, floor_plan="FloorPlan1", instruction="x", robots=(1,), goals=(),
                trans=None, max_trans=None, feasible=feasible)


def _row(table: str, name: str) -> list[str]:
    return next(line.split() for line in table.splitlines() if line.startswith(name))


def test_unknown_metrics_are_left_out_of_the_means_and_failures_count_as_0():
    judged = Scores(SR=1.0, TCR=1.0, GCR=1.0, RU=1.0, Exe=1.0, transitions=0)
    no_goals = Scores(SR=None, TCR=None, GCR=None, RU=None, Exe=0.5, transitions=0)
    no_trans = Scores(SR=None, TCR=0.0, GCR=0.5, RU=None, Exe=1.0, transitions=1)
    outcomes = [
        TaskOutcome(_task("FloorPlan1-1"), scores=judged),
        TaskOutcome(_task("FloorPlan1-2"), scores=no_goals),
        TaskOutcome(_task("FloorPlan1-3"), scores=no_trans),
        TaskOutcome(_task("FloorPlan1-4"), error="allocation: the model failed"),
    ]
    row = _row(summary_table([o.as_json() for o in outcomes]), "uncategorized")
    # category tasks errors SR TCR GCR RU Exe Speed refused (no run here has a reference's Speed)
    assert row == ["uncategorized", "4", "1", "0.50", "0.33", "0.50", "0.50", "0.62", "0.00", "0"]


def test_a_metric_nothing_judges_is_na():
    outcomes = [TaskOutcome(_task("FloorPlan1-1"), scores=Scores(None, None, None, None, 1.0, 0))]
    assert _row(summary_table([o.as_json() for o in outcomes]), "uncategorized")[3:7] == ["n/a"] * 4


def test_speed_shows_what_ru_cannot():
    """One robot doing everything scores RU 1; Speed compares its ticks with the reference plan's."""
    slow = Scores(SR=1.0, TCR=1.0, GCR=1.0, RU=1.0, Exe=1.0, transitions=0, ticks=40)
    assert slow.with_speed(10).Speed == 0.25
    assert Scores(SR=1.0, TCR=1.0, GCR=1.0, RU=1.0, Exe=1.0, transitions=0, ticks=8).with_speed(10).Speed == 1.0
    unmet = Scores(SR=0.0, TCR=0.0, GCR=0.5, RU=1.0, Exe=1.0, transitions=0, ticks=2)
    assert unmet.with_speed(10).Speed == 0.0  # fast because it did little
    assert slow.with_speed(None).Speed is None
    assert Scores(None, None, None, None, 1.0, 0, ticks=3).with_speed(10).Speed is None


def test_a_reference_plan_runs_at_speed_1_and_a_padded_one_slower(tmp_path):
    """The real Controller: the reference plan's ticks are the yardstick; the same plan with its
    sub-tasks run one after another (no parallelism) is slower."""
    from smartllm_local.benchmark.reference_plans import default_plans_dir, reference_ticks
    from smartllm_local.benchmark.run import execute_and_score
    from smartllm_local.benchmark.tasks import load_tasks
    from smartllm_local.domain import load_domain
    from smartllm_local.plan_language import parse_plan
    from smartllm_local.planner.result import PlanResult
    from smartllm_local.world.controller import open_controller

    catalogue = load_domain().catalogue
    task = next(t for t in load_tasks() if t.id == "kitchen-01")
    source = (default_plans_dir() / f"{task.id}.py").read_text()
    controller = open_controller(task.floor_plan, len(task.robots))
    try:
        ticks = reference_ticks(task, catalogue, controller)
        assert ticks and ticks > 0
        result = PlanResult(task.instruction, task.floor_plan, list(task.robots), allocated=source,
                            plan=parse_plan(source, form="allocated"))
        scores = execute_and_score(result, task.goals, catalogue, trans=task.trans, max_trans=task.max_trans,
                                   controller=controller).with_speed(ticks)
        assert scores.ticks == ticks and scores.Speed == 1.0
        slower = source + "".join(f"{n}([robots[0]])\n" for n in [parse_plan(source, form="allocated")
                                                                      .functions[0].name])
        result = PlanResult(task.instruction, task.floor_plan, list(task.robots), allocated=slower,
                            plan=parse_plan(slower, form="allocated"))
        again = execute_and_score(result, task.goals, catalogue, controller=controller).with_speed(ticks)
        assert again.ticks > ticks and 0 < again.Speed < 1
    finally:
        controller.stop()


def test_variability_is_the_spread_of_each_runs_category_mean():
    def run(srs, refused):
        lines = [{"id": f"t{k}", "category": "elemental", "feasible": True, "refused": False, "SR": v, "TCR": v,
                  "GCR": v, "RU": 1.0, "Exe": 1.0, "Speed": None} for k, v in enumerate(srs)]
        return lines + [{"id": "i", "category": "elemental", "feasible": False, "refused": refused}]

    table = variability_table([run([1.0, 0.0], True), run([1.0, 1.0], False), run([0.0, 0.0], True)])
    elemental = _row(table, "elemental")
    # means per run 0.5, 1.0, 0.0: mean 0.50, sample standard deviation 0.50
    assert elemental[:4] == ["elemental", "2", "3", "0.50±0.50"] and elemental[6:8] == ["1.00±0.00", "1.00±0.00"]
    assert elemental[8] == "n/a"
    assert _row(table, "infeasible")[-1] == "0.67±0.58"
