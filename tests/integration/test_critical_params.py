"""Safety-critical parameters (failsafes, fence, arming checks) are an admin's to change."""

from __future__ import annotations

import json
import threading
from collections.abc import Iterator
from contextlib import contextmanager

import httpx
import pytest

from backend.safety.critical_params import critical_reason
from protocol.messages import (
    AGENT_WS_PATH,
    PROTOCOL_VERSION,
    CommandOutcome,
    CommandResult,
    Hello,
    encode,
)
from tests.support.accounts import PASSWORD, _no_command_reaches, _user
from tests.support.agents import ScriptedAgent, websocket
from tests.support.api import access_token, api_client


@contextmanager
def agent_of(base: str, token: str, vehicle: str, autopilot: str) -> Iterator[ScriptedAgent]:
    hello = Hello(
        protocol=PROTOCOL_VERSION,
        vehicle_id=vehicle,
        autopilot=autopilot,
        vehicle_type="multirotor",
        system_id=1,
        modes=["GUIDED", "LAND"],
        agent_version="test",
        stream_id="s1",
    )
    url = base.replace("http://", "ws://") + AGENT_WS_PATH
    with websocket(url, {"Authorization": f"Bearer {token}"}) as socket:
        socket.send(encode(hello))
        assert json.loads(socket.recv(timeout=5))["type"] == "welcome"
        yield ScriptedAgent(socket, delivery=False)


@contextmanager
def answering_param_set(agent: ScriptedAgent, value: float) -> Iterator[dict[str, object]]:
    """Answer the next command (a param_set) as the flight controller's echo would, from a
    helper thread; yields the command the agent received, filled in on the way out."""
    received: dict[str, object] = {}

    def answer() -> None:
        request = json.loads(agent.recv(timeout=10))
        received.update(request["command"])
        outcome = CommandOutcome(
            status="accepted", message="set", values={request["command"]["param"]: value}
        )
        agent.send(encode(CommandResult(request_id=request["request_id"], outcome=outcome)))

    worker = threading.Thread(target=answer, daemon=True)
    worker.start()
    yield received
    worker.join(10)


@pytest.mark.parametrize(
    ("autopilot", "param"),
    [
        ("ardupilot", "BATT_FS_LOW_ACT"),
        ("ardupilot", "FENCE_ENABLE"),
        ("ardupilot", "ARMING_CHECK"),
        ("ardupilot", "FS_GCS_ENABLE"),
        ("ardupilot", "SYSID_MYGCS"),
        ("ardupilot", "MAV_GCS_SYSID"),
        ("ardupilot", "MAV_GCS_SYSID_HI"),
        ("px4", "NAV_DLL_ACT"),
        ("px4", "COM_LOW_BAT_ACT"),
        ("px4", "GF_ACTION"),
        ("px4", "CBRK_SUPPLY_CHK"),
        ("px4", "COM_RC_IN_MODE"),
    ],
)
def test_an_operator_cannot_change_a_safety_critical_parameter(
    hub: str,
    admin_api: httpx.Client,
    autopilot: str,
    param: str,
) -> None:
    token = admin_api.post("/api/v1/vehicles/v1/agent-tokens").json()["token"]
    with (
        agent_of(hub, token, "v1", autopilot) as agent,
        api_client(
            hub, access_token(hub, _user(admin_api, "olivia", "operator"), PASSWORD)
        ) as operator,
    ):
        for refused in (
            operator.put(f"/api/v1/vehicles/v1/params/{param}", json={"value": 0}),
            operator.post(
                "/api/v1/vehicles/v1/commands",
                json={"name": "param_set", "param": param, "value": 0},
            ),
        ):
            assert refused.status_code == 403, refused.text
            detail = refused.json()["detail"]
            assert param in detail
            assert "safety-critical" in detail
            assert "only an admin" in detail
        _no_command_reaches(agent)

        # An ordinary parameter is still the operator's to set.
        ordinary = "WPNAV_SPEED" if autopilot == "ardupilot" else "MPC_XY_CRUISE"
        with answering_param_set(agent, 5) as received:
            response = operator.put(f"/api/v1/vehicles/v1/params/{ordinary}", json={"value": 5})
            assert response.status_code == 200, response.text
        assert received["param"] == ordinary

        # An admin may change a critical one; the audit log says that it was.
        with answering_param_set(agent, 0) as received:
            allowed = admin_api.put(f"/api/v1/vehicles/v1/params/{param}", json={"value": 0})
            assert allowed.status_code == 200, allowed.text
        assert received["param"] == param

    entries = admin_api.get("/api/v1/audit", params={"action": "command"}).json()["entries"]
    by_outcome = {(entry["actor"], entry["outcome"]) for entry in entries}
    assert ("olivia", "refused") in by_outcome
    admin_entry = next(entry for entry in entries if entry["actor"] == "admin")
    assert admin_entry["detail"]["safety_critical"] == critical_reason(autopilot, param)


def test_the_lists_are_per_autopilot() -> None:
    assert critical_reason("ardupilot", "BATT2_FS_CRT_ACT") == "battery failsafe"
    assert critical_reason("ardupilot", "WPNAV_SPEED") is None
    assert critical_reason("ardupilot", "RC_OVERRIDE_TIME") is not None  # -1: held for ever
    assert critical_reason("px4", "FENCE_ENABLE") is None  # not a PX4 parameter
    assert critical_reason("px4", "COM_DL_LOSS_T") is not None
    assert critical_reason("generic", "FENCE_ENABLE") == "geofence"  # unknown: both lists
    assert critical_reason("generic", "GF_ACTION") == "geofence"
