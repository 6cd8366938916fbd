"""AI2-THOR's contextual interactions, applied to a scene's object table.

Each function takes the scene's ``objects`` (objectId -> metadata dict) and a
``touch(objectId)`` callback that records which objects changed. The rules are
those of AI2-THOR's object-type documentation:

- Heat sources heat what they hold (and what that holds): a Microwave only
  while switched on and closed, a StoveBurner while the StoveKnob that controls
  it is on, a Toaster while on (it only accepts bread slices), a CoffeeMachine
  while on, which also fills a Mug in it with coffee. Heated cookable objects
  become cooked.
- A Fridge cools what it holds.
- A receptacle holds what it accepts (:func:`refuses`): some only certain types (a
  StoveBurner a Kettle, Pan or Pot), and one that is itself carried (a bowl, a box)
  nothing bigger than itself.
- A running Faucet rinses the sink (or bathtub) and basin under it, that is
  within 1.2 m: dirty objects in them become clean, objects that hold liquid
  fill with water.

Temperatures stay as set once an object leaves the source (AI2-THOR lets them
decay back to room temperature over time; the symbolic world has no clock).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Iterator
from typing import Any

from .object_types import (
    COLD_SOURCES,
    HEAT_SOURCES,
    RECEPTACLE_ONLY_ACCEPTS,
    SLICE_RESULTS,
    TYPE_PROPERTIES,
    WATER_BASINS,
)

Objects = dict[str, dict[str, Any]]
Touch = Callable[[str], None]

_FAUCET_REACH = 1.2  # metres from a faucet to the basin it runs into


def refuses(obj: dict[str, Any], receptacle: dict[str, Any]) -> str | None:
    """Why ``receptacle`` cannot hold ``obj``, or None if it can: it accepts only other types, or it is carried
    itself (a bowl, a box; not the floor) and smaller than the thing (by bounding-box volume, where both have one)."""
    allowed = RECEPTACLE_ONLY_ACCEPTS.get(receptacle["objectType"])
    if allowed is not None and obj["objectType"] not in allowed:
        return f"a {receptacle['objectType']} only accepts {', '.join(sorted(allowed))}"
    if receptacle["objectType"] == "Floor" or not receptacle.get("pickupable"):
        return None
    size, room = volume(obj), volume(receptacle)
    if size is not None and room is not None and size > room:
        return f"{obj['objectType']} is too big for {receptacle['objectType']}"
    return None


def volume(obj: dict[str, Any]) -> float | None:
    """The volume of the object's axis-aligned bounding box, or None where it has none (a slice yet to be cut)."""
    size = (obj.get("axisAlignedBoundingBox") or {}).get("size")
    return size["x"] * size["y"] * size["z"] if size else None


def contents(objects: Objects, receptacle_id: str) -> Iterator[dict[str, Any]]:
    """Everything inside a receptacle, nested contents included, each once."""
    seen: set[str] = set()
    stack = list(objects[receptacle_id].get("receptacleObjectIds") or [])
    while stack:
        oid = stack.pop()
        if oid in seen or oid not in objects:
            continue
        seen.add(oid)
        obj = objects[oid]
        yield obj
        stack.extend(obj.get("receptacleObjectIds") or [])


def linked(objects: Objects, start: Iterable[str], field: str) -> set[str]:
    """Every objectId reached from ``start`` by following ``field`` again and again
    (``parentReceptacles``: the holders of holders; ``receptacleObjectIds``: nested contents)."""
    reached: set[str] = set()
    stack = [oid for oid in start if oid in objects]
    while stack:
        for other in objects[stack.pop()].get(field) or ():
            if other in objects and other not in reached:
                reached.add(other)
                stack.append(other)
    return reached


def is_heating(objects: Objects, source: dict[str, Any]) -> bool:
    """Whether a heat source is running now."""
    kind = source["objectType"]
    if kind == "Microwave":
        return bool(source["isToggled"]) and not source["isOpen"]
    if kind == "StoveBurner":
        return any(
            knob["isToggled"]
            for knob in objects.values()
            if knob["objectType"] == "StoveKnob" and source["objectId"] in (knob.get("controlledObjects") or [])
        )
    return bool(source["isToggled"])


def basins_of(objects: Objects, faucet: dict[str, Any]) -> list[dict[str, Any]]:
    """The sinks, bathtubs and their basins a faucet runs into."""
    fx, fz = faucet["position"]["x"], faucet["position"]["z"]
    return [
        obj
        for obj in objects.values()
        if obj["objectType"] in WATER_BASINS
        and math.hypot(obj["position"]["x"] - fx, obj["position"]["z"] - fz) <= _FAUCET_REACH
    ]


def _set(obj: dict[str, Any], field: str, value: Any, touch: Touch) -> None:
    if obj.get(field) != value:
        obj[field] = value
        touch(obj["objectId"])


def _heat(obj: dict[str, Any], touch: Touch) -> None:
    _set(obj, "temperature", "Hot", touch)
    if obj.get("cookable"):
        _set(obj, "isCooked", True, touch)


def _fill(obj: dict[str, Any], liquid: str, touch: Touch) -> None:
    if obj.get("canFillWithLiquid") and not obj.get("isBroken"):
        _set(obj, "isFilledWithLiquid", True, touch)
        _set(obj, "fillLiquid", liquid, touch)


def apply_contextual_effects(objects: Objects, touch: Touch) -> None:
    """Bring every object in line with the sources it sits in; idempotent."""
    for source in list(objects.values()):
        kind = source["objectType"]
        if source.get("isSliced"):
            continue
        if kind in HEAT_SOURCES and is_heating(objects, source):
            for obj in contents(objects, source["objectId"]):
                _heat(obj, touch)
                if kind == "CoffeeMachine" and obj["objectType"] == "Mug":
                    _fill(obj, "coffee", touch)
        elif kind in COLD_SOURCES:
            for obj in contents(objects, source["objectId"]):
                _set(obj, "temperature", "Cold", touch)
        elif kind == "Faucet" and source["isToggled"]:
            for basin in basins_of(objects, source):
                for obj in contents(objects, basin["objectId"]):
                    if obj.get("dirtyable"):
                        _set(obj, "isDirty", False, touch)
                    _fill(obj, "water", touch)


def make_pieces(whole: dict[str, Any]) -> list[dict[str, Any]]:
    """The slices (or the cracked egg) that cutting ``whole`` produces, AI2-THOR style."""
    derived, count = SLICE_RESULTS[whole["objectType"]]
    props = TYPE_PROPERTIES[derived]
    pieces = []
    for k in range(count):
        piece = {key: value for key, value in whole.items() if key not in ("receptacleObjectIds",)}
        piece.update(
            {
                "objectId": f"{whole['objectId']}|{derived}_{k}",
                "objectType": derived,
                "name": f"{derived}_{k}",
                "assetId": "",
                "mass": round(float(whole.get("mass") or 0.0) / count, 4),
                "isSliced": False,
                "isBroken": False,
                "isPickedUp": False,
                "isDirty": False,
                "receptacleObjectIds": None,
                "parentReceptacles": list(whole.get("parentReceptacles") or []) or None,
                "position": dict(whole["position"]),
                "axisAlignedBoundingBox": _scaled_box(whole.get("axisAlignedBoundingBox"), count),
                "objectOrientedBoundingBox": None,
            }
        )
        for prop in ("pickupable", "receptacle", "openable", "toggleable", "sliceable", "cookable",
                     "breakable", "dirtyable", "canFillWithLiquid", "moveable"):
            piece[prop] = prop in props
        pieces.append(piece)
    return pieces


def _scaled_box(box: dict[str, Any] | None, count: int) -> dict[str, Any] | None:
    if not box:
        return box
    size = box["size"]
    new_size = {"x": size["x"], "y": size["y"], "z": size["z"] / max(count, 1)}
    c = box["center"]
    corners = [
        [c["x"] + sx * new_size["x"] / 2, c["y"] + sy * new_size["y"] / 2, c["z"] + sz * new_size["z"] / 2]
        for sx in (1, -1) for sy in (1, -1) for sz in (1, -1)
    ]
    return {"center": dict(c), "size": new_size, "cornerPoints": corners}
