"""The README's first command, as a newcomer runs it: the default model plans a benchmark task that does what
was asked (scored against the task's goals), with nothing but the install behind it."""

from __future__ import annotations

import json
import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

README = Path(__file__).parent.parent / "README.md"


def test_the_readmes_first_command_plans_what_was_asked(tmp_path):
    command = re.search(r"pip install \. && (smartllm-local plan [^\n]+)", README.read_text(encoding="utf-8"))
    assert command, "the README's first command installs, then plans"
    args = shlex.split(command.group(1))[1:]
    assert "--model" not in args, "it shows the default model"
    env = {k: v for k, v in os.environ.items() if k != "SMARTLLM_MODEL"}
    done = subprocess.run([sys.executable, "-m", "smartllm_local", *args], cwd=tmp_path, env=env,
                          capture_output=True, text=True, timeout=900)
    assert done.returncode == 0, done.stderr[-3000:]
    out = tmp_path / args[args.index("--out") + 1]
    result = json.loads((out / "result.json").read_text())
    assert result["metrics"]["SR"] == 1.0 and result["metrics"]["GCR"] == 1.0, result["metrics"]
    assert json.loads((out / "decomposition" / "timings.json").read_text())["chat_template"] == "off"
    assert re.search(r"\bSR\s+1\.00\b", done.stdout), done.stdout[-2000:]
