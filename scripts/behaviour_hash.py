"""A hash per planned task of everything the planner decided, to prove a refactoring changed no behaviour.

Plans a fixed set of tasks through the CLI (``benchmark run``) with the code under ``--code`` first on the
path, and prints one line per task: its run, its id and a hash of its prompts, grammars, raw outputs, plans
and results (timings and anything else that varies from run to run left out). Run it on the code before a
change and after; the lines must be the same::

    python scripts/behaviour_hash.py --code /path/to/old/checkout --work /tmp/before > before.txt
    python scripts/behaviour_hash.py --code . --work /tmp/after > after.txt
    diff before.txt after.txt

The runs: household tasks with the tests' SmolLM2 (all three stages, and the decomposition with robots by
the rule) and with Qwen2.5-Coder-0.5B, two candidates (written in llama.cpp lanes), sampled SmolLM2, patrol
tasks, free generation (no grammar), a task through ``llama_cpp.server`` on loopback, and the transformers
backend. Each keeps no prefix states (``--prefix-cache off``), so no run depends on an earlier one.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import signal
import socket
import subprocess
import sys
import time
import urllib.request
from pathlib import Path

#: (name, the run's own options, its tasks), the most different first. Every run has a context of 3,072 tokens
#: (fewer examples, smaller output budgets) and one thread, so that the 15 tasks plan on two busy cores.
RUNS: list[tuple[str, list[str], list[str]]] = [
    ("transformers", ["--model", "smollm2", "--method", "decomp-rule", "--backend", "transformers"], ["bedroom-02"]),
    ("server", ["--model", "smollm2", "--method", "decomp-rule", "--backend", "server"], ["kitchen-01"]),
    ("qwen0.5b", ["--model", "qwen2.5-coder-0.5b", "--method", "decomp-rule"], ["living-01", "kitchen-01"]),
    ("patrol", ["--model", "smollm2", "--method", "decomp-rule", "--domain", "patrol"], ["patrol-01", "patrol-02"]),
    ("free", ["--model", "smollm2", "--method", "decomp-rule", "--no-grammar"], ["living-01"]),
    ("sampled", ["--model", "smollm2", "--method", "decomp-rule", "--temperature", "0.7", "--seed", "3"],
     ["kitchen-02"]),
    ("candidates-lanes", ["--model", "smollm2", "--method", "decomp-rule", "--candidates", "2"], ["kitchen-05"]),
    ("smollm2", ["--model", "smollm2"], ["living-01", "kitchen-01"]),
    ("smollm2-decomp", ["--model", "smollm2", "--method", "decomp-rule"],
     ["kitchen-02", "bedroom-01", "bedroom-02", "bathroom-01"]),
]

#: Keys of result.json, record.json and results.jsonl whose values are timings, not decisions.
TIMED = ("seconds", "tokens_per_second", "Speed")


def scrub(value):
    """``value`` without its timings."""
    if isinstance(value, dict):
        return {k: scrub(v) for k, v in value.items() if not any(t in k for t in TIMED)}
    if isinstance(value, list):
        return [scrub(v) for v in value]
    return value


def task_hash(folder: Path, line: dict) -> str:
    digest = hashlib.sha256(json.dumps(scrub(line), sort_keys=True).encode())
    for path in sorted(folder.rglob("*")):
        if not path.is_file() or path.name == "timings.json":
            continue
        digest.update(str(path.relative_to(folder)).encode())
        text = path.read_bytes()
        if path.suffix == ".json":
            text = json.dumps(scrub(json.loads(text)), sort_keys=True).encode()
        digest.update(text)
    return digest.hexdigest()[:16]


class LlamaCppServer:
    """``python -m llama_cpp.server`` serving SmolLM2 on a free loopback port (as tests/planner's server)."""

    def __init__(self, env: dict[str, str], log: Path, model: Path):
        with socket.socket() as probe:
            probe.bind(("127.0.0.1", 0))
            port = probe.getsockname()[1]
        self.url = f"http://127.0.0.1:{port}"
        self.process = subprocess.Popen(
            [sys.executable, "-m", "llama_cpp.server", "--model", str(model), "--n_ctx", "8192", "--n_threads", "1",
             "--logits_all", "False", "--host", "127.0.0.1", "--port", str(port)],
            stdout=open(log, "w"), stderr=subprocess.STDOUT, env=env, start_new_session=True)
        deadline = time.monotonic() + 120
        while True:
            try:
                urllib.request.urlopen(f"{self.url}/v1/models", timeout=2).read()
                return
            except OSError:
                if self.process.poll() is not None or time.monotonic() > deadline:
                    self.stop()
                    raise RuntimeError(f"llama_cpp.server did not start: {log.read_text()[-2000:]}") from None
                time.sleep(0.5)

    def stop(self) -> None:
        try:
            os.killpg(self.process.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
        self.process.wait(timeout=30)


def run(name: str, options: list[str], tasks: list[str], work: Path, env: dict[str, str]) -> list[str]:
    out = work / name
    args = [sys.executable, "-m", "smartllm_local", "benchmark", "run", "--out", str(out), "--restart",
            "--prefix-cache", "off", "--n-ctx", "3072", "--threads", "1", *options,
            *(a for t in tasks for a in ("--task", t))]
    server = None
    if name == "server":
        model = subprocess.run([sys.executable, "-c", "from smartllm_local.planner.models import resolve_gguf; "
                                "print(resolve_gguf('smollm2'))"], env=env, capture_output=True, text=True,
                               check=True).stdout.strip()
        server = LlamaCppServer(env, work / "server.log", Path(model))
        args += ["--endpoint", server.url]
    try:
        done = subprocess.run(args, env=env, capture_output=True, text=True)
    finally:
        if server is not None:
            server.stop()
    if done.returncode != 0:
        raise SystemExit(f"{name}: benchmark run failed:\n{done.stderr[-3000:]}")
    lines = {json.loads(s)["id"]: json.loads(s) for s in (out / "results.jsonl").read_text().splitlines()}
    return [f"{name} {task} {task_hash(out / task, lines[task])}" for task in tasks]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--code", type=Path, required=True, help="the checkout whose code plans")
    parser.add_argument("--work", type=Path, required=True, help="a folder for the runs")
    parser.add_argument("--only", action="append", help="only these runs (by name)")
    args = parser.parse_args()
    env = {**os.environ, "PYTHONPATH": str(args.code.resolve()), "OMP_WAIT_POLICY": "PASSIVE",
           "SMARTLLM_CANDIDATES": "1", "SMARTLLM_GOAL_CHECK": "false"}
    env.pop("SMARTLLM_MODEL", None)
    args.work.mkdir(parents=True, exist_ok=True)
    for name, options, tasks in RUNS:
        if args.only and name not in args.only:
            continue
        for line in run(name, options, tasks, args.work, env):
            print(line, flush=True)


if __name__ == "__main__":
    main()
