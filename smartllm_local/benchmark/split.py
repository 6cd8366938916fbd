"""A benchmark's fixed development/test split, read from ``benchmark/split.toml`` in its domain.

Prompts, examples, selectors and their settings are chosen on the development half; the test half is
what is reported beside the whole, so a figure on it was not tuned on its own tasks. Each feasible
task is in exactly one half, each category split as evenly as it can be; infeasible tasks are in both
halves and are not listed. The file's ``[drawn]`` table is what the seed drew, once (:func:`draw`
reproduces it); ``[assigned]`` holds tasks added later, one line each, assigned by hand. A feasible
task in neither table is a problem that ``benchmark check`` reports and ``benchmark run --split``
refuses, so adding a task forces a decision about its half.
"""

from __future__ import annotations

import random
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib

from ..domain import Domain
from ..errors import UserError
from .tasks import CATEGORIES, Task

HALVES = ("dev", "test")
HALF_NAMES = {"dev": "development", "test": "test"}
TABLES = ("drawn", "assigned")


@dataclass(frozen=True)
class Split:
    """A domain's split: what the seed drew, and the tasks assigned by hand since."""

    path: Path
    seed: int
    drawn: Mapping[str, str]  # task id -> "dev" | "test"
    assigned: Mapping[str, str]

    @property
    def halves(self) -> dict[str, str]:
        return {**self.drawn, **self.assigned}

    def half(self, name: str) -> frozenset[str]:
        """The feasible task ids of one half."""
        return frozenset(task for task, half in self.halves.items() if half == name)

    def record(self) -> dict[str, Any]:
        """What a run folder's run.json keeps of it: the report reads the halves from there alone."""
        return {"file": str(self.path.resolve()), "seed": self.seed,
                **{name: sorted(self.half(name)) for name in HALVES}}

    def line_of(self, task_id: str) -> int:
        """The file's line that assigns ``task_id`` (1 when none does)."""
        pattern = re.compile(rf'^\s*"?{re.escape(task_id)}"?\s*=')
        lines = self.path.read_text(encoding="utf-8").splitlines()
        return next((k + 1 for k, line in enumerate(lines) if pattern.match(line)), 1)


def load_split(path: Path) -> Split:
    """Read a split file.

    Raises:
        UserError: the file cannot be read, is not TOML, or is not laid out as a split.
    """
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except OSError as exc:
        raise UserError(f"cannot read the split file {path}: {exc.strerror or exc}") from None
    except UnicodeDecodeError as exc:
        raise UserError(f"the split file {path} is not UTF-8 text ({exc.reason})") from None
    except tomllib.TOMLDecodeError as exc:
        raise UserError(f"{path}: not valid TOML: {exc}") from None
    problems = []
    known = {"seed", "how", *TABLES}
    problems += [f"unknown key {key!r}; a split file has {', '.join(sorted(known))}"
                 for key in sorted(set(data) - known)]
    seed = data.get("seed")
    if not isinstance(seed, int) or isinstance(seed, bool):
        problems.append("needs seed = N, the seed that drew [drawn]")
    tables: dict[str, dict[str, str]] = {}
    for name in TABLES:
        table = data.get(name, {})
        if not isinstance(table, dict):
            problems.append(f"{name} must be a table of task-id = \"dev\" or \"test\" lines")
            table = {}
        problems += [f"[{name}] {task} = {half!r}: a task's half is \"dev\" or \"test\""
                     for task, half in table.items() if half not in HALVES]
        tables[name] = table
    problems += [f"{task} is in both [drawn] and [assigned]: keep one line" for task in tables["drawn"]
                 if task in tables["assigned"]]
    if problems:
        raise UserError("\n".join(f"{path}: {problem}" for problem in problems))
    return Split(path, seed, tables["drawn"], tables["assigned"])


def domain_split(domain: Domain) -> Split | None:
    """The domain's split, or None where it has no split file."""
    path = domain.split_file()
    return load_split(path) if path.is_file() else None


def require_split(domain: Domain) -> Split:
    """The domain's split, for ``--split``.

    Raises:
        UserError: the domain has no split file (saying what to add).
    """
    split = domain_split(domain)
    if split is None:
        raise UserError(f"the {domain.name} domain has no development/test split: add {domain.split_file()} "
                        "(each feasible task's id = \"dev\" or \"test\"; see docs/benchmark.md, \"The "
                        "development/test split\"), or leave out --split to take every task")
    return split


def split_problems(split: Split, tasks: Sequence[Task]) -> list[str]:
    """What is wrong with ``split`` as the split of ``tasks`` (the domain's whole benchmark): a feasible task
    in neither half, a line naming no feasible task, a category whose halves differ by more than one."""
    feasible = {t.id: t for t in tasks if t.feasible}
    infeasible = {t.id for t in tasks if not t.feasible}
    halves = split.halves
    problems = [f"{split.path}: {task.id} ({task.category}) is in neither half: add the line {task.id} = \"dev\" "
                f"or {task.id} = \"test\" under [assigned]" for task in feasible.values() if task.id not in halves]
    for task in halves:
        if task in infeasible:
            problems.append(f"{split.path}:{split.line_of(task)}: {task} is infeasible, so in both halves: "
                            "remove its line")
        elif task not in feasible:
            problems.append(f"{split.path}:{split.line_of(task)}: {task} is not a task of the benchmark: "
                            "remove its line")
    for category, (dev, test) in half_sizes(split, tasks).items():
        if abs(dev - test) > 1:
            problems.append(f"{split.path}: {category} has {dev} tasks in dev and {test} in test: assign its "
                            "tasks under [assigned] so that its halves differ by at most one")
    return problems


def half_sizes(split: Split, tasks: Sequence[Task]) -> dict[str, tuple[int, int]]:
    """Per category (in the paper's order), how many of its feasible tasks are in dev and in test."""
    halves = split.halves
    sizes = {}
    for category in (*CATEGORIES, "uncategorized"):
        group = [halves.get(t.id) for t in tasks if t.feasible and t.category == category]
        if group:
            sizes[category] = (group.count("dev"), group.count("test"))
    return sizes


def split_tasks(tasks: Sequence[Task], split: Split, half: str) -> list[Task]:
    """The tasks of one half (its feasible tasks, and every infeasible task), in the task files' order.

    Raises:
        UserError: the split does not fit the tasks (every problem named).
    """
    problems = split_problems(split, tasks)
    if problems:
        raise UserError("\n".join(problems) + "\n(`smartllm-local benchmark check` lists the same)")
    chosen = split.half(half)
    return [t for t in tasks if not t.feasible or t.id in chosen]


def check_half(half: str) -> None:
    """A ``--split`` must name a half."""
    if half not in HALVES:
        raise UserError(f"--split must be {' or '.join(HALVES)}, not {half!r} (leave it out to take every task)")


def split_summary(split: Split, tasks: Sequence[Task]) -> str:
    """A few lines for ``benchmark check``: each half's feasible tasks per category, and the infeasible."""
    sizes = half_sizes(split, tasks)
    infeasible = sum(not t.feasible for t in tasks)
    lines = [f"split {split.path} (seed {split.seed}):"]
    for k, half in enumerate(HALVES):
        counts = ", ".join(f"{category} {pair[k]}" for category, pair in sizes.items())
        lines.append(f"{half} half: {sum(pair[k] for pair in sizes.values())} feasible ({counts}) "
                     f"and the {infeasible} infeasible")
    return "\n".join(lines)


def draw(tasks: Sequence[Task], seed: int) -> dict[str, str]:
    """Draw a split of ``tasks``' feasible tasks by ``seed``: task id -> half. Each category's ids, sorted, are
    shuffled in turn (in the paper's order) by one ``random.Random(seed)``; the first half (rounded down) is dev."""
    rng = random.Random(seed)
    halves = {}
    for category in (*CATEGORIES, "uncategorized"):
        ids = sorted(t.id for t in tasks if t.feasible and t.category == category)
        rng.shuffle(ids)
        halves.update({task: "dev" if k < len(ids) // 2 else "test" for k, task in enumerate(ids)})
    return halves
