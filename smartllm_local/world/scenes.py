"""Scene data for the 120 iTHOR floor plans.

The objects come from AI2-THOR 5.0's metadata dump that the PyPI package
``procthor==0.0.1.dev2`` ships as ``procthor/databases/ai2thor-object-metadata.json``.
The file is read as data (procthor's own modules are never imported: they pull
in heavy dependencies) and split once into one small JSON file per floor plan
under the user's cache folder, so that starting a world costs milliseconds
rather than the 0.8 s it takes to parse the 43 MB dump.
"""

from __future__ import annotations

import hashlib
import importlib.util
import json
import os
import pickle
import re
import shutil
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Final

from ..errors import SceneDataError, UnknownFloorPlanError
from .rules import linked

SCENE_DATA_REQUIREMENT: Final = "procthor==0.0.1.dev2"
_INSTALL_HINT: Final = f"install it with: pip install '{SCENE_DATA_REQUIREMENT}'"

# (key in the dump, first floor plan number - 1, room type)
ROOM_BLOCKS: Final = (
    ("kitchens", 0, "kitchen"),
    ("living_rooms", 200, "living room"),
    ("bedrooms", 300, "bedroom"),
    ("bathrooms", 400, "bathroom"),
)
SCENES_PER_BLOCK: Final = 30
VALID_RANGE_TEXT: Final = (
    "FloorPlan1-30 (kitchens), FloorPlan201-230 (living rooms), "
    "FloorPlan301-330 (bedrooms), FloorPlan401-430 (bathrooms)"
)

_NAME_RE = re.compile(r"^\s*(?:floorplan)?\s*(\d+)(?:_physics)?\s*$", re.IGNORECASE)
# A scene's repaired objects, pickled: unpickling is the cheapest fresh copy (5x faster than JSON).
_memo: dict[str, bytes] = {}


@dataclass(frozen=True)
class SceneInfo:
    """What a listing shows of a floor plan without loading its objects."""

    name: str
    number: int
    room_type: str


def all_floor_plans() -> list[str]:
    """The 120 iTHOR floor plan names, in AI2-THOR's order."""
    return [
        f"FloorPlan{base + i}"
        for _, base, _ in ROOM_BLOCKS
        for i in range(1, SCENES_PER_BLOCK + 1)
    ]


def floor_plan_name(value: int | str) -> str:
    """Normalise ``6``, ``"6"``, ``"FloorPlan6"`` or ``"FloorPlan6_physics"`` to ``"FloorPlan6"``.

    Raises:
        UnknownFloorPlanError: for anything that is not one of the 120 iTHOR scenes.
    """
    match = _NAME_RE.match(str(value))
    if match:
        number = int(match.group(1))
        if any(base < number <= base + SCENES_PER_BLOCK for _, base, _ in ROOM_BLOCKS):
            return f"FloorPlan{number}"
    raise UnknownFloorPlanError(
        f"unknown floor plan {value!r}: valid floor plans are {VALID_RANGE_TEXT}"
    )


def scene_info(floor_plan: int | str) -> SceneInfo:
    """Room type and number of a floor plan."""
    name = floor_plan_name(floor_plan)
    number = int(name[len("FloorPlan"):])
    room = next(room for _, base, room in ROOM_BLOCKS if base < number <= base + SCENES_PER_BLOCK)
    return SceneInfo(name=name, number=number, room_type=room)


def source_path() -> Path:
    """Locate the AI2-THOR metadata dump inside the installed procthor package, without importing it."""
    try:
        spec = importlib.util.find_spec("procthor")
    except (ImportError, ValueError):
        spec = None
    if spec is None or not spec.submodule_search_locations:
        raise SceneDataError(f"the AI2-THOR scene data (package procthor) is not installed; {_INSTALL_HINT}")
    for location in spec.submodule_search_locations:
        path = Path(location) / "databases" / "ai2thor-object-metadata.json"
        if path.is_file():
            return path
    raise SceneDataError(
        f"procthor is installed but has no databases/ai2thor-object-metadata.json; {_INSTALL_HINT}"
    )


def cache_root() -> Path:
    """The folder this project caches derived data in (override with SMARTLLM_CACHE_DIR)."""
    if os.environ.get("SMARTLLM_CACHE_DIR"):
        return Path(os.environ["SMARTLLM_CACHE_DIR"])
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "smartllm-local"


def check_scene_data() -> Path:
    """Fail with :class:`SceneDataError` now if the scene data cannot be read; return its cache folder.

    A process that loads scenes later (the stand-in) can only report the problem
    as a failed action; checking first in the parent gives the user the one-line
    fix. Costs a stat once the per-scene cache exists.
    """
    return _ensure_cache(source_path(), cache_root())


def load_scene(
    floor_plan: int | str,
    *,
    source: Path | None = None,
    cache_dir: Path | None = None,
) -> list[dict[str, Any]]:
    """Return a fresh, mutable copy of a floor plan's objects (AI2-THOR metadata dicts).

    Args:
        floor_plan: a floor plan name or number.
        source: the metadata dump to read (default: the one procthor ships).
        cache_dir: where the per-scene split lives (default: :func:`cache_root`).

    Raises:
        UnknownFloorPlanError: the floor plan is not one of the 120.
        SceneDataError: the dump is missing or corrupt (the message says what to install).
    """
    name = floor_plan_name(floor_plan)
    src = source or source_path()
    key = f"{src}:{name}"
    if key not in _memo:
        scene_dir = _ensure_cache(src, cache_dir or cache_root())
        text = _read_cached(scene_dir / f"{name}.json")
        if text is None:
            shutil.rmtree(scene_dir, ignore_errors=True)
            scene_dir = _ensure_cache(src, cache_dir or cache_root())
            text = _read_cached(scene_dir / f"{name}.json")
            if text is None:
                raise SceneDataError(f"could not cache the scene data for {name} under {scene_dir}")
        _memo[key] = pickle.dumps(untangle_containment(json.loads(text)), protocol=pickle.HIGHEST_PROTOCOL)
    return pickle.loads(_memo[key])


def untangle_containment(objects: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """Break the containment cycles the metadata dump has (a CounterTop "inside" the Plate on it).

    Overlapping boxes make some of AI2-THOR's parentReceptacles mutual (in FloorPlan5,
    16, 18, 21, 30, 310, 329). Left in, they loop containment walks and put a counter
    inside a plate. A link in a cycle is kept only where a pickupable object sits in
    a fixed one, the one direction that is physically possible. No fixture is shut
    inside a cabinet, drawer or other thing that opens: the same overlaps put
    FloorPlan16's floor in two cabinets and FloorPlan19's fridge in a drawer, and
    so out of every robot's reach. Then only the innermost of an object's holders
    are kept (see :func:`_keep_innermost_holders`).
    """
    by_id = {o["objectId"]: o for o in objects}
    dropped = [
        (obj["objectId"], parent)
        for obj in objects
        for parent in obj.get("parentReceptacles") or []
        if parent in by_id and ((obj["objectId"] in linked(by_id, [parent], "parentReceptacles")
                                 and not (obj.get("pickupable") and not by_id[parent].get("pickupable")))
                                or (not obj.get("pickupable") and by_id[parent].get("openable")))
    ]
    for child, parent in dropped:
        _unlink(by_id, child, parent)
    return _keep_innermost_holders(objects)


def _keep_innermost_holders(objects: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """Drop a parent that also holds another of the object's parents (the burner under the pot).

    Some dumps (FloorPlan5, 14, 317, ...) list a Spatula in both its Pot and the
    StoveBurner under the Pot. The outer link does not move with the Pot, so the
    burner would go on heating a spatula that is no longer on it. Keeping only
    the innermost holders loses nothing: the outer one still holds the object
    through them. Expects a containment graph without cycles.
    """
    by_id = {o["objectId"]: o for o in objects}
    dropped = [
        (obj["objectId"], parent)
        for obj in objects
        for parent in obj.get("parentReceptacles") or []
        if any(parent in linked(by_id, [other], "parentReceptacles")
               for other in obj["parentReceptacles"] if other != parent and other in by_id)
    ]
    for child, parent in dropped:
        _unlink(by_id, child, parent)
    return objects


def _unlink(by_id: dict[str, dict[str, Any]], child: str, parent: str) -> None:
    kept = [p for p in by_id[child].get("parentReceptacles") or [] if p != parent]
    by_id[child]["parentReceptacles"] = kept or None
    if parent in by_id:
        holds = [c for c in by_id[parent].get("receptacleObjectIds") or [] if c != child]
        by_id[parent]["receptacleObjectIds"] = holds or None


def _read_cached(path: Path) -> str | None:
    try:
        text = path.read_text(encoding="utf-8")
        objects = json.loads(text)
    except (OSError, ValueError):
        return None
    if not isinstance(objects, list) or not objects:
        return None
    return text


def _cache_key(src: Path) -> str:
    try:
        stat = src.stat()
    except OSError as exc:
        raise SceneDataError(f"cannot read the AI2-THOR scene data at {src} ({exc}); {_INSTALL_HINT}") from exc
    raw = f"{src.resolve()}|{stat.st_size}|{stat.st_mtime_ns}".encode()
    return hashlib.sha256(raw).hexdigest()[:16]


def _ensure_cache(src: Path, root: Path) -> Path:
    scene_dir = root / f"scenes-{_cache_key(src)}"
    if (scene_dir / "complete").is_file():
        return scene_dir
    dump = _read_dump(src)
    try:
        root.mkdir(parents=True, exist_ok=True)
        staging = Path(tempfile.mkdtemp(prefix="scenes-", dir=root))
    except OSError as exc:
        raise SceneDataError(
            f"cannot write the scene cache under {root} ({exc.strerror or exc}); "
            "set SMARTLLM_CACHE_DIR to a writable folder"
        ) from exc
    try:
        for key, base, _ in ROOM_BLOCKS:
            for i, objects in enumerate(dump[key]):
                out = staging / f"FloorPlan{base + i + 1}.json"
                out.write_text(json.dumps(objects, separators=(",", ":")), encoding="utf-8")
        (staging / "complete").write_text(str(src), encoding="utf-8")
        try:
            os.replace(staging, scene_dir)
        except OSError:
            # Another process finished the same cache first; theirs is as good as ours.
            if not (scene_dir / "complete").is_file():
                shutil.rmtree(scene_dir, ignore_errors=True)
                os.replace(staging, scene_dir)
    finally:
        shutil.rmtree(staging, ignore_errors=True)
    return scene_dir


def _read_dump(src: Path) -> dict[str, Any]:
    problem = f"the AI2-THOR scene data at {src} is corrupt"
    try:
        dump = json.loads(src.read_bytes())
    except OSError as exc:
        raise SceneDataError(f"cannot read the AI2-THOR scene data at {src} ({exc}); {_INSTALL_HINT}") from exc
    except ValueError as exc:
        raise SceneDataError(f"{problem} ({exc}); reinstall it with: "
                             f"pip install --force-reinstall '{SCENE_DATA_REQUIREMENT}'") from exc
    for key, _, _ in ROOM_BLOCKS:
        scenes = dump.get(key) if isinstance(dump, dict) else None
        if not isinstance(scenes, list) or len(scenes) != SCENES_PER_BLOCK or not all(
            isinstance(s, list) and s and all(isinstance(o, dict) and "objectId" in o and "objectType" in o for o in s)
            for s in scenes
        ):
            raise SceneDataError(
                f"{problem} (no {SCENES_PER_BLOCK} scenes of objects under {key!r}); "
                f"reinstall it with: pip install --force-reinstall '{SCENE_DATA_REQUIREMENT}'"
            )
    return dump


@dataclass(frozen=True)
class TypeSummary:
    """One object type of a scene: how many, how heavy, what can be done with it."""

    object_type: str
    count: int
    mass: float  # the heaviest instance, in kg
    properties: tuple[str, ...]


_SUMMARY_FLAGS: Final = (
    "pickupable", "receptacle", "openable", "toggleable", "sliceable",
    "cookable", "breakable", "dirtyable", "canFillWithLiquid", "moveable",
)


def summarize_scene(floor_plan: int | str) -> list[TypeSummary]:
    """The object types of a floor plan, sorted by name."""
    groups: dict[str, list[dict[str, Any]]] = {}
    for obj in load_scene(floor_plan):
        groups.setdefault(obj["objectType"], []).append(obj)
    return [
        TypeSummary(
            object_type=kind,
            count=len(objs),
            mass=round(max(float(o.get("mass") or 0.0) for o in objs), 3),
            properties=tuple(flag for flag in _SUMMARY_FLAGS if any(o.get(flag) for o in objs)),
        )
        for kind, objs in sorted(groups.items())
    ]
