"""The 3D scene's nodes as a test reads them."""

from __future__ import annotations

import asyncio
import time
from collections.abc import Callable
from typing import Any

import viser

from protocol.messages import VehicleState, VehicleSummary

HOME = (47.397742, 8.545594, 488.0)


def _summary(vehicle: str, t: float, connected: bool = True, **state: Any) -> VehicleSummary:
    values: dict[str, Any] = {
        "home_lat": HOME[0],
        "home_lon": HOME[1],
        "home_alt_msl": HOME[2],
        "mode": "GUIDED",
    }
    values.update(state)
    # model_construct: the tests feed what a faulty source might (NaN), as the hub's
    # registry would hold it; the scene must cope without the wire's validation.
    return VehicleSummary(
        id=vehicle,
        autopilot="ardupilot",
        vehicle_type="quadrotor",
        modes=["GUIDED"],
        connected=connected,
        last_seen=t,
        state=VehicleState.model_construct(**{**VehicleState().model_dump(), **values}),
    )


def _node(server: viser.ViserServer, name: str) -> Any:
    return server.scene._handle_from_node_name.get(name)


def _under(server: viser.ViserServer, root: str) -> list[str]:
    """The nodes at or under ``root``: viser's own parent frames included."""
    names = server.scene._handle_from_node_name
    return [name for name in names if name == root or name.startswith(root + "/")]


async def until(condition: Callable[[], Any], what: str, within: float = 10.0) -> Any:
    """Polls ``condition`` (a scene read back) until it is truthy, and returns it."""
    deadline = time.monotonic() + within
    while time.monotonic() < deadline:
        if result := condition():
            return result
        await asyncio.sleep(0.02)
    raise AssertionError(f"timed out waiting for {what}")
