"""Small helpers for driving the simulator in tests."""

from __future__ import annotations

from smartllm_local.world.simulator import ActionResult, Simulator


def oid(sim: Simulator, object_type: str, index: int = 0) -> str:
    """The objectId of the index-th object of a type, in scene order."""
    ids = [i for i, o in sim.objects.items() if o["objectType"] == object_type]
    assert ids, f"no {object_type} in {sim.scene_name}"
    return ids[index]


def act(sim: Simulator, action: str, agent: int = 0, force: bool = True, **args) -> ActionResult:
    """Run an action; by default with forceAction so distance does not get in the way."""
    payload = {"action": action, **args}
    if force:
        payload["forceAction"] = True
    return sim.step(agent, payload)


def ok(result: ActionResult) -> ActionResult:
    assert result.success, result.error_message
    return result


def carry(sim: Simulator, object_type: str, agent: int = 0, index: int = 0) -> str:
    """Pick up an object of a type (opening a closed receptacle it sits in first)."""
    object_id = oid(sim, object_type, index)
    for parent in sim.objects[object_id].get("parentReceptacles") or []:
        if sim.objects[parent].get("openable") and not sim.objects[parent]["isOpen"]:
            ok(act(sim, "OpenObject", agent, objectId=parent))
    ok(act(sim, "PickupObject", agent, objectId=object_id))
    return object_id


def put(sim: Simulator, receptacle_id: str, agent: int = 0) -> None:
    receptacle = sim.objects[receptacle_id]
    if receptacle.get("openable") and not receptacle["isOpen"]:
        ok(act(sim, "OpenObject", agent, objectId=receptacle_id))
    ok(act(sim, "PutObject", agent, objectId=receptacle_id))
