"""The runs a report compares, read from their folders: run.json and results.jsonl, nothing else.

A folder is one run (``benchmark run --out DIR``) or one run per seed (``--seeds``:
``DIR/seed-<s>/``), which the report treats as one row with a spread.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from ..benchmark.results import Line, read_results
from ..benchmark.run_store import RESULTS, RUN_FILE
from ..errors import UserError

# The settings that make a run a variant of SMART-LLM (ablations and this project's switches), as labels.
_VARIANTS = (
    ("no_comments", "no comments"), ("no_summary", "no summary"), ("no_coalition", "no coalition"),
    ("free_allocation", "free allocation"), ("no_world_check", "no world check"), ("no_grammar", "no grammar"),
    ("free_teams", "free teams"), ("no_loop_guard", "no loop guard"), ("no_token_alignment", "no token alignment"),
    ("no_drafts", "no drafts"),
)
ABLATIONS = ("no_comments", "no_summary", "no_coalition")


@dataclass
class Run:
    """One row of the report: a run folder, or the per-seed runs of one ``--seeds`` folder."""

    folder: Path
    manifests: list[dict[str, Any]]
    seeds: list[list[Line]] = field(default_factory=list)  # per seed, its results lines

    @property
    def arguments(self) -> Mapping[str, Any]:
        return self.manifests[0].get("identity", {}).get("arguments", {})

    def _given(self, key: str) -> bool:
        """Whether a run had the variant ``key``: the summary from what the run planned with (its default
        depends on the model), every other one from the arguments it was given."""
        if key == "no_summary":
            prompts = self.manifests[0].get("identity", {}).get("settings", {}).get("prompts", {})
            if "summary" in prompts:
                return prompts["summary"] is False and self.method not in ("reference",)
        return bool(self.arguments.get(key))

    @property
    def method(self) -> str:
        return str(self.arguments.get("method") or "smartllm")

    @property
    def model(self) -> str:
        """The model file's name without its extension; "-" for a method that uses none."""
        name = self.manifests[0].get("identity", {}).get("model", {}).get("name")
        if not name or self.method == "reference":
            return "-"
        return name.removesuffix(".gguf")

    @property
    def variant(self) -> str:
        """The switches that set this run apart from the default SMART-LLM ("" for none)."""
        tags = [label for key, label in _VARIANTS if self._given(key)]
        chat = self.arguments.get("chat_template")
        if chat in ("on", "none"):  # set by hand: auto is the default
            tags.append(f"chat template {chat}")
        temperature = self.arguments.get("temperature") or 0
        if temperature:
            tags.append(f"T={temperature:g}")
        return ", ".join(tags)

    @property
    def ablation(self) -> str:
        """The paper's Table III row name: which parts of the prompts were left out."""
        left_out = [label for key, label in _VARIANTS if key in ABLATIONS and self._given(key)]
        return ", ".join(left_out) if left_out else "full"

    @property
    def label(self) -> str:
        parts = [self.method] + ([self.model] if self.model != "-" else [])
        return " · ".join(parts) + (f" ({self.variant})" if self.variant else "")

    @property
    def lines(self) -> list[Line]:
        """Every seed's lines together."""
        return [line for lines in self.seeds for line in lines]

    @property
    def task_ids(self) -> frozenset[str]:
        return frozenset(line["id"] for line in self.seeds[0]) if self.seeds else frozenset()

    @property
    def run_folders(self) -> list[Path]:
        """The folders of its runs: the folder itself, or one per seed."""
        if (self.folder / RUN_FILE).is_file():
            return [self.folder]
        return sorted((p for p in self.folder.glob("seed-*") if (p / RUN_FILE).is_file()),
                      key=lambda p: (len(p.name), p.name))

    def restricted(self, ids: frozenset[str]) -> Run:
        """The same run with only the lines of tasks ``ids``."""
        return replace(self, seeds=[[line for line in lines if line["id"] in ids] for lines in self.seeds])

    def parts(self) -> list[tuple[str, Run]]:
        """The task sets a table gives this run's rows for, labelled: a run of one half (``--split``) is that
        half; a run of every task whose run.json keeps the split is its test half (the feasible tasks the
        split puts there, and every infeasible one), then all; a run without a split is all."""
        half = self.arguments.get("split")
        if half:
            return [(f"{half} half", self)]
        test = frozenset(self.manifests[0].get("split", {}).get("test", ()))
        if not test & {line["id"] for line in self.lines if line["feasible"]}:
            return [("all", self)]
        infeasible = frozenset(line["id"] for line in self.lines if not line["feasible"])
        return [("test half", self.restricted(test | infeasible)), ("all", self)]


def load_run(folder: str | Path) -> Run:
    """Read a run folder (or a ``--seeds`` folder of them).

    Raises:
        UserError: the folder is missing, holds no run, or a run in it cannot be read.
    """
    folder = Path(folder)
    hint = "give the --out folder of a `smartllm-local benchmark run`"
    if not folder.is_dir():
        raise UserError(f"{folder} is not a folder: {hint}")
    if (folder / RUN_FILE).is_file():
        parts = [folder]
    else:
        parts = sorted((p for p in folder.glob("seed-*") if (p / RUN_FILE).is_file()),
                       key=lambda p: (len(p.name), p.name))
        if not parts:
            raise UserError(f"{folder} holds no benchmark run (no {RUN_FILE}, no seed-*/{RUN_FILE}): {hint}")
    run = Run(folder, [])
    for part in parts:
        try:
            manifest = json.loads((part / RUN_FILE).read_text(encoding="utf-8"))
            lines = read_results(part / RESULTS) if (part / RESULTS).is_file() else {}
        except (OSError, ValueError) as exc:
            raise UserError(f"cannot read the run in {part}: {exc}") from exc
        if not isinstance(manifest, dict):
            raise UserError(f"{part / RUN_FILE} is not a run description (a JSON object): {hint}")
        if not lines:
            raise UserError(f"{part} has no scored task yet ({RESULTS} is missing or empty): finish or resume "
                            "the run first")
        run.manifests.append(manifest)
        run.seeds.append(list(lines.values()))
    return run
