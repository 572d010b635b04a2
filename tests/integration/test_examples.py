"""The numbered examples in examples/, run as a user runs them, against the demo fleet,
so that they cannot rot: each must finish with status 0, and stop with a clear reason
and a non-zero status when the hub says no."""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
import textwrap
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from gcs.launcher import LocalFleet, free_port
from tests.conftest import FLEET_SPEEDUP
from tests.support.api import access_token, api_client
from tests.support.docs import page_holding
from tests.support.processes import running_fleet
from tests.support.waiting import poll_until
from tests.support.watcher import FleetWatcher, ready

pytestmark = pytest.mark.integration

EXAMPLES = Path(__file__).parents[2] / "examples"
# A take-off, a flight to a point and a landing at the fleet's speed-up, with room to spare.
EXAMPLE_TIMEOUT_S = 240


@pytest.fixture(scope="module")
def fleet(tmp_path_factory: pytest.TempPathFactory) -> Iterator[LocalFleet]:
    """A demo fleet of its own, as a new user finds it: full packs, home where it started,
    whatever the rest of the suite has flown the shared one through."""
    with running_fleet(
        tmp_path_factory.mktemp("examples"), vehicles=3, speedup=FLEET_SPEEDUP
    ) as local_fleet:
        yield local_fleet


@pytest.fixture(scope="module")
def fleet_admin_token(fleet: LocalFleet) -> str:
    return access_token(fleet.plan.hub_http, "admin", fleet.plan.admin_password)


@pytest.fixture(autouse=True)
def fleet_up(fleet: LocalFleet, fleet_admin_token: str) -> None:
    """Every vehicle of the demo fleet connected and reporting, as a user finds it."""
    with FleetWatcher(fleet.plan.hub_http, fleet_admin_token) as watcher:
        for index in range(fleet.plan.vehicles):
            watcher.wait_until(ready(fleet.vehicle_id(index)), 60, f"vehicle {index} ready")


def run_example(
    name: str, fleet: LocalFleet, *args: str, cwd: Path | None = None, **env: str
) -> subprocess.CompletedProcess[str]:
    """``python examples/<name> args`` with the hub's address and the admin's login in
    the environment (``env`` adds to or overrides them; an empty value removes one)."""
    environment = {key: value for key, value in os.environ.items() if not key.startswith("GCS_")}
    environment.update(
        GCS_HUB=fleet.plan.hub_http, GCS_USERNAME="admin", GCS_PASSWORD=fleet.plan.admin_password
    )
    environment.update(env)
    environment = {key: value for key, value in environment.items() if value}
    return subprocess.run(
        [sys.executable, str(EXAMPLES / name), *args],
        env=environment,
        cwd=cwd,
        capture_output=True,
        text=True,
        timeout=EXAMPLE_TIMEOUT_S,
        check=False,
    )


def succeeded(run: subprocess.CompletedProcess[str]) -> str:
    assert run.returncode == 0, f"exit {run.returncode}\n{run.stdout}\n{run.stderr}"
    return run.stdout


def failed(run: subprocess.CompletedProcess[str]) -> str:
    """The one line an example ends with when the hub refused something."""
    assert run.returncode == 1, f"exit {run.returncode}\n{run.stdout}\n{run.stderr}"
    assert "Traceback" not in run.stderr, run.stderr
    return run.stderr.strip()


def test_log_in_list_the_fleet_and_make_a_token(fleet: LocalFleet) -> None:
    name = "01_log_in_and_list_the_fleet.py"
    out = succeeded(run_example(name, fleet, "--api-token", "examples", "--scopes", "read"))
    assert "logged in as admin (admin)" in out
    assert all(fleet.vehicle_id(i) in out for i in range(fleet.plan.vehicles)), out
    token = out.rsplit("export GCS_TOKEN=", 1)[1].strip()

    # The token works on its own, for what its scope allows.
    out = succeeded(run_example(name, fleet, GCS_TOKEN=token, GCS_USERNAME="", GCS_PASSWORD=""))
    assert "logged in as admin (admin): read" in out
    refused = failed(run_example("04_command_a_group.py", fleet, GCS_TOKEN=token))
    assert refused.startswith("error: POST /api/v1/fleet/commands answered 403:"), refused


def test_without_credentials_the_example_says_how_to_log_in(fleet: LocalFleet) -> None:
    run = run_example("01_log_in_and_list_the_fleet.py", fleet, GCS_USERNAME="", GCS_PASSWORD="")
    assert failed(run) == "error: set GCS_TOKEN, or GCS_USERNAME and GCS_PASSWORD, to log in"

    run = run_example("01_log_in_and_list_the_fleet.py", fleet, GCS_PASSWORD="not-the-password")
    assert failed(run).startswith("error: POST /api/v1/auth/token answered 401:")


@pytest.mark.parametrize("name", sorted(path.name for path in EXAMPLES.glob("0*.py")))
def test_with_the_hub_unreachable_each_example_says_so(name: str, fleet: LocalFleet) -> None:
    """One line with the reason and status 1, not a traceback: nothing listens there."""
    nowhere = f"http://127.0.0.1:{free_port()}"
    message = failed(run_example(name, fleet, GCS_HUB=nowhere))
    assert message.startswith(f"error: cannot reach the hub at {nowhere}: "), message
    assert "refused" in message.lower(), message


def test_export_to_a_missing_folder_says_so(fleet: LocalFleet, tmp_path: Path) -> None:
    missing = tmp_path / "not-made-yet"
    run = run_example("05_export_a_flight.py", fleet, "--output", str(missing))
    assert failed(run) == f"error: the output folder {missing} does not exist"
    assert not missing.exists()


def test_every_example_uses_the_client_package() -> None:
    for example in EXAMPLES.glob("*.py"):
        source = example.read_text()
        assert "from gcs_client import" in source, example.name
        assert "import httpx" not in source, example.name
        assert "import websockets" not in source, example.name
        assert "from websockets" not in source, example.name
    assert not (EXAMPLES / "hubclient.py").exists()


def test_watch_the_fleet(fleet: LocalFleet) -> None:
    out = succeeded(run_example("02_watch_the_fleet.py", fleet, "--updates", "5"))
    lines = out.splitlines()
    assert lines[0].startswith("fleet: ")
    assert "pong: hello" in lines
    assert sum(line.startswith(fleet.vehicle_id(0)[:4]) for line in lines) >= 5


def test_the_feed_refusal_says_how_to_authenticate(fleet: LocalFleet) -> None:
    run = run_example("02_watch_the_fleet.py", fleet, GCS_TOKEN="not-a-token")
    assert failed(run).startswith("error: the hub closed the live feed: 4401 ")


def test_command_a_vehicle_then_export_its_flight(fleet: LocalFleet, tmp_path: Path) -> None:
    vehicle = fleet.vehicle_id(0)
    out = succeeded(run_example("03_command_a_vehicle.py", fleet, vehicle))
    assert f"{vehicle} takeoff:" in out
    assert f"{vehicle} landed and disarmed" in out

    out = succeeded(run_example("05_export_a_flight.py", fleet, "--vehicle", vehicle, cwd=tmp_path))
    (export,) = tmp_path.glob(f"{vehicle}_flight*.geojson")
    assert f"wrote {export.name}" in out or f"wrote {export}" in out
    features = json.loads(export.read_text())["features"]
    track = next(f for f in features if f["geometry"]["type"] == "LineString")
    assert len(track["geometry"]["coordinates"]) > 10


def test_a_refused_command_names_the_field(fleet: LocalFleet) -> None:
    run = run_example("03_command_a_vehicle.py", fleet, fleet.vehicle_id(1), "--altitude", "900")
    message = failed(run)
    assert message.startswith("error: POST /api/v1/vehicles/"), message
    assert "altitude" in message, message
    assert "500" in message, message


def test_command_a_group(fleet: LocalFleet) -> None:
    out = succeeded(run_example("04_command_a_group.py", fleet, "--altitude", "5"))
    vehicles = [fleet.vehicle_id(i) for i in range(fleet.plan.vehicles)]
    assert f"airborne: {', '.join(vehicles)}" in out
    assert f"landed and disarmed: {', '.join(vehicles)}" in out


def test_read_the_audit_log(fleet: LocalFleet, fleet_admin_token: str) -> None:
    """Each entry names the credential used, a filter narrows the log, and the example
    follows next_before_id from page to page without repeating or skipping an entry."""
    with api_client(fleet.plan.hub_http, fleet_admin_token) as api:
        # Eight entries at least (token.create each), for pages to follow.
        made = [
            api.post("/api/v1/auth/api-tokens", json={"name": name, "scopes": ["read"]})
            for name in ("wall", *(f"kiosk-{n}" for n in range(7)))
        ]
        assert all(answer.status_code == 201 for answer in made), made[0].text
        read_only = made[0].json()["token"]
    refused = failed(run_example("04_command_a_group.py", fleet, GCS_TOKEN=read_only))
    assert " answered 403:" in refused

    out = succeeded(run_example("06_read_the_audit_log.py", fleet, "--action", "denied"))
    newest = out.splitlines()[0].split()
    assert newest[2:8] == ["admin", "via", "wall", "denied", "POST", "/api/v1/fleet/commands"]

    out = succeeded(run_example("06_read_the_audit_log.py", fleet, "--last", "7", "--page", "3"))
    lines = out.splitlines()
    assert lines[-1] == "7 entries"
    ids = [int(line.split()[0]) for line in lines[:-1]]
    everything = api_get_audit(fleet, fleet_admin_token, limit=7)
    assert ids == [entry["id"] for entry in everything]  # newest first, none twice

    refused = failed(run_example("06_read_the_audit_log.py", fleet, "--action", "takeoff"))
    assert refused.startswith("error: GET /api/v1/audit answered 422:"), refused
    assert "command" in refused  # the valid actions are named


def api_get_audit(fleet: LocalFleet, token: str, limit: int) -> list[dict[str, Any]]:
    with api_client(fleet.plan.hub_http, token) as api:
        page = api.get("/api/v1/audit", params={"limit": limit})
    assert page.status_code == 200, page.text
    entries: list[dict[str, Any]] = page.json()["entries"]
    return entries


CLIENT_STEPS = "From nothing to a working client"


def readme_client_steps() -> list[str]:
    """The shell blocks of "From nothing to a working client" (the integrator's guide), in
    order."""
    text = page_holding(CLIENT_STEPS).read_text()
    section = text.split(CLIENT_STEPS, 1)[1]
    section = section.split("The scripts in [examples/]", 1)[0]
    return [textwrap.dedent(block) for block in re.findall(r"```sh\n(.*?)```", section, re.S)]


def json_values(text: str) -> list[Any]:
    """The JSON answers curl printed back to back (it adds no newline)."""
    decoder, values, at = json.JSONDecoder(), [], 0
    while (at := len(text) - len(text[at:].lstrip())) < len(text):
        value, at = decoder.raw_decode(text, at)
        values.append(value)
    return values


def test_the_readmes_client_steps_work_in_order(fleet: LocalFleet, tmp_path: Path) -> None:
    """A new user's path: each step's shell block, run in one shell as they come, with the
    HUB and PASSWORD step 0 says to export, in a folder of the user's own."""
    steps = readme_client_steps()
    assert len(steps) == 6, "one block for each of steps 1 to 6"
    vehicle = "sim_1"
    assert vehicle == fleet.vehicle_id(0)  # the id the guide's steps use
    watcher_token = access_token(fleet.plan.hub_http, "admin", fleet.plan.admin_password)
    with FleetWatcher(fleet.plan.hub_http, watcher_token) as watcher:
        watcher.wait_until(
            lambda _: bool(watcher.state(vehicle).get("ready_to_fly")), 120, f"{vehicle} ready"
        )
    # Step 3 runs the example as `.venv/bin/python examples/...` from a checkout.
    (tmp_path / ".venv").symlink_to(Path(sys.executable).parents[1])
    (tmp_path / "examples").symlink_to(EXAMPLES)
    separator = "=== step done ==="

    def shell(steps: list[str]) -> str:
        """The steps in one shell, as a user types them; what they printed."""
        script = "set -euo pipefail\n" + f"\necho\necho '{separator}'\n".join(steps)
        environment = {k: v for k, v in os.environ.items() if not k.startswith("GCS_")}
        environment |= {"HUB": fleet.plan.hub_http, "PASSWORD": fleet.plan.admin_password}
        run = subprocess.run(
            ["bash", "-c", script],
            env=environment,
            cwd=tmp_path,
            capture_output=True,
            text=True,
            timeout=EXAMPLE_TIMEOUT_S,
            check=False,
        )
        assert run.returncode == 0, f"{run.stdout}\n{run.stderr}"
        return run.stdout

    def finished_flights() -> list[int]:
        with api_client(fleet.plan.hub_http, watcher_token) as api:
            page = api.get("/api/v1/flights", params={"vehicle_id": vehicle}).json()
        return [flight["id"] for flight in page["flights"] if flight["end_time"]]

    flown_before = finished_flights()
    # Steps 1 to 4, then the user waits for the flight that step 5 exports to end.
    # The shell's TOKEN is kept for steps 5 and 6 as the user's shell would keep it.
    log_in, first_call, feed, command, _ = shell([*steps[:4], 'printf %s "$TOKEN" > token']).split(
        separator
    )
    # Both commands answered before the wait for their flight, so a refusal says so.
    takeoff, landing = json_values(command)
    assert takeoff["outcome"]["status"] == "accepted", takeoff
    [landed] = landing["results"]
    assert (landed["vehicle_id"], landed["outcome"]["status"]) == (vehicle, "accepted")
    [flown] = poll_until(
        lambda: [f for f in finished_flights() if f not in flown_before],
        120,
        f"{vehicle}'s flight to end",
    )
    export, audit = shell(["TOKEN=$(cat token)\n" + steps[4], steps[5]]).split(separator)

    [api_token] = json_values(log_in)
    assert api_token["name"] == "my-script"
    assert sorted(api_token["scopes"]) == ["command", "read"]
    assert api_token["token"]
    me, vehicles = json_values(first_call)
    assert me["username"] == "admin"
    assert vehicle in {v["id"] for v in vehicles}
    assert "pong: hello" in feed.splitlines()
    assert feed.strip().splitlines()[0].startswith("fleet: ")
    assert export.strip() == ""
    features = json.loads((tmp_path / "flight.geojson").read_text())["features"]
    [track] = [f for f in features if f["geometry"]["type"] == "LineString"]
    # The flight just flown: step 5 takes the newest that has ended.
    assert track["properties"]["flight_id"] == flown
    # Climbed to 9 m and landed, as step 4 does: a short track, but a track.
    assert len(track["geometry"]["coordinates"]) >= 2
    [page] = json_values(audit)
    assert 1 <= len(page["entries"]) <= 5
    assert "next_before_id" in page
