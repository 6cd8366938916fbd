"""``smartllm-local bench`` with the real SmolLM2, llama.cpp and the stand-in: its figures hang together (seven plans
of two tasks and four ``plan`` processes, minutes: in the heavy suite)."""

from __future__ import annotations

import json

import pytest

from smartllm_local.benchmark.speed import later_prompt_costs
from smartllm_local.benchmark.tasks import load_tasks
from tests.cli.test_cli_errors import cli, one_line_error


@pytest.mark.heavy
def test_bench_measures_decoding_reuse_and_the_executor(tmp_path):
    out = tmp_path / "bench.json"
    proc = cli("bench", "--models", "smollm2", "--sample", "2", "--no-benchmark", "--sharing", "--out", out)
    assert proc.returncode == 0, proc.stderr
    report = json.loads(out.read_text())
    decode = report["models"]["smollm2"]["decode"]
    for way in ("constrained", "free"):
        found = decode[way]
        assert found["tasks"] == 2 and found["generated_tokens"] > 0 and found["seconds"] > 0
        written = found["generated_tokens"] + found["forced_tokens"]
        assert found["tokens_per_s"] == pytest.approx(written / found["seconds"], rel=1e-3)
    assert decode["free"]["forced_tokens"] == 0 < decode["constrained"]["forced_tokens"]
    assert report["constrained_over_free_decode"]["smollm2"] == decode["constrained_over_free"] > 0
    prompt = report["models"]["smollm2"]["prefill"]  # on a CPU keeping states pays: a new process finds them
    assert prompt["keeps_states"] is prompt["stores_states"] is True
    assert prompt["second_process"]["reused"] > 0 and prompt["engine_s"] > 0
    assert report["prefill_over_engine"]["smollm2"] == prompt["prefill_over_engine"] > 0
    prefix = report["models"]["smollm2"]["prefix"]
    for stage, cost in prefix["stages"].items():
        if stage == "allocation":  # it goes on in its coalition's context: only its opening line is new
            assert 0 < cost["first"]["prompt"] - cost["first"]["reused"] < 12
        else:
            assert cost["first"]["reused"] == 0, stage  # an empty store: the first task evaluates everything
        assert cost["second_process"]["reused"] > 0, stage  # a new backend finds it on disk
    # later tasks and the second process evaluate part of their prompts (how much is a figure, not a test)
    assert 0 < report["reused_over_fresh_prompt_tokens"]["smollm2"] < 1
    assert 0 < report["second_process_over_fresh_prompt_tokens"]["smollm2"] < 1
    feasible = sum(t.feasible for t in load_tasks())
    assert report["executor"]["plans"] == feasible and report["executor_actions_per_s"] > 0
    assert report["benchmark_minutes"] is None
    shared = report["sharing"]  # plan alone, then two at once (how much slower is a figure, not a test)
    assert shared["task"] == report["sample_tasks"][0] and shared["copies"] == len(shared["together_s"]) == 2
    assert shared["alone_s"] > 0 and min(shared["together_s"]) > 0
    assert report["two_plans_over_one"] == shared["together_over_alone"] == pytest.approx(
        max(shared["together_s"]) / shared["alone_s"], abs=0.01)
    assert "smollm2" in proc.stdout and "actions/s" in proc.stdout


def test_bench_finds_every_model_before_measuring(tmp_path):
    one_line_error(cli("bench", "--models", "smollm2,missing.gguf", "--out", tmp_path / "b.json"),
                   "missing.gguf does not exist")
    assert not (tmp_path / "b.json").exists()


def test_bench_takes_plans_model_options_and_refuses_a_server_without_endpoint(tmp_path):
    one_line_error(cli("bench", "--backend", "server", "--out", tmp_path / "b.json"), "--endpoint")
    assert not (tmp_path / "b.json").exists()


def test_the_whole_benchmark_is_run_with_the_options_bench_was_given():
    from smartllm_local.cli.options import ModelOptions

    options = ModelOptions(model="model.gguf", n_ctx=4096, threads=8, n_gpu_layers=-1, chat_template="none")
    assert options.as_arguments() == ["--model", "model.gguf", "--backend", "llamacpp", "--n-ctx", "4096",
                                      "--n-gpu-layers", "-1", "--chat-template", "none", "--threads", "8"]
    served = ModelOptions(backend="server", endpoint="http://127.0.0.1:8080")
    assert served.as_arguments()[:4] == ["--backend", "server", "--endpoint", "http://127.0.0.1:8080"]
    slow = ModelOptions(backend="server", endpoint="http://127.0.0.1:8080", server_timeout=900.0)
    assert slow.as_arguments()[4:6] == ["--server-timeout", "900.0"]


def test_every_model_option_is_declared_once_and_reaches_model_options():
    """The commands take their model options from one list (``model_options``); each must be a ModelOptions
    parameter, and each ModelOptions parameter an option: a renamed one would fail here, not drop silently."""
    import inspect

    from smartllm_local.cli.benchmark import run
    from smartllm_local.cli.options import MODEL_PARAMETERS, ModelOptions, model_options
    from smartllm_local.cli.plan import plan_command
    from smartllm_local.cli.speed import bench_command

    wanted = set(inspect.signature(ModelOptions).parameters)
    assert {p.name for p in MODEL_PARAMETERS} == wanted
    assert wanted <= set(inspect.signature(run).parameters)
    assert wanted - {"parallel"} <= set(inspect.signature(plan_command).parameters)
    bench = set(inspect.signature(bench_command).parameters)
    assert {"backend", "endpoint", "n_gpu_layers", "chat_template"} <= bench and "model_settings" not in bench
    with pytest.raises(ValueError, match="no model option modle"):
        model_options("modle")


def test_later_prompt_costs_reads_what_a_run_reused_per_stage():
    def task(decomposition, allocation=None):
        tokens = {"decomposition": dict(zip(("prompt", "reused"), decomposition))}
        if allocation:
            tokens["allocation"] = dict(zip(("prompt", "reused"), allocation))
        return {"id": "t", "tokens": tokens}

    # the first evaluates all; a task on its floor plan its instruction; a task on another its scene too;
    # a task that never reached allocation (a stage left at 0 prompt tokens) is not counted there
    results = [task((1000, 0), (800, 0)), task((1000, 980), (0, 0)), task((1100, 700), (900, 600))]
    costs = later_prompt_costs(results)
    assert costs["decomposition"] == {"first_prompt": 1000, "later_tasks": 2, "later_evaluated_mean": 210.0,
                                      "later_over_first_prompt_tokens": 0.21}
    assert costs["allocation"]["later_tasks"] == 1 and costs["allocation"]["later_evaluated_mean"] == 300.0
    assert "coalition" not in costs and later_prompt_costs(results[:1]) == {}
