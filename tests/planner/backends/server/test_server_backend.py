"""Planning against a real model server on loopback: llama-cpp-python's ``python -m llama_cpp.server``
serving the embedded SmolLM2, driven through the CLI as a lab would drive its GPU box; and llama.cpp's own
``llama-server``, built from source, in the heavy suite (``python -m pytest -m heavy``).

A server that dies or stalls in the middle of a run costs the tasks it was serving an error, within the
timeout, and the run goes on to its end.
"""

from __future__ import annotations

import json
import os
import signal
import socket
import subprocess
import sys
import time
import urllib.request
from pathlib import Path

import pytest

from smartllm_local.domain import load_domain
from smartllm_local.plan_language import parse_plan
from smartllm_local.planner.backends.amx import amx_runs
from smartllm_local.planner.models import resolve_gguf
from tests.cli.test_cli_errors import cli, one_line_error
from tests.llama_server import llama_server

TASKS = ("kitchen-01", "living-01")


#: llama_cpp.server with its model loaded in plain buffers: it has no option for that (see amx_traps).
PLAIN_LLAMA_CPP_SERVER = """\
import runpy
import llama_cpp
from smartllm_local.planner.backends.amx import without_extra_buffers
with without_extra_buffers(llama_cpp, wanted=True):
    runpy.run_module("llama_cpp.server", run_name="__main__", alter_sys=True)
"""


def amx_traps(model: Path) -> bool:
    """Whether llama.cpp's AMX kernels trap on this machine for ``model`` (smartllm_local.planner.backends.amx):
    a server must then load it without llama.cpp's extra buffer types, as the in-process backend does."""
    import llama_cpp

    return not amx_runs(llama_cpp, model)


def llama_cpp_server(model: Path) -> list[str]:
    """The command that starts llama-cpp-python's server for ``model`` on this machine."""
    return [sys.executable, "-c", PLAIN_LLAMA_CPP_SERVER] if amx_traps(model) else [sys.executable, "-m",
                                                                                    "llama_cpp.server"]


class Server:
    """A server process on a free loopback port (``command`` with ``--host`` and ``--port`` added), ready
    once ``ready`` answers; its log says which requests it answered. By default llama_cpp.server. It runs in
    a process group of its own, which :meth:`stop` ends whole (vLLM's engine is a process of its own)."""

    def __init__(self, log: Path, threads: int = 1, command: list[str] | None = None, ready: str = "/v1/models",
                 env: dict[str, str] | None = None, start_limit: float = 120):
        with socket.socket() as probe:
            probe.bind(("127.0.0.1", 0))
            self.port = probe.getsockname()[1]
        self.url, self.log = f"http://127.0.0.1:{self.port}", log
        command = command or [*llama_cpp_server(resolve_gguf(None)), "--model", str(resolve_gguf(None)),
                              "--n_ctx", "8192", "--n_threads", str(threads), "--logits_all", "False"]
        self.process = subprocess.Popen([*command, "--host", "127.0.0.1", "--port", str(self.port)],
                                        stdout=open(log, "w"), stderr=subprocess.STDOUT,
                                        env={**os.environ, "PYTHONUNBUFFERED": "1", **(env or {})},
                                        start_new_session=True)
        deadline = time.monotonic() + start_limit
        while True:
            try:
                urllib.request.urlopen(f"{self.url}{ready}", timeout=2).read()
                return
            except OSError as exc:
                if self.process.poll() is not None or time.monotonic() > deadline:
                    self.stop()
                    raise RuntimeError(f"{command[0]} did not start: {log.read_text()[-2000:]}") from exc
                time.sleep(0.5)

    def answered(self, request: str = "POST /v1/completions") -> int:
        return self.log.read_text(errors="replace").count(request)

    def wait_for(self, count: int, request: str = "POST /v1/completions", limit: float = 120) -> None:
        deadline = time.monotonic() + limit
        while self.answered(request) < count:
            assert time.monotonic() < deadline and self.process.poll() is None, self.log.read_text()[-2000:]
            time.sleep(0.2)

    def stop(self) -> None:
        for sent in (signal.SIGCONT, signal.SIGKILL):
            try:
                os.killpg(self.process.pid, sent)
            except ProcessLookupError:
                break  # the group is gone (its leader was killed on purpose, and had no children)
        self.process.wait(timeout=30)


@pytest.fixture
def server(tmp_path):
    """A server of a test's own, which it may stop or kill."""
    running = Server(tmp_path / "server.log", threads=2)
    yield running
    running.stop()


@pytest.fixture(scope="module")
def shared_server(tmp_path_factory):
    """A server the tests that only plan through it share."""
    running = Server(tmp_path_factory.mktemp("server") / "server.log", threads=2)
    yield running
    running.stop()


def lines(folder: Path) -> dict[str, dict]:
    return {line["id"]: line for line in map(json.loads, (folder / "results.jsonl").read_text().splitlines())}


def test_a_task_decomposed_through_a_server_validates_and_executes(shared_server, tmp_path):
    """A decomposition written line by line through llama_cpp.server (robots by the rule) is a valid plan, which
    executes; every stage through two servers at once is in the heavy suite."""
    out = tmp_path / "run"
    run = cli("benchmark", "run", "--method", "decomp-rule", "--backend", "server", "--endpoint", shared_server.url,
              "--out", out, "--task", TASKS[0])
    assert run.returncode == 0, run.stderr
    assert shared_server.answered() > 0
    line = lines(out)[TASKS[0]]
    assert not line.get("error") and line["tokens"]["decomposition"]["generated"] > 0, line
    if not line["refused"]:
        parse_plan((out / TASKS[0] / "decomposed.py").read_text(), form="decomposed")
        assert line["Exe"] is not None


@pytest.mark.heavy
def test_two_workers_plan_over_two_servers_and_every_stage_validates(tmp_path):
    servers = [Server(tmp_path / f"server-{n}.log") for n in range(2)]  # one core each: they run side by side
    try:
        out = tmp_path / "run"
        args = ["benchmark", "run", "--backend", "server", "--endpoint", ",".join(s.url for s in servers),
                "--workers", "2", "--out", out, *(a for t in TASKS for a in ("--task", t))]
        run = cli(*args)
        assert run.returncode == 0, run.stderr
        assert all(s.answered() > 0 for s in servers)  # both endpoints planned
    finally:
        for s in servers:
            s.stop()
    catalogue = load_domain().catalogue
    for task, line in lines(out).items():
        assert not line.get("error"), line
        result = json.loads((out / task / "result.json").read_text())
        assert list(result["stages"]) == ["decomposition", "coalition", "allocation"]
        assert all(line["tokens"][stage]["generated"] > 0 for stage in ("decomposition", "coalition", "allocation"))
        plan = (out / task / "allocated.py").read_text()
        parse_plan(plan, form="allocated", skills=catalogue.skills, team_size=len(result["robots"]))
    assert set(lines(out)) == set(TASKS)
    manifest = json.loads((out / "run.json").read_text())
    assert (manifest["identity"]["arguments"]["backend"] == "server"
            and "workers" not in manifest["identity"]["arguments"])


def test_a_server_killed_mid_run_fails_its_tasks_with_a_clear_error_and_the_run_ends(server, tmp_path):
    out = tmp_path / "run"
    args = [sys.executable, "-m", "smartllm_local", "benchmark", "run", "--method", "decomp-rule", "--backend",
            "server", "--endpoint", server.url, "--out", str(out), *(a for t in TASKS for a in ("--task", t))]
    run = subprocess.Popen(args, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    server.wait_for(2)
    server.process.kill()
    stdout, stderr = run.communicate(timeout=120)
    assert run.returncode == 0, stderr
    results = lines(out)
    assert set(results) == set(TASKS)
    for line in results.values():
        assert line["error"].startswith("decomposition: the server at ") and "cannot be reached" in line["error"], line


def test_a_stalled_server_fails_the_task_within_the_timeout(server, tmp_path):
    out = tmp_path / "run"
    args = [sys.executable, "-m", "smartllm_local", "benchmark", "run", "--method", "decomp-rule", "--backend",
            "server", "--endpoint", server.url, "--server-timeout", "4", "--out", str(out), "--task", TASKS[0]]
    run = subprocess.Popen(args, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    server.wait_for(1, "POST /extras/tokenize")  # the planner has checked the server: its task is starting
    os.kill(server.process.pid, signal.SIGSTOP)
    stalled = time.monotonic()
    stdout, stderr = run.communicate(timeout=60)
    assert time.monotonic() - stalled < 30
    assert run.returncode == 0, stderr
    error = lines(out)[TASKS[0]]["error"]
    assert "gave no answer in 4 s" in error and "--server-timeout" in error, error


def test_ctrl_c_ends_a_run_whose_workers_wait_on_a_stalled_server_at_once(server, tmp_path):
    """Both workers wait on a server that stopped answering, with the default 300 s timeout: Ctrl-C ends
    the run in seconds, and no task is scored with the error the interruption caused."""
    out = tmp_path / "run"
    args = [sys.executable, "-m", "smartllm_local", "benchmark", "run", "--method", "decomp-rule", "--backend",
            "server", "--endpoint", server.url, "--workers", "2", "--out", str(out),
            *(a for t in TASKS for a in ("--task", t))]
    run = subprocess.Popen(args, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                           preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    server.wait_for(1)  # a completion answered: both workers are planning
    os.kill(server.process.pid, signal.SIGSTOP)
    time.sleep(1)
    run.send_signal(signal.SIGINT)
    interrupted = time.monotonic()
    _, stderr = run.communicate(timeout=120)
    assert time.monotonic() - interrupted < 15, stderr
    assert run.returncode == 130 and "interrupted: 0 of 2 tasks scored" in stderr, stderr
    assert "Traceback" not in stderr and not (out / "results.jsonl").exists()


def test_server_options_are_checked_before_anything_runs(tmp_path):
    with socket.socket() as probe:  # a port where nothing listens
        probe.bind(("127.0.0.1", 0))
        closed = probe.getsockname()[1]
    one_line_error(cli("plan", "x", "--floor-plan", "1", "--robots", "1", "--backend", "server"), "--endpoint")
    one_line_error(cli("plan", "x", "--floor-plan", "1", "--robots", "1", "--endpoint", "http://127.0.0.1:1"),
                   "--backend server")
    one_line_error(cli("benchmark", "run", "--out", tmp_path / "r", "--backend", "transformers", "--workers", "2"),
                   "--backend server")
    one_line_error(cli("plan", "x", "--floor-plan", "1", "--robots", "1", "--backend", "server", "--endpoint",
                       "ftp://host"), "not an http(s) URL")
    one_line_error(cli("plan", "x", "--floor-plan", "1", "--robots", "1", "--backend", "server", "--endpoint",
                       f"http://127.0.0.1:{closed}"), "cannot be reached", "is it running?")
    one_line_error(cli("plan", "x", "--floor-plan", "1", "--robots", "1", "--backend", "server", "--endpoint",
                       "http://127.0.0.1:1", "--server-timeout", "0"), "--server-timeout")


def test_a_vocabulary_that_is_not_the_served_models_is_refused(shared_server):
    gemma = resolve_gguf("gemma3-270m")
    one_line_error(cli("plan", "x", "--floor-plan", "1", "--robots", "1", "--backend", "server", "--endpoint",
                       shared_server.url, "--model", gemma), "tokenizes text differently", "--model")


def _llama_server(tmp_path: Path, *args: str) -> tuple[Server, Path]:
    """llama-server on the embedded SmolLM2, whose file is gone from this machine once the server has loaded
    it (as on a GPU box): the tokenizer and chat template are the server's own."""
    log, served = tmp_path / "llama-server.log", tmp_path / "served.gguf"
    served.symlink_to(resolve_gguf(None))
    plain = ["--no-repack"] if amx_traps(resolve_gguf(None)) else []  # the built server's AMX traps here too
    server = Server(log, command=[str(llama_server()), "-m", str(served), "-t", "2", *plain, *args], ready="/health")
    served.unlink()
    return server, log


@pytest.mark.heavy
def test_llama_server_plans_token_for_token_what_the_in_process_backend_plans(tmp_path):
    """Greedy plans through llama.cpp's own server (flash attention off, as in-process on the CPU) are the
    in-process backend's, stage for stage and token for token, prefix reuse and the loop guard included."""
    tasks = (*TASKS, "kitchen-02")
    task_args = [a for t in tasks for a in ("--task", t)]
    run = cli("benchmark", "run", "--out", tmp_path / "in-process", "--prefix-cache", "off", *task_args)
    assert run.returncode == 0, run.stderr
    server, _ = _llama_server(tmp_path, "-c", "8192", "-np", "1", "-fa", "off")
    try:
        run = cli("benchmark", "run", "--backend", "server", "--endpoint", server.url, "--out", tmp_path / "server",
                  *task_args)
        assert run.returncode == 0, run.stderr
    finally:
        server.stop()
    local, remote = lines(tmp_path / "in-process"), lines(tmp_path / "server")
    assert set(remote) == set(tasks) and not any(line.get("error") for line in remote.values())
    for task in tasks:
        stages = json.loads((tmp_path / "server" / task / "result.json").read_text())["stages"]
        assert list(stages) == ["decomposition", "coalition", "allocation"]
        assert stages["decomposition"]["chat_template"] == "applied"  # SmolLM2's template, from /props
        for stage in stages:
            ours, theirs = ((tmp_path / run / task / stage / "raw_output.txt").read_text()
                            for run in ("in-process", "server"))
            assert theirs == ours, (task, stage)
            counts = [{k: line[task]["tokens"][stage][k] for k in ("prompt", "generated")} for line in (local, remote)]
            assert counts[0] == counts[1], (task, stage)
    shared = json.loads((tmp_path / "server" / "kitchen-02" / "decomposition" / "timings.json").read_text())
    assert remote["kitchen-02"]["tokens"]["decomposition"]["reused"] >= shared["shared_tokens"] > 1000  # the examples


@pytest.mark.heavy
def test_bench_measures_through_a_server_what_it_measures_in_process(tmp_path):
    """``bench --backend server``: the prompt path, decoding and prefix reuse through llama-server's slot (no engine
    of its own to time against: ``prefill_over_engine`` is null), with the figures' shape an in-process run has."""
    server, _ = _llama_server(tmp_path, "-c", "8192", "-np", "1")
    try:
        out = tmp_path / "bench.json"
        run = cli("bench", "--backend", "server", "--endpoint", server.url, "--sample", "2", "--no-benchmark",
                  "--no-executor", "--out", out)
        assert run.returncode == 0, run.stderr
    finally:
        server.stop()
    report = json.loads(out.read_text())
    served = report["models"]["served"]
    assert served["prefill"]["prefill_over_engine"] is None and served["prefill"]["first"]["seconds"] > 0
    # The time to the first token includes the request that evaluates the prompt's last batch in the slot; a
    # slot holds one context, so after another prompt (the "kept" measure's) it holds only what the two share.
    assert served["prefill"]["kept"]["reused"] < 16 < served["prefill"]["prompt_tokens"]
    assert served["decode"]["free"]["generated_tokens"] > 0 < served["decode"]["constrained"]["tokens_per_s"]
    assert served["prefix"]["stages"]["decomposition"]["later_evaluated_mean"] is not None
    assert report["machine"]["backend"] == "server" and report["executor"] is None


@pytest.mark.heavy
def test_two_workers_plan_on_two_llama_server_slots(tmp_path):
    server, log = _llama_server(tmp_path, "-c", "8192", "-np", "2")
    try:
        out = tmp_path / "run"
        run = cli("benchmark", "run", "--method", "decomp-rule", "--backend", "server", "--endpoint", server.url,
                  "--workers", "2", "--out", out, *(a for t in TASKS for a in ("--task", t)))
        assert run.returncode == 0, run.stderr
    finally:
        server.stop()
    results = lines(out)
    assert set(results) == set(TASKS) and not any(line.get("error") for line in results.values())
    served = log.read_text()
    assert "launch_slot_: id  0" in served and "launch_slot_: id  1" in served  # both slots planned
