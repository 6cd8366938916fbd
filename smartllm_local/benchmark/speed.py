"""``smartllm-local bench``: the speed figures docs/measurements.md and docs/servers-and-gpus.md quote, measured
side by side in one run.

Each model is measured as ``plan`` would run it (its backend, GPU layers, context and chat template):

- the prompt path: ``prefill`` of the first sample task's decomposition prompt in a new backend with an empty
  prefix store (kept states, the store and batches included), over the seconds llama.cpp takes to evaluate the
  same tokens alone (``prefill_over_engine``; llama.cpp in-process only), and the same prompt again, with the
  states kept in memory and from the store in a new backend;
- decoding: per model, the tokens per second the decomposition stage writes with its grammar and
  without it (free generation with stop strings), over the same tasks, prompt evaluation left out;
- prefix reuse: per model, the prompt tokens evaluated and the time to the first token of every
  stage, for the first task of a run (nothing kept), the later ones (the examples' states kept in
  memory) and the first task again in a new backend (the states from the disk store, as a second
  ``plan`` process finds them);
- the executor: every feasible task's reference plan, plans and actions per second;
- sharing the cores: ``plan`` of the first sample task with the first model alone, then two at once
  (:mod:`.sharing`);
- optionally, ``benchmark run`` over every task with the first model, one seed, from an empty prefix
  store, timed as a user would time it, with the prompt tokens its later tasks evaluated per stage
  (there tasks on the same floor plan also share their decomposition's scene).
"""

from __future__ import annotations

import json
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any

from ..errors import SmartLLMError
from ..executor import run_plan
from ..planner.backends import Backend, Sampling
from ..planner.pipeline import Planner, PlannerConfig
from ..planner.prompting.prompts import STAGES
from ..planner.result import PlanResult
from ..provenance import versions
from ..robots import Catalogue
from ..world.controller import open_controller
from ..worlds import scene_objects
from .reference_plans import load_reference_plan
from .sharing import core_sharing
from .tasks import Task


def spread_tasks(tasks: Sequence[Task], count: int) -> list[Task]:
    """``count`` feasible tasks spread over the list (so over its categories)."""
    feasible = [t for t in tasks if t.feasible]
    step = max(1, len(feasible) // max(1, count))
    return feasible[::step][:count]


Load = Callable[[str], Backend]  # a backend for the model measured, given its prefix store ("off": none)


def prefill_cost(load: Load, config: PlannerConfig, catalogue: Catalogue, task: Task) -> dict[str, Any]:
    """Seconds to prefill ``task``'s decomposition prompt: in a new backend with an empty store, against llama.cpp
    evaluating the same tokens alone; again in that backend; and in a new one on the store the first filled."""
    found: dict[str, Any] = {}
    with tempfile.TemporaryDirectory(prefix="smartllm-bench-") as store:
        for way in ("first", "second_process"):
            backend = load(store)
            try:
                fitted = Planner(backend, catalogue, config).decomposition_prompt(
                    task.instruction, scene_objects(task.floor_plan), catalogue.team(task.robots))
                tokens, prefixes = list(fitted.tokens), fitted.prefixes
                engine = getattr(backend, "engine_seconds", None)
                if way == "first":  # first, so that the device's first use (its kernels loaded) is not prefill's
                    found["engine_s"] = round(min(engine(tokens) for _ in range(2)), 3) if engine else None
                backend.prefill(tokens[:8], ())
                found[way] = _timed_prefill(backend, tokens, prefixes)
                if way == "first":
                    found["kept"] = _timed_prefill(backend, tokens, prefixes, warm=tokens[:8])
                    found["keeps_states"] = getattr(backend, "keeps_states", None)
                    found["stores_states"] = getattr(backend, "stores_states", None)
            finally:
                backend.close()
    found["prompt_tokens"] = len(tokens)
    found["prefill_over_engine"] = round(found["first"]["seconds"] / found["engine_s"], 3) \
        if found["engine_s"] else None
    return found


def _timed_prefill(backend: Backend, tokens: list[int], prefixes: Sequence[int],
                   warm: Sequence[int] = ()) -> dict[str, Any]:
    """Seconds from the prompt to its first token: ``prefill``, then one token drawn (in process the prompt's
    logits are then read; through a server, whose slot evaluates a prompt's last batch with the first request,
    that request is made)."""
    if warm:  # another prompt in the cache first, as a later task finds it
        backend.prefill(list(warm), ())
    started = time.perf_counter()
    reused = backend.prefill(tokens, prefixes)
    backend.generate(tokens, grammar=None, max_tokens=1, sampling=Sampling(loop_guard=None))
    return {"seconds": round(time.perf_counter() - started, 3), "reused": reused}


def decode_speed(load: Load, config: PlannerConfig, catalogue: Catalogue, tasks: Sequence[Task]) -> dict[str, Any]:
    """The decomposition stage's output tokens per second with its grammar and without, prompt evaluation
    left out. Constrained output counts the tokens the model chose and those the grammar forced (in one
    batch each); ``generated_per_s`` counts the chosen ones alone."""
    backend = load("off")
    found: dict[str, Any] = {}
    try:
        for name, grammar in (("constrained", True), ("free", False)):
            planner = Planner(backend, catalogue, replace(config, grammar=grammar))
            generated = forced = 0
            seconds = 0.0
            for task in tasks:
                result = PlanResult(task.instruction, task.floor_plan, list(task.robots))
                record = planner.decompose(result)
                generated, forced = generated + record.generated_tokens, forced + record.forced_tokens
                seconds += record.seconds - record.prompt_seconds
            found[name] = {"tasks": len(tasks), "generated_tokens": generated, "forced_tokens": forced,
                           "seconds": round(seconds, 3), "tokens_per_s": round((generated + forced) / seconds, 2),
                           "generated_per_s": round(generated / seconds, 2)}
    finally:
        backend.close()
    found["constrained_over_free"] = round(found["constrained"]["tokens_per_s"] / found["free"]["tokens_per_s"], 3)
    return found


def _costs(result: PlanResult) -> dict[str, dict[str, float]]:
    return {r.stage: {"prompt": r.prompt_tokens, "reused": r.reused_tokens, "prompted": r.prompted,
                      "evaluated": r.prompt_tokens - r.reused_tokens if r.prompted else 0,
                      "ttft_s": round(r.prompt_seconds, 3)} for r in result.stages.values()}


def prefix_reuse(load: Load, config: PlannerConfig, catalogue: Catalogue, tasks: Sequence[Task]) -> dict[str, Any]:
    """Prompt tokens evaluated and time to the first token per stage: the first task of a run, the later
    ones, and the first again in a new backend on the same (at first empty) store."""
    with tempfile.TemporaryDirectory(prefix="smartllm-bench-") as store:
        runs: list[list[dict[str, dict[str, float]]]] = []
        for batch in (tasks, tasks[:1]):  # a run, then a second "process"
            backend = load(store)
            try:
                planner = Planner(backend, catalogue, config)
                runs.append([_costs(planner.plan(t.instruction, t.floor_plan, list(t.robots))) for t in batch])
            finally:
                backend.close()
    (first, *later), (again,) = runs
    stages: dict[str, Any] = {}
    for stage in STAGES:
        if stage not in first:
            continue
        rest = [costs[stage] for costs in later if stage in costs]
        evaluated = statistics.fmean(c["evaluated"] for c in rest) if rest else None
        stages[stage] = {
            "first": first[stage], "second_process": again.get(stage),
            "later_evaluated_mean": round(evaluated, 1) if evaluated is not None else None,
            "later_ttft_s_mean": round(statistics.fmean(c["ttft_s"] for c in rest), 3) if rest else None,
            "later_over_first_prompt_tokens": round(evaluated / first[stage]["prompt"], 3)
            if evaluated is not None else None,
        }
    later_costs = [c for costs in later for c in costs.values()]
    return {
        "tasks": len(tasks), "stages": stages,
        "reused_over_fresh_prompt_tokens": round(sum(c["evaluated"] for c in later_costs)
                                                 / sum(c["prompt"] for c in later_costs), 3) if later_costs else None,
        "second_process_over_fresh_prompt_tokens": round(sum(c["evaluated"] for c in again.values())
                                                         / sum(c["prompt"] for c in again.values()), 3),
    }


def executor_speed(catalogue: Catalogue, tasks: Sequence[Task], build: str | None = None) -> dict[str, Any]:
    """Every feasible task's reference plan on one controller: plans and actions per second."""
    plans = []
    for task in (t for t in tasks if t.feasible):
        plan, problem = load_reference_plan(task, catalogue)
        if plan is None:
            raise SmartLLMError(f"task {task.id}: {problem}; smartllm-local benchmark check lists every such problem")
        plans.append((task, plan))
    actions = 0
    controller = open_controller(plans[0][0].floor_plan, agent_count=len(plans[0][0].robots), build=build)
    try:
        started = time.perf_counter()
        for task, plan in plans:
            execution = run_plan(plan, task.floor_plan, catalogue.team(task.robots), controller=controller,
                                 skills=catalogue.skills)
            actions += execution.attempted
        seconds = time.perf_counter() - started
    finally:
        controller.stop()
    return {"plans": len(plans), "actions": actions, "seconds": round(seconds, 3),
            "plans_per_s": round(len(plans) / seconds, 2), "actions_per_s": round(actions / seconds, 1)}


def time_benchmark(options: Sequence[str], out: Path | None = None) -> dict[str, Any]:
    """``smartllm-local benchmark run`` with the model ``options`` (as ``plan`` takes them) over every task, one
    seed, greedy, from an empty prefix store, timed from start to end (model loading included), in minutes; and
    per stage, the prompt tokens its later tasks evaluated over those of its first. Its run folder is ``out``
    if given."""
    with tempfile.TemporaryDirectory(prefix="smartllm-bench-") as folder:
        run = out or Path(folder) / "run"
        command = [sys.executable, "-m", "smartllm_local", "benchmark", "run", *options,
                   "--out", str(run), "--prefix-cache", str(Path(folder) / "states")]
        started = time.perf_counter()
        done = subprocess.run(command, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        if done.returncode != 0:
            raise SmartLLMError(f"the benchmark run failed: {done.stderr.strip()[-500:]}")
        minutes = round((time.perf_counter() - started) / 60, 2)
        results = [json.loads(line) for line in (run / "results.jsonl").read_text(encoding="utf-8").splitlines()
                   if line.strip()]
    return {"minutes": minutes, "stages": later_prompt_costs(results)}


def later_prompt_costs(results: Sequence[dict[str, Any]]) -> dict[str, Any]:
    """Per stage, over a run's results in order: the first task's prompt tokens, and the tokens the later
    tasks evaluated (their prompts less what they reused), on average and over the first's."""
    stages: dict[str, Any] = {}
    for stage in STAGES:
        costs = [c for c in (r.get("tokens", {}).get(stage) for r in results) if c and c["prompt"]]
        if len(costs) > 1:
            first, later = costs[0], costs[1:]
            evaluated = statistics.fmean(c["prompt"] - c["reused"] for c in later)
            stages[stage] = {"first_prompt": first["prompt"], "later_tasks": len(later),
                             "later_evaluated_mean": round(evaluated, 1),
                             "later_over_first_prompt_tokens": round(evaluated / first["prompt"], 3)}
    return stages


def run_bench(models: dict[str, tuple[Load, PlannerConfig]], catalogue: Catalogue, tasks: Sequence[Task], *,
              sample: int, benchmark_options: Sequence[str] | None = None,
              benchmark_out: Path | None = None, executor: bool = True,
              sharing_options: Sequence[str] | None = None,
              machine: dict[str, Any] | None = None) -> dict[str, Any]:
    """Everything above, as the JSON ``bench`` writes: per model (named as given, each with how to load it and
    the planner's settings), the prompt path, decoding and prefix reuse; the executor; and, given the first
    model's ``benchmark_options``, the whole benchmark; given its ``sharing_options``, plans alone and two at
    once."""
    chosen = spread_tasks(tasks, sample)
    per_model = {name: {"prefill": prefill_cost(load, config, catalogue, chosen[0]),
                        "decode": decode_speed(load, config, catalogue, chosen),
                        "prefix": prefix_reuse(load, config, catalogue, chosen)}
                 for name, (load, config) in models.items()}
    timed = executor_speed(catalogue, tasks) if executor else None
    shared = core_sharing(sharing_options, chosen[0].id) if sharing_options is not None else None
    whole = time_benchmark(benchmark_options, benchmark_out) if benchmark_options is not None else None
    return {
        "machine": {"cpus": os.cpu_count(), "platform": platform.platform(), **(machine or {})},
        "versions": versions(), "sample_tasks": [t.id for t in chosen], "models": per_model,
        "prefill_over_engine": {m: r["prefill"]["prefill_over_engine"] for m, r in per_model.items()},
        "constrained_over_free_decode": {m: r["decode"]["constrained_over_free"] for m, r in per_model.items()},
        "reused_over_fresh_prompt_tokens": {m: r["prefix"]["reused_over_fresh_prompt_tokens"]
                                            for m, r in per_model.items()},
        "second_process_over_fresh_prompt_tokens": {m: r["prefix"]["second_process_over_fresh_prompt_tokens"]
                                                    for m, r in per_model.items()},
        "benchmark_model": next(iter(models)) if whole else None,
        "benchmark": whole, "benchmark_minutes": whole["minutes"] if whole else None,
        "executor": timed, "executor_actions_per_s": timed["actions_per_s"] if timed else None,
        "sharing": shared, "two_plans_over_one": shared["together_over_alone"] if shared else None,
    }


def summary(report: dict[str, Any]) -> str:
    """The figures as a few lines of text."""
    lines = [f"{'model':<14}{'constrained tok/s':>18}{'free tok/s':>12}{'ratio':>7}"
             f"{'later/first prompt':>20}{'2nd process':>13}"]
    for model, found in report["models"].items():
        decode, prefix, prompt = found["decode"], found["prefix"], found["prefill"]
        lines.append(f"{model:<14}{decode['constrained']['tokens_per_s']:>18}{decode['free']['tokens_per_s']:>12}"
                     f"{decode['constrained_over_free']:>7}{prefix['reused_over_fresh_prompt_tokens']!s:>20}"
                     f"{prefix['second_process_over_fresh_prompt_tokens']!s:>13}")
        lines.append(f"  prompt path: {prompt['prompt_tokens']} tokens prefilled in {prompt['first']['seconds']} s "
                     f"(llama.cpp alone: {prompt['engine_s']} s; prefill_over_engine {prompt['prefill_over_engine']}; "
                     f"states kept: {prompt['keeps_states']}, stored: {prompt['stores_states']}); again "
                     f"{prompt['kept']['seconds']} s, in a new process {prompt['second_process']['seconds']} s")
        for stage, cost in prefix["stages"].items():
            lines.append(f"  {stage:<14} first task: {cost['first']['prompt']} prompt tokens, ttft "
                         f"{cost['first']['ttft_s']} s; later tasks: {cost['later_evaluated_mean']} evaluated "
                         f"({cost['later_over_first_prompt_tokens']} of the first's), "
                         f"ttft {cost['later_ttft_s_mean']} s")
    executor = report["executor"]
    if executor is not None:
        lines.append(f"executor: {executor['plans']} reference plans, "
                     f"{executor['actions']} actions in {executor['seconds']} s "
                     f"({executor['plans_per_s']} plans/s, {executor['actions_per_s']} actions/s)")
    shared = report["sharing"]
    if shared is not None:
        lines.append(f"sharing the cores: plan {shared['task']} alone {shared['alone_s']} s, {shared['copies']} at "
                     f"once {', '.join(map(str, shared['together_s']))} s ({shared['together_over_alone']} x alone)")
    if report["benchmark_minutes"] is not None:
        lines.append(f"whole benchmark with {report['benchmark_model']}: {report['benchmark_minutes']} min")
        for stage, cost in report["benchmark"]["stages"].items():
            lines.append(f"  {stage:<14} first task: {cost['first_prompt']} prompt tokens; {cost['later_tasks']} later "
                         f"tasks: {cost['later_evaluated_mean']} evaluated ({cost['later_over_first_prompt_tokens']} "
                         f"of the first's)")
    return "\n".join(lines)
