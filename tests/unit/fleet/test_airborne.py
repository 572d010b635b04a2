"""Whether a vehicle flies, for the commands that need it in the air: the autopilot's
landed state and arming, anything unknown refused as unknown."""

from __future__ import annotations

import pytest

from backend.fleet.airborne import TakeoffClock, flies, not_airborne
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


GROUND = VehicleState(landed_state="on_ground")
FLYING = VehicleState(armed=True, landed_state="in_air")
UNKNOWN = VehicleState(fcu_connected=False, armed=True, landed_state="in_air")


def test_the_take_off_clock_starts_at_the_first_flying_state_after_the_ground() -> None:
    clock = TakeoffClock()
    clock.observe(GROUND, 100.0)
    assert clock.airborne_since is None
    clock.observe(VehicleState(armed=True, landed_state="takeoff"), 105.0)
    clock.observe(FLYING, 110.0)
    clock.observe(UNKNOWN, 120.0)  # a flight controller link blip keeps the flight
    clock.observe(FLYING, 130.0)
    assert clock.airborne_since == 105.0
    clock.observe(GROUND, 200.0)
    assert clock.airborne_since is None
    clock.observe(FLYING, 300.0)
    assert clock.airborne_since == 300.0


def test_a_vehicle_first_seen_flying_has_no_known_take_off() -> None:
    """The hub started (or heard of it) mid-flight: unknown, not 'since now'."""
    clock = TakeoffClock()
    clock.observe(FLYING, 50.0)
    clock.observe(FLYING, 60.0)
    assert clock.airborne_since is None
    assert flies(VehicleState(armed=False, landed_state="in_air")) is None
    assert flies(VehicleState(armed=False)) is False
