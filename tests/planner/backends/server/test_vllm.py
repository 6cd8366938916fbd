"""Planning against a real vLLM on loopback (the CPU build, serving the embedded SmolLM2 as a checkpoint), and
vLLM's grammar engine reading every kind of grammar the planner sends it as the planner means it.

vLLM computes other logits than llama.cpp (another engine, float32 weights dequantized from the GGUF), so its
plans are not compared with in-process ones; every one of them must validate, as any backend's must.
"""

from __future__ import annotations

import json
import os
import random
import shutil
import signal
import subprocess
import sys
import time

import pytest

from smartllm_local.domain import load_domain
from smartllm_local.plan_language import parse_plan
from smartllm_local.planner.backends.server.backend import connect
from tests.cli.test_cli_errors import cli, one_line_error
from tests.planner.backends.server.test_server_backend import Server, lines
from tests.vllm_server import ENVIRONMENT, SERVE, smollm2_checkpoint, vllm_python

TASKS = ("kitchen-01", "living-01")
pytestmark = pytest.mark.heavy  # installs vLLM into an environment of its own (minutes on a clean clone)


@pytest.fixture(scope="module")
def vllm(tmp_path_factory):
    python, checkpoint = vllm_python(), smollm2_checkpoint()
    log = tmp_path_factory.mktemp("vllm") / "vllm.log"
    server = Server(log, command=[str(python), *SERVE, "--model", str(checkpoint)], env=ENVIRONMENT,
                    start_limit=300)
    yield server
    server.stop()


def test_two_workers_plan_through_vllm_and_every_stage_validates(vllm, tmp_path):
    """Two workers share one vLLM, which batches their requests; the served checkpoint's folder is on this
    machine, so its tokenizer and chat template are read from it (no --model). Every stage of every task is
    planned, and each allocation finds the context its coalition left in vLLM's prefix cache."""
    out = tmp_path / "run"
    run = cli("benchmark", "run", "--backend", "server", "--endpoint", vllm.url, "--workers", "2", "--out", out,
              *(a for t in TASKS for a in ("--task", t)))
    assert run.returncode == 0, run.stderr
    catalogue = load_domain().catalogue
    results = lines(out)
    assert set(results) == set(TASKS) and not all(line["refused"] for line in results.values())
    for task, line in results.items():
        assert not line.get("error"), line
        result = json.loads((out / task / "result.json").read_text())
        assert result["stages"]["decomposition"]["chat_template"] == "applied"  # SmolLM2's, from the folder
        if line["refused"]:
            continue
        assert list(result["stages"]) == ["decomposition", "coalition", "allocation"]
        assert all(line["tokens"][stage]["generated"] > 0 for stage in result["stages"])
        plan = (out / task / "allocated.py").read_text()
        parse_plan(plan, form="allocated", skills=catalogue.skills, team_size=len(result["robots"]))
        # vLLM says which prompt tokens came from its cache, which keeps whole blocks of 32 tokens
        allocation = line["tokens"]["allocation"]
        assert allocation["prompt"] - 64 < allocation["reused"] < allocation["prompt"]


def test_the_vocabulary_is_checked_against_the_one_vllm_serves(vllm, tmp_path):
    """A copy of the checkpoint's tokenizer files alone (as on a planner's machine apart from the GPU box), or
    the served model's GGUF, is the served vocabulary; another model's is refused before anything runs."""
    copy = tmp_path / "tokenizer"
    copy.mkdir()
    for name in ("tokenizer.json", "tokenizer_config.json", "chat_template.jinja"):
        shutil.copy(smollm2_checkpoint() / name, copy / name)
    for model in (str(copy), "smollm2"):
        (backend,) = connect([vllm.url], model)
        assert backend.dialect.name == "vLLM" and backend.n_ctx == 8192  # vLLM's max_model_len
        assert backend.chat_template and backend.chat_template.startswith("{% for message in messages %}")
        backend.close()
    one_line_error(cli("plan", "x", "--floor-plan", "1", "--robots", "1", "--backend", "server", "--endpoint",
                       vllm.url, "--model", "gemma3-270m"), "tokenizes text differently", "--model")


def test_a_stalled_vllm_fails_the_task_within_the_timeout_and_the_run_ends(vllm, tmp_path):
    """vLLM stops answering (its processes stopped) in the middle of a decomposition: the task fails with the
    timeout's error, and the run ends normally. Last of the tests that use the server, which goes on after."""
    out = tmp_path / "run"
    args = [sys.executable, "-m", "smartllm_local", "benchmark", "run", "--method", "decomp-rule", "--backend",
            "server", "--endpoint", vllm.url, "--server-timeout", "4", "--out", str(out), "--task", TASKS[0]]
    before = vllm.answered()
    run = subprocess.Popen(args, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    vllm.wait_for(before + 2)  # the prompt and a first stretch of a line: the decomposition is under way
    os.killpg(vllm.process.pid, signal.SIGSTOP)
    stalled = time.monotonic()
    try:
        _, stderr = run.communicate(timeout=60)
    finally:
        os.killpg(vllm.process.pid, signal.SIGCONT)
    assert time.monotonic() - stalled < 30
    assert run.returncode == 0, stderr
    error = lines(out)[TASKS[0]]["error"]
    assert error.startswith("decomposition: the server at ") and "gave no answer in 4 s" in error, error


def test_vllms_grammar_engine_reads_every_grammar_the_planner_sends_as_the_planner_means_it():
    """XGrammar (vLLM's grammar engine) is given the grammar of what may follow every third cut of every line
    adversarial writers write through three tasks' stages, with the rest of the line and texts that almost
    follow: it admits exactly what the planner's own grammar admits."""
    from tests.planner.constraints import test_guarantees as guarantees

    rng = random.Random(11)
    cases = []
    for grammar, line in guarantees.collect_lines(rng, ["kitchen-01", "living-01", "bathroom-01"]):
        for cut in range(0, len(line), 3):
            after, rest = grammar.after(line[:cut]), line[cut:]
            near = [rest[:-1], rest + "x", rest[:-1] + "_\n", rest.replace("'", '"', 1), rest.upper()]
            texts = [rest, *(t for t in near if t != rest)]
            cases.append({"gbnf": after.to_gbnf(), "texts": texts, "admits": [after.matches(t) for t in texts]})
    assert len(cases) > 1000 and any(not a for case in cases for a in case["admits"])
    check = (
        "import json, sys\n"
        "import xgrammar\n"
        "from xgrammar.testing import _is_grammar_accept_string as admits\n"
        "for case in json.load(sys.stdin):\n"
        "    grammar = xgrammar.Grammar.from_ebnf(case['gbnf'])\n"
        "    for text, want in zip(case['texts'], case['admits']):\n"
        "        if admits(grammar, text) != want:\n"
        "            print(json.dumps([case['gbnf'], text, want]))\n"
    )
    done = subprocess.run([str(vllm_python()), "-c", check], input=json.dumps(cases), capture_output=True,
                          text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-3000:]
    assert done.stdout == "", done.stdout[:3000]
