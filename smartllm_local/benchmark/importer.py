"""Import SMART-LLM's task files (``data/final_test/FloorPlan<N>.json``), and LaMMA-P's MAT-THOR
files of the same format in that folder (``FloorPlan<N>pddl.json``, ``FloorPlan<N>pddlvague.json``,
``FloorPlan<N>vague.json``), as a task file.

The original files hold one task per line, mostly as Python literals rather
than JSON, and are messy: missing brackets, stray spaces and commas in object
names, informal names ("trash", "TV"), ``"None"`` as a state. Every line that
can be read is imported; what can be repaired unambiguously is repaired, what
has to be guessed is guessed, and both come with a note, as does every line or
file that is skipped, so nothing is changed or dropped silently.

The text is never executed: a line is read with ``json.loads``, then
``ast.literal_eval`` (literals only), then with missing brackets added.
Imported ids are the file's name without ``.json`` and the line number
(``FloorPlan15-3``, ``FloorPlan6pddl-2``) so that results stay comparable
across imports of the same files.

MAT-THOR's files differ in three ways, each handled with a note: a vague
command file's tasks get MAT-THOR's category "vague" (its other files do not
say which tasks are compound and which complex: those stay uncategorized); they
give ``min_trans`` rather than the ``max_trans`` RU is measured against, so RU
and SR are unknown for them; and a state written on a receptacle ("Fridge"
containing lettuce and tomato, "Sliced") is the state of what it contains.
"""

from __future__ import annotations

import ast
import difflib
import json
import re
import reprlib
from collections import Counter
from collections.abc import Iterator
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path
from typing import Any

from ..domain import load_domain
from ..errors import UnknownFloorPlanError, UserError
from ..robots import Catalogue
from ..scoring import STATES
from ..world.object_types import INFORMAL_NAMES, SLICE_RESULTS
from ..world.scenes import floor_plan_name, load_scene
from .tasks import check_task

MAX_LINE_CHARS = 100_000
# Trying one missing bracket at every place costs a parse per place: real task lines are a few hundred characters.
_MAX_SEARCH_CHARS = 4_000
# SMART-LLM's FloorPlan<N>.json, or MAT-THOR's with a suffix (pddl, vague, _task<K>).
_FILE_RE = re.compile(r"FloorPlan([1-9][0-9]*)((?:pddl)?(?:vague)?(?:_task[0-9]+)?)\.json")
_CLOSERS = {"[": "]", "{": "}"}
_STATE_ALIASES = {"OPEN": "OPENED", "CLOSE": "CLOSED"}



@dataclass(frozen=True)
class Note:
    """What happened to one task line (or one whole file, where ``line`` is None)."""

    file: str
    line: int | None
    task_id: str | None
    kind: str  # repaired, guessed or skipped
    reason: str

    def __str__(self) -> str:
        where = self.file if self.line is None else f"{self.file}:{self.line}: {self.task_id}"
        return f"{where}: {self.kind}: {self.reason}"


@dataclass
class ImportReport:
    """The imported task dicts (one task-file line each) and a note per line that was not imported as is."""

    tasks: list[dict[str, Any]] = field(default_factory=list)
    notes: list[Note] = field(default_factory=list)

    def summary(self) -> str:
        counts = Counter(n.kind for n in self.notes if n.line is not None)
        text = (f"{len(self.tasks)} imported, {counts['repaired']} repaired, {counts['guessed']} guessed, "
                f"{counts['skipped']} skipped")
        files = sum(1 for n in self.notes if n.line is None)
        return text + (f", {files} file(s) skipped" if files else "")


class _Skip(Exception):
    """A line that cannot be imported; the message is the note's reason."""


@dataclass
class _Fixes:
    """Reasons collected while converting one line, each once, in order."""

    repaired: list[str] = field(default_factory=list)
    guessed: list[str] = field(default_factory=list)

    def add(self, kind: str, reason: str) -> None:
        reasons = self.guessed if kind == "guessed" else self.repaired
        if reason not in reasons:
            reasons.append(reason)


def import_smartllm(source: str | Path, *, catalogue: Catalogue | None = None) -> ImportReport:
    """Import every ``FloorPlan<N>.json`` of SMART-LLM's repository (or its ``data/final_test`` folder).

    Raises:
        UserError: ``source`` is missing or holds no such files (bad lines and files only get notes).
    """
    folder = find_final_test(Path(source))
    catalogue = catalogue or load_domain().catalogue
    report = ImportReport()
    for path in sorted(folder.glob("*.json"), key=_file_order):
        if path.is_file():
            _import_file(path, catalogue, report)
    return report


def find_final_test(source: Path) -> Path:
    """The folder holding the task files: ``source/data/final_test`` or ``source`` itself."""
    hint = "give SMART-LLM's repository or its data/final_test folder"
    if not source.exists():
        raise UserError(f"{source} does not exist: {hint}")
    if not source.is_dir():
        raise UserError(f"{source} is not a folder: {hint}")
    for folder in (source / "data" / "final_test", source):
        if folder.is_dir() and any(folder.glob("*.json")):
            return folder
    raise UserError(f"found no data/final_test/*.json files under {source}: {hint}")


def _file_order(path: Path) -> tuple[int, int, str]:
    match = _FILE_RE.fullmatch(path.name)
    return (0, int(match.group(1)), path.name) if match else (1, 0, path.name)


def _import_file(path: Path, catalogue: Catalogue, report: ImportReport) -> None:
    name = path.name
    match = _FILE_RE.fullmatch(name)
    if not match:
        report.notes.append(Note(name, None, None, "skipped", "not named FloorPlan<N>.json or FloorPlan<N>pddl.json "
                                                               "(the floor plan comes from the file name)"))
        return
    source = _Source(suffix=match.group(2))
    try:
        scene = floor_plan_name(match.group(1))
        text = path.read_text(encoding="utf-8-sig")
    except UnknownFloorPlanError as exc:
        report.notes.append(Note(name, None, None, "skipped", str(exc)))
        return
    except (OSError, UnicodeDecodeError) as exc:
        report.notes.append(Note(name, None, None, "skipped", f"cannot read it as UTF-8 text ({exc})"))
        return
    for number, line in enumerate(text.split("\n"), start=1):  # line numbers as editors count them
        if not line.strip():
            continue
        task_id, fixes = f"{name.removesuffix('.json')}-{number}", _Fixes()
        try:
            task = _convert(line, task_id, scene, catalogue, fixes, source)
            where = f"{name}:{number}"
            _, problems = check_task(task, catalogue, where)
            if problems:
                raise _Skip("; ".join(p.removeprefix(f"{where}: ") for p in problems))
        except _Skip as skip:
            report.notes.append(Note(name, number, task_id, "skipped", str(skip)))
            continue
        report.tasks.append(task)
        if fixes.guessed or fixes.repaired:
            kind = "guessed" if fixes.guessed else "repaired"
            report.notes.append(Note(name, number, task_id, kind, "; ".join(fixes.guessed + fixes.repaired)))


@dataclass(frozen=True)
class _Source:
    """Which dataset a file belongs to, from its name."""

    suffix: str  # "" for SMART-LLM's files

    @property
    def mat_thor(self) -> bool:
        return bool(self.suffix)

    @property
    def category(self) -> str:
        return "vague" if "vague" in self.suffix else "uncategorized"


def _convert(line: str, task_id: str, scene: str, catalogue: Catalogue, fixes: _Fixes,
             source: _Source) -> dict[str, Any]:
    """One original line -> one task dict in this project's format."""
    data = _parse(line, fixes)
    instruction = data.get("task")
    if not isinstance(instruction, str) or not instruction.strip():
        raise _Skip('no "task" text')
    robots = data.get("robot list")
    if not isinstance(robots, list) or not robots or not all(type(r) is int for r in robots):
        raise _Skip(f'"robot list" is not a list of robot ids: {reprlib.repr(robots)}')
    unknown = [r for r in robots if r not in catalogue.robots]
    if unknown:
        raise _Skip(f"robot id(s) {unknown} are not in the robot catalogue")
    goals = _goals(data.get("object_states"), scene, fixes)
    missing = [key for key in ("trans", "max_trans") if data.get(key) is None]
    if source.mat_thor and "max_trans" in missing and data.get("min_trans") is not None:
        fixes.add("repaired", "MAT-THOR gives min_trans, not the max_trans RU is measured against: RU and SR "
                              "are unknown (TCR, GCR and Exe are scored)")
    elif missing:
        fixes.add("repaired", f"no {' or '.join(missing)}: null, so RU and SR are unknown")
    return {
        "id": task_id, "category": source.category, "floor_plan": int(scene[len("FloorPlan"):]),
        "instruction": instruction.strip(), "robots": robots, "goals": goals,
        "trans": data.get("trans"), "max_trans": data.get("max_trans"), "feasible": True,
    }


def _goals(entries: Any, scene: str, fixes: _Fixes) -> list[dict[str, Any]]:
    """``object_states`` -> goal entries with AI2-THOR types of the scene and known states."""
    if not isinstance(entries, list):
        if entries is not None:
            raise _Skip(f"object_states is not a list: {reprlib.repr(entries)}")
        entries = []
    goals = []
    for k, entry in enumerate(entries):
        at = f"object_states[{k}]"
        if not isinstance(entry, dict):
            raise _Skip(f"{at} is not an object: {reprlib.repr(entry)}")
        extra = sorted(str(key) for key in entry if key not in ("name", "contains", "state"))
        if extra:
            fixes.add("repaired", f"{at}: ignored field(s) {', '.join(extra)}")
        contains = [] if entry.get("contains") is None else entry["contains"]
        if not isinstance(contains, list):
            raise _Skip(f"{at}.contains is not a list: {reprlib.repr(contains)}")
        state = _state(entry.get("state"), at, fixes)
        if state is None and not contains:
            fixes.add("repaired", f"{at} ({reprlib.repr(entry.get('name'))}) has no state and contains nothing: "
                                  "dropped")
            continue
        name = _map_name(entry.get("name"), scene, fixes)
        if state == "SLICED" and contains and name not in SLICE_RESULTS:
            # MAT-THOR writes "Fridge contains Lettuce, Tomato; Sliced": it is what the fridge holds that is sliced.
            fixes.add("repaired", f"{at}: {name} cannot be sliced: SLICED moved to what it contains")
            goals += [{"name": _map_name(item, scene, fixes), "contains": [], "state": "SLICED"} for item in contains]
            state = None
        goals.append({"name": name, "contains": [_map_name(item, scene, fixes) for item in contains], "state": state})
    if not goals:
        what = "no goal conditions left" if entries else "no object_states"
        fixes.add("repaired", f"{what}: imported without goals, so GCR, TCR and SR are unknown")
    return goals


def _state(value: Any, at: str, fixes: _Fixes) -> str | None:
    if value is None:
        return None
    if not isinstance(value, str):
        raise _Skip(f"{at}.state is not a state: {reprlib.repr(value)}")
    state = value.strip().upper()
    if state in ("", "NONE", "NULL"):
        fixes.add("repaired", f"state {value!r} -> null")
        return None
    state = _STATE_ALIASES.get(state, state)
    if state not in STATES:
        raise _Skip(f"{at}.state {value!r} is not one of {', '.join(STATES)} or None")
    if state != value:
        fixes.add("repaired", f"state {value!r} -> {state}")
    return state


def _key(name: str) -> str:
    return re.sub(r"[^a-z0-9]", "", name.lower())


@lru_cache(maxsize=256)
def _scene_types(scene: str) -> dict[str, str]:
    """Name key -> object type, for the types a goal may name in this scene (slices included)."""
    types = {o["objectType"] for o in load_scene(scene)}
    types |= {SLICE_RESULTS[t][0] for t in types if t in SLICE_RESULTS}
    return {_key(t): t for t in sorted(types)}


def _map_name(raw: Any, scene: str, fixes: _Fixes) -> str:
    """An object name as written -> an AI2-THOR type present in the scene, or skip the line."""
    if not isinstance(raw, str) or not _key(raw):
        raise _Skip(f"object name {reprlib.repr(raw)} is not a name")
    types, key = _scene_types(scene), _key(raw)
    forms = [key] + ([key[:-1]] if key.endswith("s") else []) + ([key[:-2]] if key.endswith("es") else [])
    for form in forms:
        if form in types:
            return _mapped(raw, types[form], "repaired", "", fixes)
        present = [t for t in INFORMAL_NAMES.get(form, ()) if _key(t) in types]
        if len(present) == 1:
            return _mapped(raw, present[0], "repaired", "", fixes)
        if present:
            return _mapped(raw, present[0], "guessed", f" ({scene} also has {', '.join(present[1:])})", fixes)
    close = difflib.get_close_matches(key, list(types), n=1, cutoff=0.75)
    if close:
        return _mapped(raw, types[close[0]], "guessed", f" (the closest type in {scene})", fixes)
    raise _Skip(f"no object like {raw!r} in {scene}")


def _mapped(raw: str, found: str, kind: str, why: str, fixes: _Fixes) -> str:
    if found != raw:
        fixes.add(kind, f"{raw!r} -> {found}{why}")
    return found


def _parse(line: str, fixes: _Fixes) -> dict[str, Any]:
    """Read a line as JSON or a Python literal, adding missing brackets where that makes it readable."""
    if len(line) > MAX_LINE_CHARS:
        raise _Skip(f"unreadable: longer than {MAX_LINE_CHARS} characters")
    text = line.rstrip()
    data = _read(text)
    if data is not None:
        return data
    balanced, added = _balance(text)
    if added and (data := _read(balanced)) is not None:
        fixes.add("repaired", f"added missing {', '.join(added)}")
        return data
    found: dict[str, dict[str, Any]] = {}
    for candidate, where in _insertions(text):
        value = _read(candidate)
        if value is not None and value not in found.values():
            found[where] = value
    if len(found) == 1:  # one place only: several would be a guess
        (where, data), = found.items()
        fixes.add("repaired", f"added missing {where}")
        return data
    raise _Skip("unreadable: not a task object in JSON or Python-literal form")


def _read(text: str) -> dict[str, Any] | None:
    """The text as a dict, read as JSON or as a Python literal (never executed); None if it is neither."""
    try:
        value = json.loads(text)
    except (ValueError, RecursionError):
        try:
            value = ast.literal_eval(text)
        except (ValueError, TypeError, SyntaxError, MemoryError, RecursionError):
            return None
    return value if isinstance(value, dict) else None


def _structure(text: str) -> Iterator[tuple[int, str]]:
    """Positions of brackets and commas outside string literals."""
    quote, escaped = "", False
    for i, ch in enumerate(text):
        if quote:
            if escaped:
                escaped = False
            elif ch == "\\":
                escaped = True
            elif ch == quote:
                quote = ""
        elif ch in "\"'":
            quote = ch
        elif ch in "[]{},":
            yield i, ch


def _balance(text: str) -> tuple[str, list[str]]:
    """Close every bracket left open, as late as possible: where an outer one closes, else at the end."""
    stack: list[str] = []
    pieces: list[str] = []
    added: list[str] = []
    last = 0
    for i, ch in _structure(text):
        if ch in _CLOSERS:
            stack.append(_CLOSERS[ch])
        elif ch in "]}" and ch in stack:
            while stack[-1] != ch:
                closer = stack.pop()
                pieces += [text[last:i], closer]
                last = i
                added.append(f"{closer!r} at column {i + 1}")
            stack.pop()
    pieces.append(text[last:])
    added += [f"{closer!r} at the end" for closer in reversed(stack)]
    return "".join(pieces) + "".join(reversed(stack)), added


def _insertions(text: str) -> Iterator[tuple[str, str]]:
    """The text with one closing bracket added before a comma, a bracket or the end."""
    if len(text) > _MAX_SEARCH_CHARS:
        return
    for i in [i for i, ch in _structure(text) if ch in ",]}"] + [len(text)]:
        for closer in "]}":
            yield text[:i] + closer + text[i:], f"{closer!r} at column {i + 1}"
