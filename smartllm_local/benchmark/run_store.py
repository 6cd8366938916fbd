"""A benchmark run's folder, written so that a run killed at any moment resumes where it stopped.

- ``run.json``: what the run is (arguments, model digest, versions, task files). A
  folder is resumed only by the same run; anything else is a clear error unless
  the user asks to start over.
- ``<task>/<stage>/record.json``: each finished stage of each task, written
  atomically the moment it finishes. A resumed run puts the stages back and
  goes on from the first one missing; a damaged record is run again, never trusted.
- ``results.jsonl``: one line per scored task, appended (and flushed to disk) the
  moment it is scored. A line cut short by a kill is dropped on resume.
"""

from __future__ import annotations

import json
import os
import shutil
from collections.abc import Iterator, Mapping
from pathlib import Path
from typing import Any

from ..errors import UserError
from ..files import json_text, write_atomic
from ..planner.result import StageRecord
from .results import parse_results

RUN_FILE = "run.json"
RESULTS = "results.jsonl"
RECORD = "record.json"
STAGES = ("decomposition", "coalition", "allocation")
# What a run writes in a task's folder (removed when the user starts over; nothing else is).
TASK_FILES = ("decomposed.py", "coalition.txt", "allocated.py", "result.json", "trace.json")


class RunStore:
    """The run folder ``out``, opened for the run ``manifest`` describes."""

    def __init__(self, out: str | Path, manifest: Mapping[str, Any], *, restart: bool = False):
        self.out = Path(out)
        path = self.out / RUN_FILE
        if path.is_file() and not restart:
            try:
                before = json.loads(path.read_text())
            except (OSError, ValueError) as exc:
                raise UserError(f"{path} cannot be read ({exc}); start over with --restart") from exc
            changed = differences(before.get("identity", {}), manifest.get("identity", {}))
            if changed:
                raise UserError(
                    f"{self.out} holds a run with other settings ({'; '.join(changed[:4])}); give another "
                    f"--out, or --restart to discard that run and start over")
            manifest = {**manifest, "started": before.get("started"),
                        "resumed": [*before.get("resumed", []), manifest.get("started")]}
        elif restart:
            self.clear()
        elif self.out.is_dir() and (self.out / RESULTS).exists():
            raise UserError(f"{self.out} holds results without a {RUN_FILE} (a run of an older version); "
                            "give another --out, or --restart to start over")
        write_atomic(path, json_text(dict(manifest)))

    def clear(self) -> None:
        """Remove what a run writes here (run.json, results, task folders' artifacts); nothing else."""
        for name in (RUN_FILE, RESULTS, "summary.txt"):
            (self.out / name).unlink(missing_ok=True)
        if not self.out.is_dir():
            return
        for folder in self.out.iterdir():
            if not folder.is_dir() or folder.is_symlink():
                continue
            if (folder / "result.json").is_file() or any((folder / s / RECORD).is_file() for s in STAGES):
                for stage in STAGES:
                    shutil.rmtree(folder / stage, ignore_errors=True)
                for name in TASK_FILES:
                    (folder / name).unlink(missing_ok=True)
                if not any(folder.iterdir()):
                    folder.rmdir()

    # ------------------------------------------------------------ stages

    def save_stage(self, task_id: str, record: StageRecord) -> None:
        write_atomic(self.out / task_id / record.stage / RECORD, json_text(record.saved()))

    def saved_stages(self, task_id: str) -> Iterator[StageRecord]:
        """The task's finished stages in order, up to the first missing or damaged one."""
        for stage in STAGES:
            path = self.out / task_id / stage / RECORD
            if not path.is_file():
                continue  # a stage the run skips (--no-coalition) or has not reached
            try:
                record = StageRecord.restored(json.loads(path.read_text()))
            except (OSError, ValueError, TypeError):
                return
            if record.stage != stage:
                return
            yield record

    def forget_stages(self, task_id: str, first: str) -> None:
        """Drop the saved stages from ``first`` on (one was damaged: they are run again)."""
        for stage in STAGES[STAGES.index(first):]:
            (self.out / task_id / stage / RECORD).unlink(missing_ok=True)

    # ----------------------------------------------------------- results

    def results(self) -> dict[str, dict[str, Any]]:
        """The scored tasks' lines by task id. A last line cut short by a kill is removed from the file."""
        path = self.out / RESULTS
        if not path.is_file():
            return {}
        text = path.read_text(encoding="utf-8")
        found, good = parse_results(text)
        if good < len(text):
            write_atomic(path, text[:good])
        return found

    def append_result(self, line: Mapping[str, Any]) -> None:
        """Append one scored task's line, on disk before this returns."""
        self.out.mkdir(parents=True, exist_ok=True)
        with open(self.out / RESULTS, "a", encoding="utf-8") as handle:
            handle.write(json.dumps(line) + "\n")
            handle.flush()
            os.fsync(handle.fileno())


def differences(before: Mapping[str, Any], now: Mapping[str, Any], prefix: str = "") -> list[str]:
    """What differs between two manifests' identities, as 'key: old -> new'."""
    changed = []
    for key in sorted(set(before) | set(now)):
        old, new = before.get(key), now.get(key)
        if isinstance(old, Mapping) and isinstance(new, Mapping):
            changed += differences(old, new, f"{prefix}{key}.")
        elif old != new:
            changed.append(f"{prefix}{key}: {_short(old)} -> {_short(new)}")
    return changed


def _short(value: Any) -> str:
    text = json.dumps(value)
    return text if len(text) <= 40 else text[:37] + "..."
