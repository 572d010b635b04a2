"""The client package (gcs_client) against real hubs: an in-process hub for credentials and
errors, the shared fleet (hub, simulators and agents as processes) for vehicles, commands
and the live feed, and a cuttable TCP proxy for a link that drops."""

from __future__ import annotations

import asyncio
import time
from collections.abc import Iterator
from pathlib import Path

import httpx
import pytest

from gcs.launcher import LocalFleet, free_port
from gcs_client import (
    Conflict,
    FeedClosed,
    Forbidden,
    Hub,
    HubUnreachable,
    InvalidCommand,
    NotFound,
    SyncHub,
    Unauthorized,
    Unprocessable,
)
from gcs_client.models import (
    EventBatch,
    FleetSnapshot,
    TakeoffCommand,
    VehicleBatch,
    VehicleState,
    VehicleSummary,
)
from tests.conftest import ADMIN_PASSWORD, hub_settings
from tests.support.api import api_client
from tests.support.hub_server import running_hub
from tests.support.tcp_proxy import CuttableProxy

pytestmark = pytest.mark.integration

# Short enough that the test sees the client renew it, long enough for a request or two.
SHORT_TTL_S = 5.0


def admin(url: str) -> Hub:
    return Hub(url, username="admin", password=ADMIN_PASSWORD)


@pytest.fixture
def short_lived_hub(tmp_path: Path) -> Iterator[str]:
    """A hub whose access tokens last SHORT_TTL_S."""
    with running_hub(hub_settings(tmp_path, access_token_ttl_s=SHORT_TTL_S)) as url:
        yield url


def test_log_in_and_list_the_fleet_async_and_sync(fleet: LocalFleet) -> None:
    url = fleet.plan.hub_http
    vehicles = [fleet.vehicle_id(index) for index in range(fleet.plan.vehicles)]

    async def run() -> None:
        async with Hub(url, username="admin", password=fleet.plan.admin_password) as hub:
            me = await hub.auth.me()
            assert (me.username, me.role) == ("admin", "admin")
            listed = await hub.vehicles.list()
            assert all(isinstance(vehicle, VehicleSummary) for vehicle in listed)
            assert set(vehicles) <= {vehicle.id for vehicle in listed}
            one = await hub.vehicles.get(vehicles[0])
            assert one.connected
            assert isinstance(one.state, VehicleState)
            assert one.state.lat is not None

    asyncio.run(run())
    with SyncHub(url, username="admin", password=fleet.plan.admin_password) as hub:
        assert hub.auth.me().username == "admin"
        assert set(vehicles) <= {vehicle.id for vehicle in hub.vehicles.list()}


def test_errors_carry_the_hubs_reason(hub: str) -> None:
    with SyncHub(hub, username="admin", password=ADMIN_PASSWORD) as client:
        with pytest.raises(NotFound) as missing:
            client.vehicles.get("no_such_vehicle")
        assert missing.value.status == 404
        assert missing.value.reason == "unknown vehicle 'no_such_vehicle'"
        assert str(missing.value) == (
            "GET /api/v1/vehicles/no_such_vehicle answered 404: unknown vehicle 'no_such_vehicle'"
        )

        with pytest.raises(Unprocessable) as refused:
            client.audit.page(action="takeoff")
        [problem] = refused.value.problems
        assert problem.loc == ["query", "action"]
        assert "command" in refused.value.reason  # the valid actions are named
        assert refused.value.reason.startswith("query.action: ")

        user = {"username": "pilot", "password": "correct-horse-battery-staple-9", "role": "viewer"}
        client.request("POST", "/api/v1/users", json=user)
        with pytest.raises(Conflict) as exists:
            client.request("POST", "/api/v1/users", json=user)
        assert "pilot" in exists.value.reason

        read_only = client.auth.create_api_token("wall", ["read"]).token
        with pytest.raises(InvalidCommand, match="takeof"):
            client.vehicles.command("sim_1", "takeof")  # never sent

    with SyncHub(hub, token=read_only) as wall:
        assert wall.auth.me().permissions == ["read"]
        with pytest.raises(Forbidden) as forbidden:
            wall.fleet.command("land")
        assert forbidden.value.status == 403
        assert "command" in forbidden.value.reason

    with pytest.raises(Unauthorized) as wrong:
        SyncHub(hub, username="admin", password="not-the-password").__enter__()
    assert str(wrong.value).startswith("POST /api/v1/auth/token answered 401: ")

    nowhere = f"http://127.0.0.1:{free_port()}"
    with pytest.raises(HubUnreachable, match=f"cannot reach the hub at {nowhere}: .*refused"):
        _me(nowhere)


def _me(url: str) -> None:
    with SyncHub(url, token="anything") as client:
        client.auth.me()


def test_an_access_token_is_renewed_before_it_expires(short_lived_hub: str) -> None:
    async def run() -> str:
        async with admin(short_lived_hub) as hub:
            first = await hub.token()
            deadline = time.monotonic() + SHORT_TTL_S * 3
            # Requests keep working past the first token's lifetime: the client logs in
            # again shortly before it ends, so none goes out with a lapsed token.
            while time.monotonic() < deadline:
                assert (await hub.auth.me()).username == "admin"
                await asyncio.sleep(0.2)  # pacing the requests, not synchronisation
            assert await hub.token() != first
        return first

    first = asyncio.run(run())
    with httpx.Client(base_url=short_lived_hub) as raw:
        answer = raw.get("/api/v1/auth/me", headers={"Authorization": f"Bearer {first}"})
    assert answer.status_code == 401  # the first token did lapse


def test_a_revoked_token_is_replaced_by_logging_in_again(hub: str) -> None:
    with SyncHub(hub, username="admin", password=ADMIN_PASSWORD) as client:
        revoked = client.hub._token
        assert revoked is not None
        with api_client(hub, revoked) as other:
            assert other.post("/api/v1/auth/logout").status_code == 204
        assert client.auth.me().username == "admin"  # a 401, a login, the request again
        assert client.hub._token != revoked

    # With a token only, nothing to log in with: the 401 is the caller's.
    with SyncHub(hub, token=revoked) as client, pytest.raises(Unauthorized):
        client.auth.me()


def test_the_feed_logs_in_again_when_the_hub_closes_it_for_an_expired_token(
    short_lived_hub: str,
) -> None:
    """The hub closes a feed with 4401 when its token expires; the client logs in again
    and reconnects, and the caller sees a new fleet snapshot, not an error."""

    async def run() -> int:
        async with admin(short_lived_hub) as hub:
            feed = hub.feed()
            snapshots = 0
            async with asyncio.timeout(SHORT_TTL_S * 10):
                async for message in feed:
                    snapshots += isinstance(message, FleetSnapshot)
                    if snapshots == 2:
                        return feed.connections
        raise AssertionError("the feed ended")

    # Each connection lasts as long as its token; one could end before its snapshot on a
    # busy machine, so two snapshots may take more than two connections.
    assert asyncio.run(run()) >= 2

    async def refused() -> None:
        async with Hub(short_lived_hub, token="not-a-token") as hub:
            async for _ in hub.feed():
                pass

    with pytest.raises(FeedClosed) as closed:
        asyncio.run(refused())
    assert closed.value.code == 4401
    assert str(closed.value).startswith("the hub closed the live feed: 4401 ")


def test_the_feed_reconnects_after_the_link_drops_and_resumes(fleet: LocalFleet) -> None:
    """Through a proxy that is cut mid-feed: the iterator carries on with a new connection,
    the hub's fresh snapshot, then the events the flight log stored during the gap."""
    hub_port = int(fleet.plan.hub_http.rsplit(":", 1)[1])
    vehicle = fleet.vehicle_id(0)

    async def run() -> None:
        with CuttableProxy(("127.0.0.1", hub_port)) as proxy:
            url = f"http://127.0.0.1:{proxy.port}"
            async with (
                Hub(url, username="admin", password=fleet.plan.admin_password) as hub,
                Hub(
                    fleet.plan.hub_http, username="admin", password=fleet.plan.admin_password
                ) as direct,
            ):
                feed = hub.feed()
                seen: list[str] = []
                async with asyncio.timeout(120):
                    async for message in feed:
                        seen.append(message.type)
                        if isinstance(message, FleetSnapshot) and feed.connections == 1:
                            await ask_a_parameter(direct)  # an event for the feed to carry
                        if isinstance(message, EventBatch) and feed.connections == 1:
                            # Cut the link, and make another event while the feed is away
                            # (a command's result, which goes to the flight log).
                            proxy.cut()
                            cut_at = time.time()
                            await ask_a_parameter(direct)
                            await poll_until_async_hub(direct, cut_at)
                            proxy.start()
                        if feed.connections == 2 and isinstance(message, VehicleBatch):
                            break
                assert seen.count("fleet") == 2, seen
                after = seen[seen.index("fleet", seen.index("fleet") + 1) :]
                assert after[1] == "events", after  # the gap's events, before anything new

    async def ask_a_parameter(hub: Hub) -> None:
        await hub.vehicles.command(vehicle, "param_get", param="SYSID_THISMAV")

    async def poll_until_async_hub(hub: Hub, since: float) -> None:
        """Until the flight log holds the command's event (its writer batches)."""
        async with asyncio.timeout(30):
            while True:  # polling the store, which announces nothing
                page = await hub.events.page(vehicle_id=vehicle, kind="command", start=since)
                if page.events:
                    return
                await asyncio.sleep(0.1)

    asyncio.run(run())


def test_command_a_vehicle_and_follow_it(settled_fleet: LocalFleet) -> None:
    vehicle = settled_fleet.vehicle_id(1)
    password = settled_fleet.plan.admin_password

    async def run() -> None:
        async with (
            Hub(settled_fleet.plan.hub_http, username="admin", password=password) as hub,
            hub.watch() as fleet,
        ):
            with pytest.raises(Unprocessable) as refused:
                await hub.vehicles.command(vehicle, "takeoff", altitude=900)
            assert "altitude" in refused.value.reason
            await fleet.wait_until(lambda: fleet.state(vehicle).ready_to_fly, 120, "ready")
            answer = await hub.vehicles.command(vehicle, TakeoffCommand(altitude=5))
            assert answer.outcome.status == "accepted"
            await fleet.wait_until(lambda: (fleet.state(vehicle).alt_rel or 0) > 4, 120, "climb")
            group = await hub.fleet.command("land", [vehicle])
            [result] = group.results
            assert result.outcome is not None
            assert result.outcome.status == "accepted"
            await fleet.wait_until(lambda: not fleet.state(vehicle).armed, 120, "landed")

    asyncio.run(run())


def test_telemetry_yields_every_vehicle_then_each_change(fleet: LocalFleet) -> None:
    vehicles = {fleet.vehicle_id(index) for index in range(fleet.plan.vehicles)}

    def follow() -> set[str]:
        with SyncHub(
            fleet.plan.hub_http, username="admin", password=fleet.plan.admin_password
        ) as hub:
            seen: dict[str, int] = {}
            for vehicle in hub.telemetry():
                assert vehicle.autopilot  # filled in from the snapshot, though left out
                seen[vehicle.id] = seen.get(vehicle.id, 0) + 1
                if vehicles <= set(seen) and min(seen[v] for v in vehicles) >= 3:
                    return set(seen)
        raise AssertionError("the feed ended")

    assert vehicles <= follow()
