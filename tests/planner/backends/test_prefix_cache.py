"""The examples' key/value states, evaluated once: kept across tasks in a process and across processes on disk.

The store's unit tests use bytes; the reuse tests use the real llama.cpp with the embedded models, in one
process and through the CLI.
"""

from __future__ import annotations

import json
import os
import subprocess
from pathlib import Path

import pytest

from smartllm_local.benchmark.tasks import find_task, load_tasks
from smartllm_local.domain import load_domain
from smartllm_local.errors import UserError
from smartllm_local.planner.backends import load_backend
from smartllm_local.planner.backends.prefix_cache import (
    PrefixReuse,
    PrefixStore,
    default_store_folder,
    open_store,
    state_key,
)
from smartllm_local.planner.pipeline import Planner
from smartllm_local.planner.result import PlanResult
from smartllm_local.worlds import scene_objects
from tests.cli.test_cli_errors import cli, one_line_error

PREFIX = [1, 5, 9, 200]


def entries(folder: Path) -> list[Path]:
    return sorted(folder.glob("*.kv"))


def test_a_stored_state_comes_back_for_its_prefix_only(tmp_path):
    store = PrefixStore(tmp_path)
    key = state_key({"model": "m"}, PREFIX)
    assert store.save(key, PREFIX, b"state bytes")
    assert store.load(key, PREFIX) == b"state bytes"
    assert store.load(key, PREFIX[:-1]) is None  # same name, other tokens: never trusted
    assert state_key({"model": "other"}, PREFIX) != key != state_key({"model": "m"}, PREFIX[:-1])
    assert not list(tmp_path.glob(".entry.*"))  # no temporary file left behind


@pytest.mark.parametrize("damage", [
    lambda data: data[: len(data) // 2],  # truncated by a crash or a full disk
    lambda data: data[:-1] + bytes([data[-1] ^ 1]),  # one bit of the state flipped
    lambda data: b"not a state at all",
    lambda data: b"",
    lambda data: data.replace(b'"tokens": [1, 5', b'"tokens": [1, 6'),  # header of another prefix
])
def test_a_damaged_entry_is_deleted_and_never_trusted(tmp_path, damage):
    store = PrefixStore(tmp_path)
    key = state_key({"model": "m"}, PREFIX)
    store.save(key, PREFIX, bytes(range(256)) * 4)
    path, = entries(tmp_path)
    path.write_bytes(damage(path.read_bytes()))
    assert store.load(key, PREFIX) is None
    assert not path.exists() and store.rejected == 1


def test_the_store_keeps_within_its_bound_dropping_the_least_recently_used(tmp_path):
    store = PrefixStore(tmp_path, max_bytes=3_500)
    keys = [state_key({"n": n}, PREFIX) for n in range(3)]
    for n, key in enumerate(keys):
        store.save(key, PREFIX, bytes([n]) * 1_000)
        os.utime(store._path(key), ns=(n * 10**9, n * 10**9))  # saved one second apart
    assert store.load(keys[0], PREFIX) is not None  # used now: the most recent
    store.save(state_key({"n": 3}, PREFIX), PREFIX, b"\3" * 1_000)
    assert store.load(keys[1], PREFIX) is None  # the least recently used went
    assert all(store.load(k, PREFIX) is not None for k in (keys[0], keys[2]))
    assert sum(p.stat().st_size for p in entries(tmp_path)) <= 3_500


def test_a_store_that_cannot_be_written_costs_only_the_reuse(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("x")
    store = PrefixStore(blocker / "states")  # under a file: never a folder
    assert store.save(state_key({}, PREFIX), PREFIX, b"s") is False
    assert store.load(state_key({}, PREFIX), PREFIX) is None


def test_the_default_store_is_in_the_users_cache_and_off_is_none(monkeypatch, tmp_path):
    monkeypatch.delenv("SMARTLLM_CACHE_DIR", raising=False)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    assert default_store_folder() == tmp_path / "smartllm-local" / "prefix-states"
    assert open_store(None).folder == default_store_folder()
    assert open_store("off") is None
    assert open_store(tmp_path / "mine").folder == tmp_path / "mine"
    (tmp_path / "a-file").write_text("x")
    with pytest.raises(UserError, match="--prefix-cache"):
        open_store(tmp_path / "a-file")


def test_a_prefix_cache_that_is_a_file_is_exit_2_before_the_model_loads(tmp_path):
    (tmp_path / "states").write_text("x")
    one_line_error(cli("plan", "--task", "kitchen-01", "--prefix-cache", tmp_path / "states"),
                   "--prefix-cache", "is an existing file")


def test_later_tasks_reuse_the_examples_and_scene_and_plan_what_they_plan_alone():
    """Gemma-3, a sliding-window model, whose loaded states give other logits than the live cache they
    were saved from: a task planned alone (every prompt evaluated whole, its states saved), then after
    another on the same floor plan (its examples' and scene's states loaded from memory), writes exactly
    the same, and its decomposition evaluates only its instruction."""
    catalogue = load_domain().catalogue
    first, second = (find_task(load_tasks(), t) for t in ("living-01", "living-02"))
    assert first.floor_plan == second.floor_plan
    shared = load_backend("llamacpp", "gemma3-270m", prefix_cache="off")
    try:
        planner = Planner(shared, catalogue)
        alone = planner.plan(second.instruction, second.floor_plan, second.robots)
        before = planner.plan(first.instruction, first.floor_plan, first.robots)
        after = planner.plan(second.instruction, second.floor_plan, second.robots)
    finally:
        shared.close()
    assert list(after.stages) == list(alone.stages) == ["decomposition", "coalition", "allocation"]
    assert [r.output for r in after.stages.values()] == [r.output for r in alone.stages.values()] and after.allocated
    assert all(alone.stage(name).reused_tokens == 0 and alone.stage(name).shared_tokens > 0
               for name in ("decomposition", "coalition"))
    decomposition, coalition = ((before.stage(name), after.stage(name)) for name in ("decomposition", "coalition"))
    assert decomposition[1].reused_tokens > decomposition[1].shared_tokens > 0
    assert decomposition[1].prompt_tokens - decomposition[1].reused_tokens < 80  # the team's skills and the instruction
    assert coalition[1].reused_tokens == (coalition[1].shared_tokens if coalition[0].examples == coalition[1].examples
                                          else 0)
    for run in (alone, after):
        # The coalition chose; living-02's allocation had nothing left to choose (its sub-task's robot and every
        # step's were the coalition's and the team's): the planner wrote it, and no prompt was evaluated. An
        # allocation that goes on in its coalition's context: tests/benchmark/test_speed.py.
        record, coalition = run.stage("allocation"), run.stage("coalition")
        assert coalition.prompted and coalition.generated_tokens > 0
        assert not record.prompted and record.generated_tokens == record.reused_tokens == 0 < record.forced_tokens


def _planned(tmp_path, states=None):
    """SmolLM2 plans kitchen-01 through the CLI with a store of its own: (allocated plan, stage records, the
    process) of each run, named, with the options given."""
    states = states or tmp_path / "states"

    def plan(name: str, *options: str) -> tuple[str, dict[str, dict], subprocess.CompletedProcess]:
        proc = cli("plan", "--task", "kitchen-01", "--prefix-cache", states, "--out", tmp_path / name, *options)
        assert proc.returncode == 0, proc.stderr
        stages = json.loads((tmp_path / name / "result.json").read_text())["stages"]
        return (tmp_path / name / "allocated.py").read_text(), stages, proc

    return states, plan


def test_a_second_process_starts_from_the_stored_examples(kitchen01, tmp_path):
    """After the session's plan of kitchen-01 (a store of its own, empty before), a second ``plan`` evaluates none
    of the examples, nor the scene's objects in its decomposition, and writes the same plan (``--quiet``: with
    no progress on stderr, only its notices, and only the plan on stdout)."""
    _, plan = _planned(tmp_path, kitchen01.states)
    first = (kitchen01.out / "allocated.py").read_text()
    cold = json.loads((kitchen01.out / "result.json").read_text())["stages"]
    stored = entries(kitchen01.states)
    # The decomposition's examples and scene. kitchen-01's one robot leaves the coalition and the allocation
    # nothing to choose: the planner writes them and evaluates no prompt, so nothing of theirs is stored (a coalition
    # and allocation the model writes, from stored examples: tests/benchmark/test_speed.py).
    assert len(stored) == 2 and cold["decomposition"]["reused_tokens"] == 0
    assert not any(cold[stage]["prompted"] or cold[stage]["generated_tokens"] for stage in ("coalition", "allocation"))
    second, warm, proc = plan("second", "--quiet")
    assert second == first
    assert all(line.startswith("notice: ") for line in proc.stderr.splitlines()) and proc.stdout == second
    decomposition = warm["decomposition"]
    assert decomposition["prompt_tokens"] - decomposition["reused_tokens"] < 90  # team skills, instruction, chat turn
    assert len(entries(kitchen01.states)) == 2


@pytest.mark.heavy
def test_a_damaged_store_is_rebuilt(tmp_path):
    """With every entry cut short, a process evaluates the examples again, writes the same plan, and stores them
    anew (a damaged entry is never trusted: test_a_damaged_entry_is_deleted_and_never_trusted, by default)."""
    states, plan = _planned(tmp_path)
    first, _, _ = plan("first")
    stored = entries(states)
    for path in stored:
        path.write_bytes(path.read_bytes()[:1000])
    third, rebuilt, _ = plan("third")
    assert third == first and rebuilt["coalition"]["reused_tokens"] == rebuilt["decomposition"]["reused_tokens"] == 0
    assert [p.stat().st_size > 1000 for p in entries(states)] == [True] * 2  # the decomposition's (see above)


class _Keeper(PrefixReuse):
    """The decision alone: a cache of ``held`` tokens whose state takes ``per_token`` bytes each."""

    def __init__(self, held: int, per_token: int):
        self._tokens, self.per_token = [0] * held, per_token

    def _state_bytes(self) -> int:
        return len(self._tokens) * self.per_token


@pytest.mark.parametrize(("per_token", "keeps", "stores"), [
    (20_000, True, True),  # a small model on a CPU: copying is a sliver of evaluating
    (150_000, True, False),  # out of the engine and back pays, through the disk it does not
    (500_000, False, False),  # a 7B on a GPU: evaluating again is cheaper than copying
])
def test_states_are_kept_only_where_copying_them_costs_a_fifth_of_evaluating(per_token, keeps, stores):
    keeper = _Keeper(2000, per_token)
    keeper._decide_keeping(1000, 1000 * 0.8e-3)  # 1,250 tokens a second
    assert (keeper.keeps_states, keeper.stores_states) == (keeps, stores)


def test_a_short_piece_decides_nothing():
    keeper = _Keeper(2000, 10**9)
    keeper._decide_keeping(PrefixReuse._DECIDE_TOKENS - 1, 10.0)
    assert keeper.keeps_states is None and keeper.stores_states is None


def test_where_keeping_does_not_pay_prompts_are_evaluated_whole_and_plan_the_same(smollm2, tmp_path):
    """A backend that measures (as one on a GPU does) and finds copying states dear keeps none and stores none,
    reuses what its live cache shares with the next prompt, and writes what a backend that keeps them writes
    (on the CPU every backend keeps them, decided from the start)."""
    assert smollm2.keeps_states is smollm2.stores_states is True
    catalogue = load_domain().catalogue
    task = find_task(load_tasks(), "kitchen-01")
    dear = load_backend("llamacpp", "smollm2", n_ctx=8192, prefix_cache=tmp_path / "states")
    try:
        dear.keeps_states = dear.stores_states = None  # measured, as where layers are on a GPU
        dear.MEMORY_BYTES_PER_S = 1.0
        planner = Planner(dear, catalogue)
        record = planner.decompose(PlanResult(task.instruction, task.floor_plan, list(task.robots)))
        assert dear.keeps_states is False and dear.stores_states is False
        assert not (tmp_path / "states").exists() or not entries(tmp_path / "states")
        context = list(dear._tokens[:-2])  # the prompt and most of what was written after it
        evaluated = dear.evaluated_tokens
        reused = dear.prefill(context, record_prefixes(planner, task))
        assert dear._tokens == context and reused == len(context) - (dear.evaluated_tokens - evaluated)
        assert len(context) - 3 <= reused < len(context)  # the live cache's prefix: its last token or two again
    finally:
        dear.close()
    kept = Planner(smollm2, catalogue).decompose(PlanResult(task.instruction, task.floor_plan,
                                                            list(task.robots)))
    assert record.output == kept.output and record.reused_tokens == 0


def record_prefixes(planner: Planner, task) -> list[int]:
    return planner.decomposition_prompt(task.instruction, scene_objects(task.floor_plan),
                                        load_domain().catalogue.team(task.robots)).prefixes
