"""Lanes: several sequences of SmolLM2 decoded together in one llama.cpp context, each from a thread of its own,
driven by the planner's own stage code; their outputs are those of the backend alone."""

from __future__ import annotations

import threading
from collections.abc import Callable

import numpy as np
import pytest

from smartllm_local.benchmark.tasks import load_tasks
from smartllm_local.domain import load_domain
from smartllm_local.errors import ModelError
from smartllm_local.planner.backends.lanes import open_lanes
from smartllm_local.planner.decoding.grammar import Grammar, GrammarError, alt, chars, rep, seq
from smartllm_local.planner.decoding.matcher import Matcher
from smartllm_local.planner.decoding.repetition import LoopGuard
from smartllm_local.planner.decoding.sampling import Sampling
from smartllm_local.planner.pipeline import Planner
from smartllm_local.planner.result import PlanResult

FRUIT = "# a list of fruit:\n"
WORDS = Grammar({"root": seq("# ", rep(chars("abcdefghijklmnopqrstuvwxyz "), 1, 40), "\n")})
TIMEOUT = 600  # seconds a lane's thread may take before the test calls it hung


def in_threads(views: list, work: Callable[[int, object], object]) -> list:
    """``work(i, view)`` for each view at once, one thread each; the results (or the exceptions raised), in order.
    A thread still running after TIMEOUT fails the test: a lane left waiting."""
    results: list = [None] * len(views)

    def run(i: int) -> None:
        try:
            results[i] = work(i, views[i])
        except Exception as exc:  # noqa: BLE001 - handed to the test
            results[i] = exc

    threads = [threading.Thread(target=run, args=(i,), daemon=True) for i in range(len(views))]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join(TIMEOUT)
    assert not any(thread.is_alive() for thread in threads), "a lane never returned: it was left waiting"
    return results


def decompose(backend, task_id: str):
    """The decomposition stage of a household task, as the planner runs it (greedy), on ``backend``."""
    task = next(t for t in load_tasks() if t.id == task_id)
    planner = Planner(backend, load_domain().catalogue)
    scene = planner.scene(task.floor_plan)
    result = PlanResult(instruction=task.instruction, floor_plan=scene.floor_plan, robots=list(task.robots))
    return planner.decompose(result)


@pytest.fixture(scope="module")
def alone(smollm2) -> dict:
    """Each task's decomposition stage as the backend runs it by itself, one task at a time."""
    return {task: decompose(smollm2, task) for task in ("kitchen-01", "kitchen-05")}


def test_a_lane_alone_runs_the_stage_as_the_backend_does_from_the_state_the_backend_kept(smollm2, alone):
    """The decomposition stage through a lane in a batch of one writes what the backend writes, its prompt begun
    from the examples' and scene's state the backend kept (SmolLM2's logits do not change with batching)."""
    with open_lanes(smollm2, 1) as (views, concurrent):
        assert views == [smollm2] and not concurrent  # one lane is the backend itself
    with smollm2.lanes(1) as views:
        lane = decompose(views[0], "kitchen-01")
    own = alone["kitchen-01"]
    assert lane.reused_tokens >= lane.shared_tokens > 0
    assert (lane.output, lane.raw, lane.context) == (own.output, own.raw, own.context)


def test_lanes_given_one_task_each_write_the_decomposition_the_backend_writes_alone(smollm2, alone):
    with open_lanes(smollm2, 3) as (views, concurrent):
        assert concurrent and len({id(v) for v in views}) == 3
        records = in_threads(views, lambda i, view: decompose(view, "kitchen-01"))
        evaluated = sum(v.evaluated_tokens for v in views)
    for record in records:
        assert not isinstance(record, Exception), record
        assert record.plan is not None and not record.error and record.refusal is None
        assert record.reused_tokens >= record.shared_tokens > 0
    assert [r.output for r in records] == [alone["kitchen-01"].output] * 3
    # the part of the prompt no state was kept for, once, and each lane's own tokens
    assert evaluated < records[0].prompt_tokens - records[0].shared_tokens + 3 * len(records[0].context)


def test_lanes_given_different_tasks_each_write_their_own_decomposition(smollm2, alone):
    tasks = ["kitchen-01", "kitchen-05"]
    with open_lanes(smollm2, 2) as (views, _):
        records = in_threads(views, lambda i, view: decompose(view, tasks[i]))
    for record, task in zip(records, tasks):
        assert not isinstance(record, Exception), record
        assert record.plan is not None and not record.error
        assert record.output == alone[task].output


def test_a_lane_alone_writes_what_the_backend_writes(smollm2):
    context = smollm2.tokenize(FRUIT, bos=True)
    own = smollm2.generate(context, grammar=WORDS, max_tokens=60, sampling=Sampling())
    with smollm2.lanes(1) as views:
        lane = views[0].generate(context, grammar=WORDS, max_tokens=60, sampling=Sampling())
    assert (lane.text, lane.tokens, lane.logprob) == (own.text, own.tokens, own.logprob)


@pytest.mark.parametrize("unified", [False, True])
def test_a_prompt_given_to_every_lane_is_evaluated_once_and_each_token_step_is_one_batch(smollm2, unified):
    context = smollm2.tokenize(FRUIT * 40, bos=True)
    with smollm2.lanes(4, unified=unified) as views:
        reused = in_threads(views, lambda i, view: view.prefill(context, ()))
        assert sum(v.evaluated_tokens for v in views) == len(context) + 3  # each other lane: its last token's logits
        assert sorted(reused) == [0] + [len(context) - 1] * 3
        batches = views[0].batches
        outs = in_threads(views, lambda i, view: view.generate(context, grammar=WORDS, max_tokens=60,
                                                                sampling=Sampling()))
        steps = views[0].batches - batches
    assert len({o.text for o in outs}) == 1 and WORDS.matches(outs[0].text)
    assert steps <= len(outs[0].tokens) + 1  # one llama_decode per token for all four lanes


class _Exploding(LoopGuard):
    """A loop guard that fails once a line is long enough: a lane that raises midway through its line."""

    def loops(self, line: str) -> bool:
        if len(line) > 8:
            raise RuntimeError("this lane fails")
        return super().loops(line)


class _Rejected(Grammar):
    def to_gbnf(self) -> str:
        return 'root ::= "a" missing-rule\n'


def test_a_lane_that_raises_leaves_the_others_running(smollm2):
    context = smollm2.tokenize(FRUIT, bos=True)
    own = smollm2.generate(context, grammar=WORDS, max_tokens=60, sampling=Sampling()).text

    def work(i: int, view):
        grammar = _Rejected({"root": "a"}) if i == 1 else WORDS
        guard = _Exploding() if i == 2 else LoopGuard()
        return view.generate(context, grammar=grammar, max_tokens=60, sampling=Sampling(loop_guard=guard)).text

    with open_lanes(smollm2, 4) as (views, _):
        results = in_threads(views, work)
    assert isinstance(results[1], GrammarError) and "this lane fails" in str(results[2])
    assert results[0] == results[3] == own


def test_the_backend_writes_the_same_after_lanes_and_a_closed_lane_says_so(smollm2):
    context = smollm2.tokenize(FRUIT, bos=True)
    before = smollm2.generate(context, grammar=WORDS, max_tokens=60, sampling=Sampling())
    with smollm2.lanes(2) as views:
        in_threads(views, lambda i, view: view.generate(context + [i + 100], grammar=WORDS, max_tokens=60,
                                                        sampling=Sampling()))
    after = smollm2.generate(context, grammar=WORDS, max_tokens=60, sampling=Sampling())
    assert (after.text, after.tokens) == (before.text, before.tokens)
    with pytest.raises(ModelError, match="closed"):
        views[0].generate(context, grammar=WORDS, max_tokens=60, sampling=Sampling())


def test_sampled_lanes_are_reproducible_by_their_seeds(smollm2):
    context = smollm2.tokenize(FRUIT, bos=True)

    def sample(i: int, view) -> str:
        hot = Sampling(temperature=1.5, seed=i)
        return view.generate(context, grammar=WORDS, max_tokens=60, sampling=hot, rng=np.random.default_rng(i)).text

    runs = []
    for _ in range(2):
        with open_lanes(smollm2, 4) as (views, _):
            runs.append(in_threads(views, sample))
    assert runs[0] == runs[1]
    assert len(set(runs[0])) > 1
    assert all(Matcher(WORDS).advance(t) for t in runs[0])  # a line, or where the model ended, the start of one


def test_one_lane_or_a_backend_without_lanes_is_the_backend_itself():
    class Plain:
        pass

    backend = Plain()
    with open_lanes(backend, 3) as (views, concurrent):
        assert views == [backend] * 3 and not concurrent
    with open_lanes(backend, 1) as (views, concurrent):
        assert views == [backend] and not concurrent
    with pytest.raises(ValueError):
        with open_lanes(backend, 0):
            pass


def test_each_lane_keeps_its_own_grammar(smollm2):
    """Each lane has its own grammar: lanes given different alternatives each write one of their own."""
    context = smollm2.tokenize("The capital of France is", bos=True)
    choices = [(" London.\n", " Rome.\n"), (" Paris.\n", " Madrid.\n")]
    with open_lanes(smollm2, 2) as (views, _):
        texts = in_threads(views, lambda i, view: view.generate(
            context, grammar=Grammar({"root": alt(*choices[i])}), max_tokens=8, sampling=Sampling()).text)
    assert texts[0] in choices[0] and texts[1] in choices[1]
