"""Tasks planned several at once (``benchmark run --parallel K``): the scheduler's order and its ending, the
option's refusals, and SmolLM2's greedy run with K=3 lanes against one task at a time."""

from __future__ import annotations

import json
import subprocess
import sys
import threading
from pathlib import Path

import pytest

from smartllm_local.benchmark.parallel import plan_and_execute
from smartllm_local.benchmark.run import run_benchmark
from smartllm_local.benchmark.run_store import RunStore
from smartllm_local.benchmark.tasks import find_task, load_tasks
from smartllm_local.domain import load_domain
from smartllm_local.planner.result import StageRecord
from tests.benchmark.test_resume import _Recorded
from tests.cli.test_cli_errors import cli, one_line_error

TIMEOUT = 60  # seconds a scheduler test may take before it is called hung


def schedule(todo, workers, plan, goes_on=lambda item: True, execute=None, interrupt=lambda: None):
    """plan_and_execute in a thread of its own, so that a hang fails the test; what it did or raised."""
    done: dict = {"executed": [], "raised": None}

    def run() -> None:
        try:
            plan_and_execute(list(range(len(todo))), todo, workers, plan, goes_on,
                             execute or (lambda k, item: done["executed"].append(item)), interrupt)
        except BaseException as exc:  # noqa: BLE001 - handed to the test
            done["raised"] = exc

    thread = threading.Thread(target=run, daemon=True)
    thread.start()
    thread.join(TIMEOUT)
    assert not thread.is_alive(), "the scheduler hung"
    return done


def test_one_worker_goes_stage_by_stage_and_executes_in_task_order():
    planned = []
    done = schedule([[0, 1], [0, 1], [1]], ["w"], lambda w, item, number: planned.append((number, item)))
    assert done["raised"] is None
    assert planned == [(0, 0), (0, 1), (1, 0), (1, 1), (1, 2)]
    assert done["executed"] == [0, 1, 2]


def test_tasks_planned_out_of_order_are_executed_in_task_order():
    """Task 0's pass ends last: the others wait for it to be executed first, and no pass waits for a slower
    task of the same stage (task 1's second pass starts while task 0's first runs)."""
    release, second_pass = threading.Event(), threading.Event()
    log = []

    def plan(worker, item, number):
        log.append((worker, item, number))
        if (item, number) == (0, 0):
            assert release.wait(TIMEOUT)
        if (item, number) == (1, 1):
            second_pass.set()
            release.set()

    executed = []
    done = schedule([[0, 1], [0, 1], [0, 1]], ["a", "b"], plan, execute=lambda k, item: executed.append(item))
    assert done["raised"] is None and second_pass.is_set()
    assert executed == [0, 1, 2]
    assert sorted((item, number) for _, item, number in log) == [(i, n) for i in range(3) for n in range(2)]
    for item in range(3):  # each task's passes in order
        assert [n for _, i, n in log if i == item] == [0, 1]


def test_a_task_that_stops_going_on_runs_no_further_pass():
    planned = []
    done = schedule([[0, 1, 2], [0, 1, 2]], ["a", "b"], lambda w, item, number: planned.append((item, number)),
                    goes_on=lambda item: item != 0)
    assert done["raised"] is None
    assert sorted(planned) == [(0, 0), (1, 0), (1, 1), (1, 2)] and done["executed"] == [0, 1]


def test_an_interrupted_run_starts_no_pass_interrupts_those_in_flight_and_ends_its_threads():
    """Ctrl-C while executing task 0: interrupt() is called, the pass in flight (waiting on the model) ends,
    no other starts, and every worker's thread has ended when the scheduler raises."""
    in_flight, interrupted = {1: threading.Event(), 2: threading.Event()}, threading.Event()
    planned, threads = [], []

    def plan(worker, item, number):
        threads.append(threading.current_thread())
        planned.append(item)
        if item in in_flight:
            in_flight[item].set()
            assert interrupted.wait(TIMEOUT)  # a lane waiting for a batch until the lanes close

    def execute(k, item):
        assert all(event.wait(TIMEOUT) for event in in_flight.values())  # both workers busy
        raise KeyboardInterrupt

    done = schedule([[0], [0], [0], [0]], ["a", "b"], plan, execute=execute, interrupt=interrupted.set)
    assert isinstance(done["raised"], KeyboardInterrupt) and interrupted.is_set()
    assert not any(thread.is_alive() for thread in threads)
    assert sorted(planned) == [0, 1, 2]  # task 3's pass never started


def test_a_failing_worker_stops_the_run_with_its_error():
    threads = []

    def plan(worker, item, number):
        threads.append(threading.current_thread())
        if item == 1:
            raise RuntimeError("a bug in the scheduler's caller")

    done = schedule([[0], [0], [0]], ["a", "b"], plan)
    assert isinstance(done["raised"], RuntimeError) and 2 not in done["executed"]
    assert not any(thread.is_alive() for thread in threads)


class _Overlapping(_Recorded):
    """A fake method whose kitchen-05 coalition waits until a task has been scored (``waited``: it was)."""

    def __init__(self, scored: threading.Event):
        super().__init__()
        self.scored, self.waited = scored, False

    def _run(self, stage, task):
        noted = super()._run(stage, task)

        def run(result):
            if (stage, task.id) == ("coalition", "kitchen-05"):
                self.waited = self.scored.wait(TIMEOUT)
            noted(result)
        return run


def test_a_run_on_two_workers_resumes_keeps_each_pass_on_one_worker_and_scores_in_task_order(tmp_path):
    """run_benchmark with two workers (fake methods noting what they run): the first tasks are executed and
    scored while the last is planned, the stages a store holds are not run again, a task's coalition and the
    allocation that goes on in its context run on one worker, one after the other, and the results lines are in
    the tasks' order."""
    catalogue = load_domain().catalogue
    ids = ("kitchen-01", "kitchen-02", "kitchen-03", "kitchen-04", "kitchen-05")
    tasks = [find_task(load_tasks(), t) for t in ids]
    store = RunStore(tmp_path, {"identity": {}, "started": "now"})
    store.save_stage("kitchen-02", StageRecord("coalition", output="saved\n"))
    store.save_stage("kitchen-02", StageRecord("allocation", output="# INFEASIBLE: saved\n", refusal="saved"))
    scored = threading.Event()
    store.append_result = lambda line, append=store.append_result: (append(line), scored.set())
    workers = [_Overlapping(scored), _Overlapping(scored)]
    run_benchmark(tasks, workers, catalogue, store=store)
    assert workers[0].waited or workers[1].waited, "kitchen-05 was planned before any task was scored"
    calls = [call for worker in workers for call in worker.calls]
    assert sorted(calls) == sorted((stage, t) for t in ids if t != "kitchen-02"
                                   for stage in ("coalition", "allocation"))
    for worker in workers:  # each coalition followed at once by its allocation, on its worker
        assert all(worker.calls[i + 1] == ("allocation", task) for i, (stage, task) in enumerate(worker.calls)
                   if stage == "coalition")
    assert list(store.results()) == list(ids)


@pytest.mark.parametrize(("args", "parts"), [
    (["--parallel", "0"], ["--parallel must be 1 or more", "not 0"]),
    (["--parallel", "-3"], ["--parallel must be 1 or more", "not -3"]),
    (["--parallel", "257"], ["llama.cpp holds at most 256 sequences", "give 256 or fewer"]),
    (["--backend", "transformers", "--parallel", "4"], ["transformers backend decodes one sequence at a time",
                                                        "--backend llamacpp", "leave out --parallel"]),
])
def test_bad_parallel_is_refused_before_anything_runs(tmp_path, args, parts):
    one_line_error(cli("benchmark", "run", "--task", "kitchen-01", "--out", tmp_path / "r", *args), *parts)
    assert not (tmp_path / "r").exists()


TASKS = ("kitchen-01", "kitchen-02", "living-01", "bedroom-01")
# The only fields that may differ: times, and the prompt tokens a cache gave (what other lanes' sequences held).
TIMED = {"seconds", "prompt_seconds", "reused"}


def _untimed(value):
    if isinstance(value, dict):
        return {k: _untimed(v) for k, v in value.items() if k not in TIMED}
    return value


def _run(out: Path, states: Path, *extra: str) -> list[dict]:
    proc = subprocess.run([sys.executable, "-m", "smartllm_local", "benchmark", "run", "--prefix-cache", str(states),
                           "--out", str(out), *extra, *(a for t in TASKS for a in ("--task", t))],
                          capture_output=True, text=True, timeout=1800)
    assert proc.returncode == 0, proc.stderr
    return [json.loads(line) for line in (out / "results.jsonl").read_text().splitlines()]


@pytest.mark.heavy  # two SmolLM2 runs of four tasks: 117 s of the default suite
def test_three_tasks_at_once_write_the_plans_of_one_at_a_time(tmp_path):
    """SmolLM2, greedy: with --parallel 3 (three lanes of one model, the four tasks' stages in shared batches)
    every stage writes what it writes one task at a time, and the results file lists the tasks in their order."""
    states = tmp_path / "states"
    alone = _run(tmp_path / "k1", states)
    together = _run(tmp_path / "k3", states, "--parallel", "3")
    assert [line["id"] for line in together] == list(TASKS)
    assert [_untimed(line) for line in together] == [_untimed(line) for line in alone]
    written = [path.relative_to(tmp_path / "k1") for pattern in ("*/*/raw_output.txt", "*/decomposed.py",
                                                                 "*/coalition.txt", "*/allocated.py")
               for path in (tmp_path / "k1").glob(pattern)]
    assert any(path.name == "allocated.py" for path in written)  # a plan, at least, to compare
    for path in written:
        assert (tmp_path / "k3" / path).read_text() == (tmp_path / "k1" / path).read_text(), path
    assert json.loads((tmp_path / "k3" / "run.json").read_text())["identity"] == \
        json.loads((tmp_path / "k1" / "run.json").read_text())["identity"]
