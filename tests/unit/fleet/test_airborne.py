"""Whether a vehicle flies, for the commands that need it in the air: the autopilot's
landed state and arming, anything unknown refused as unknown."""

from __future__ import annotations

import pytest

from backend.fleet.airborne import not_airborne
from protocol.messages import VehicleState


@pytest.mark.parametrize(
    ("state", "reason"),
    [
        (None, "v has not reported its state"),
        (VehicleState(armed=True), "v: its landed state is unknown"),
        (VehicleState(armed=True, alt_rel=30.0), "v: its landed state is unknown"),
        (VehicleState(landed_state="on_ground"), "v is on the ground: take off first"),
        (VehicleState(armed=True, landed_state="on_ground"), "v is on the ground: take off first"),
        (VehicleState(armed=True, landed_state="landing"), "v is landing"),
        (VehicleState(landed_state="in_air"), "v is disarmed: take off first"),
        (
            VehicleState(fcu_connected=False, armed=True, landed_state="in_air"),
            "v: its flight controller is not connected, its landed state is unknown",
        ),
        (VehicleState(armed=True, landed_state="in_air"), None),
        (VehicleState(armed=True, landed_state="takeoff"), None),
    ],
)
def test_only_an_armed_vehicle_that_says_it_flies_is_airborne(
    state: VehicleState | None, reason: str | None
) -> None:
    assert not_airborne("v", state) == reason
