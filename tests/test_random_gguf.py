"""scripts/random_gguf.py: random-weight Llama-2 shapes for measuring where no model can be downloaded. On the CPU
the tiny shape is written, loaded by llama.cpp and planned with; the 7B and 70B shapes are checked by their size."""

from __future__ import annotations

import json
import lzma
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from smartllm_local.benchmark.results import read_results
from smartllm_local.domain import load_domain
from smartllm_local.plan_language import parse_plan
from smartllm_local.planner.backends import load_backend
from smartllm_local.planner.backends.llamacpp import LlamaCppBackend
from smartllm_local.planner.pipeline import Planner, PlannerConfig

SCRIPTS = Path(__file__).resolve().parent.parent / "scripts"
sys.path.insert(0, str(SCRIPTS))
import random_gguf  # noqa: E402


def test_the_shapes_have_llama_2s_sizes():
    """As written on the lent H200: 3.8 GB (7B) and 38.8 GB (70B) in Q4_0."""
    def size(shape):
        return sum(rows * columns // 32 * 18 if rows > 1 else 4 * columns
                   for _, rows, columns in random_gguf.tensors(random_gguf.SHAPES[shape], 32000))
    assert 3.7e9 < size("7b") < 3.9e9 and 38.5e9 < size("70b") < 39.0e9


def test_a_tiny_shape_loads_in_llama_cpp_and_plans_a_valid_plan(tmp_path):
    out = tmp_path / "tiny.gguf"
    done = subprocess.run([sys.executable, str(SCRIPTS / "random_gguf.py"), "--shape", "tiny", "--out", str(out)],
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert not out.with_name(out.name + ".partial").exists()
    backend = load_backend("llamacpp", str(out), n_ctx=4096, prefix_cache="off")
    try:
        assert backend.llm.metadata["llama.block_count"] == "2" and backend.n_vocab == 32000
        vocab = tmp_path / "vocab.gguf"
        vocab.write_bytes(lzma.decompress(random_gguf.VOCAB.read_bytes()))
        llama2 = LlamaCppBackend(vocab, n_ctx=512, vocab_only=True)
        text = "# SubTask 1: put the apple in the fridge (skills: GoToObject)\n"
        assert backend.tokenize(text, bos=True) == llama2.tokenize(text, bos=True), "Llama-2's own tokenizer"
        llama2.close()
        result = Planner(backend, load_domain().catalogue, PlannerConfig()).plan(
            "Put the apple in the fridge.", 6, [1, 2])
        assert result.refusal is not None or parse_plan(result.allocated, form="allocated")
    finally:
        backend.close()


def test_bad_output_is_refused_with_status_2(tmp_path):
    done = subprocess.run([sys.executable, str(SCRIPTS / "random_gguf.py"), "--shape", "tiny", "--out",
                           str(tmp_path / "missing" / "x.gguf")], capture_output=True, text=True, timeout=60)
    assert done.returncode == 2 and "--out" in done.stderr


def test_the_gpu_check_runs_on_the_cpu_with_a_tiny_shape(tmp_path):
    """scripts/gpu_check.sh as a GPU machine runs it, with the tiny shape and the installed llama.cpp: the plan,
    the numpy-first load and the table."""
    env = {**os.environ, "PYTHON": sys.executable, "OUT": str(tmp_path), "GGUF_DIR": str(tmp_path),
           "GPU_CHECK_SECONDS": "100000"}
    done = subprocess.run(["bash", str(SCRIPTS / "gpu_check.sh"), "run", "--cpu"], env=env, capture_output=True,
                          text=True, timeout=1200)
    assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-2000:]
    row = next(line for line in done.stdout.splitlines() if line.startswith("| tiny |"))
    assert re.match(r"\| tiny \| \d+ \| \d+\.\d \(\d+\.\d, [\d,]+\) \|", row), row
    assert (tmp_path / "tiny" / "decomposition" / "timings.json").is_file()
    # every import-order variant loads with this build, the project's own load with numpy first among them
    variants = dict(re.findall(r"^  ([\w'+=,-]+): exit (\d+)$", done.stdout, re.M))
    assert len(variants) == 8 and set(variants.values()) == {"0"}, variants
    # bench ran with plan's model options: its prompt path against llama.cpp alone, in the table
    models = json.loads((tmp_path / "bench-tiny.json").read_text())["models"]
    prefill = models[str(tmp_path / "random-llama-2-tiny.gguf")]["prefill"]
    assert prefill["engine_s"] > 0 and prefill["first"]["seconds"] > 0 and prefill["prompt_tokens"] > 1000
    assert prefill["prefill_over_engine"] == round(prefill["first"]["seconds"] / prefill["engine_s"], 3)
    assert f"({prefill['prefill_over_engine']:.2f})" in row
    # the benchmark runs with K tasks at once: K = 1 and 2 on two tasks, tasks per minute from their wall time
    rates = re.findall(r"^\| (\d+) \| (\d+) \| (\d+) \| (\d+\.\d|inf) \| \d+ \|$", done.stdout, re.M)
    assert [(k, tasks) for k, tasks, _, _ in rates] == [("1", "2"), ("2", "2")], done.stdout[-2000:]
    for k, _, wall, rate in rates:
        lines = (tmp_path / f"parallel-{k}" / "results.jsonl").read_text().splitlines()
        assert [json.loads(line)["id"] for line in lines] == ["kitchen-01", "kitchen-02"]
        assert rate == "inf" if wall == "0" else float(rate) == round(60 * 2 / int(wall), 1)


@pytest.mark.heavy
def test_a_random_weight_model_sampled_at_temperature_1_plans_only_actions_that_succeed(tmp_path):
    """Exe 1.00 for every model, proven with the least likely one: a random-weight tiny shape (greedy, it refuses
    every task at the first token, so it is sampled at temperature 1, seeds 0, 1 and 2) plans every household
    task, and in every category every action of every plan it executes succeeds, wherever the world check met
    no dead end (there it falls back to unchecked choices; none is expected, and they are counted). The
    summary's Exe is lower: it counts a refused feasible task as 0, and this model refuses most. About 12
    minutes on 2 shared cores."""
    model = tmp_path / "tiny.gguf"
    random_gguf.write(random_gguf.SHAPES["tiny"], model)
    run = tmp_path / "run"
    done = subprocess.run([sys.executable, "-m", "smartllm_local", "benchmark", "run", "--model", str(model),
                           "--n-ctx", "4096", "--temperature", "1", "--seeds", "3", "--prefix-cache", "off",
                           "--out", str(run)], capture_output=True, text=True, timeout=3600,
                          env={**os.environ, "OMP_WAIT_POLICY": "PASSIVE"})
    assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-2000:]
    executed: dict[str, list[float]] = {}
    dead_ends = 0
    for seed in (0, 1, 2):
        folder = run / f"seed-{seed}"
        for line in read_results(folder / "results.jsonl").values():
            if line["feasible"] and not line["refused"] and not line.get("error") and "ticks" in line:
                found = sum(json.loads(path.read_text())["world_check"]["dead_ends"]
                            for path in (folder / line["id"]).glob("*/timings.json"))
                dead_ends += found
                if not found:
                    executed.setdefault(line["category"], []).append(line["Exe"])
    assert set(executed) == {"elemental", "simple", "compound", "complex"}, executed
    assert sum(len(v) for v in executed.values()) >= 30 and dead_ends <= 3, (executed, dead_ends)
    assert all(exe == 1.0 for values in executed.values() for exe in values), executed
