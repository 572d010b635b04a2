"""Users of each role and what they may not do, against a real hub."""

from __future__ import annotations

import time

import httpx
import pytest
from websockets.sync.client import ClientConnection

from protocol.messages import (
    Telemetry,
    VehicleState,
    encode,
)

PASSWORD = "correct horse battery"


# A 200 m square around the vehicle's home, near ArduPilot's SITL field.
HOME = (-35.363262, 149.165237)


def _user(admin_api: httpx.Client, name: str, role: str) -> str:
    response = admin_api.post(
        "/api/v1/users", json={"username": name, "password": PASSWORD, "role": role}
    )
    assert response.status_code == 201, response.text
    return name


def _report_position(agent: ClientConnection, seq: int = 0) -> None:
    state = VehicleState(
        lat=HOME[0],
        lon=HOME[1],
        alt_rel=0.0,
        home_lat=HOME[0],
        home_lon=HOME[1],
        battery_remaining=90.0,
        gps_fix=3,
        mode="GUIDED",
    )
    agent.send(encode(Telemetry(seq=seq, time=time.time(), state=state)))


def _no_command_reaches(agent: ClientConnection) -> None:
    with pytest.raises(TimeoutError):
        agent.recv(timeout=0.5)  # nothing may arrive: waiting briefly is the assertion
