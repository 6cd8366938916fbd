"""Planning beside another busy process: ``plan`` alone, then several ``plan`` processes at once.

Users plan on a laptop, on CI runners with parallel jobs, beside a server; two processes that share 2 cores
should each take about twice their time alone, no more (see :mod:`smartllm_local.planner.backends.cores`).
Each process plans the same task from the same prefix store, which a first, untimed plan fills, so every timed
process does the same work a user's second ``plan`` does.
"""

from __future__ import annotations

import subprocess
import sys
import tempfile
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from ..errors import SmartLLMError


def _plans(command: list[str], copies: int) -> list[float]:
    """The wall time of each of ``copies`` processes of ``command`` started together."""
    logs = [tempfile.TemporaryFile(mode="w+") for _ in range(copies)]  # a pipe could fill and stall a process
    started = time.perf_counter()
    running = [subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=log) for log in logs]
    seconds = [0.0] * copies
    while not all(seconds):
        for i, process in enumerate(running):
            if not seconds[i] and process.poll() is not None:
                seconds[i] = time.perf_counter() - started
        time.sleep(0.05)
    for process, log in zip(running, logs):
        log.seek(0)
        error = log.read().strip()[-500:]
        log.close()
        if process.returncode not in (0, 1):  # 1: a plan that failed or was refused, still planned
            raise SmartLLMError(f"a plan process failed while measuring core sharing: {error}")
    return seconds


def core_sharing(options: Sequence[str], task: str, *, copies: int = 2) -> dict[str, Any]:
    """``plan --task task`` with the model ``options`` alone, then ``copies`` at once (seconds, each timed from
    the start together), from a prefix store the first, untimed run fills; and the slowest over the one alone."""
    with tempfile.TemporaryDirectory(prefix="smartllm-sharing-") as folder:
        command = [sys.executable, "-m", "smartllm_local", "plan", "--task", task, *options,
                   "--prefix-cache", str(Path(folder) / "states")]
        first = _plans(command, 1)[0]
        alone = _plans(command, 1)[0]
        together = _plans(command, copies)
    return {"task": task, "first_s": round(first, 2), "alone_s": round(alone, 2),
            "together_s": [round(s, 2) for s in together], "copies": copies,
            "together_over_alone": round(max(together) / alone, 2)}
