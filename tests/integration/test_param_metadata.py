"""ArduPilot's parameter metadata on the hub (GCS_PARAM_METADATA_DIR, apm.pdef.json per
firmware family, as ArduPilot publishes it): a write outside a parameter's range or values
is refused before anything reaches the vehicle, whichever route it takes, and answers say
what the parameter means. A real hub on loopback; the test plays the agent on its socket."""

from __future__ import annotations

import json
import threading
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import httpx
import pytest
from websockets.sync.client import ClientConnection, connect

from protocol.messages import AGENT_WS_PATH, CommandOutcome, CommandResult, encode
from tests.conftest import hub_settings
from tests.support.hellos import agent_hello
from tests.support.hub_server import running_hub

pytestmark = pytest.mark.integration

METADATA = Path(__file__).parent.parent / "data" / "param_metadata"


@pytest.fixture
def hub(tmp_path: Path) -> Iterator[str]:
    with running_hub(hub_settings(tmp_path, param_metadata_dir=METADATA)) as base_url:
        yield base_url


class PlayedAgent:
    """An ArduCopter's agent that answers every command by accepting it, and keeps them."""

    def __init__(self, hub: str, token: str) -> None:
        url = hub.replace("http://", "ws://") + AGENT_WS_PATH
        self.socket: ClientConnection = connect(
            url, additional_headers={"Authorization": f"Bearer {token}"}
        )
        self.socket.send(encode(agent_hello("v1")))
        assert json.loads(self.socket.recv(timeout=5))["type"] == "welcome"
        self.commands: list[dict[str, Any]] = []
        self._reader = threading.Thread(target=self._answer, daemon=True)
        self._reader.start()

    def _answer(self) -> None:
        try:
            for frame in self.socket:
                message = json.loads(frame)
                if message["type"] != "command":
                    continue
                command = message["command"]
                self.commands.append(command)
                value = command.get("value", 3.0)
                outcome = CommandOutcome(
                    status="accepted", message="ok", values={command["param"]: value}
                )
                self.socket.send(
                    encode(CommandResult(request_id=message["request_id"], outcome=outcome))
                )
        except Exception:
            return

    def close(self) -> None:
        self.socket.close()
        self._reader.join(5)


def test_an_arducopter_write_outside_its_metadata_is_refused_before_the_vehicle(
    hub: str, enrol: Callable[[str], str], admin_api: httpx.Client
) -> None:
    agent = PlayedAgent(hub, enrol("v1"))
    try:
        url = "/api/v1/vehicles/v1/params"
        too_fast = admin_api.put(f"{url}/WPNAV_SPEED", json={"value": 5000})
        assert too_fast.status_code == 409, too_fast.text
        assert too_fast.json()["detail"] == "WPNAV_SPEED: 5000 is outside its range 10..2000 cm/s"
        not_a_value = admin_api.post(
            "/api/v1/vehicles/v1/commands",
            json={"name": "param_set", "param": "FS_THR_ENABLE", "value": 2},
        )
        assert not_a_value.status_code == 409, not_a_value.text
        assert (
            "FS_THR_ENABLE: 2 is not one of the values it takes (0 Disabled, " in not_a_value.text
        )
        assert agent.commands == []  # neither reached the vehicle

        written = admin_api.put(f"{url}/WPNAV_SPEED", json={"value": 1000})
        assert written.status_code == 200, written.text
        body = written.json()
        assert body["range_checked"] is True
        assert body["metadata"]["source"] == "file"
        assert body["metadata"]["units"] == "cm/s"
        assert body["metadata"]["description"] == "Waypoint Horizontal Speed Target"
        assert (body["metadata"]["min"], body["metadata"]["max"]) == (10, 2000)

        # A parameter the file does not describe: sent, and said to be unchecked.
        unknown = admin_api.put(f"{url}/RC_OVERRIDE_TIME", json={"value": 3})
        assert unknown.status_code == 200, unknown.text
        assert unknown.json()["range_checked"] is False
        assert unknown.json()["metadata"] is None
        read = admin_api.get(f"{url}/FS_THR_ENABLE").json()
        assert read["metadata"]["values"][1] == {"value": 1, "description": "Enabled always RTL"}
        assert read["range_checked"] is None  # a read checks nothing
    finally:
        agent.close()
