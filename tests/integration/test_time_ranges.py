"""Range queries include both bounds, at a sample's exact stored time, on SQLite and on
PostgreSQL: Unix seconds as the API returned them, and date-times printed from them."""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator
from datetime import UTC, datetime

import httpx
import pytest

from protocol.messages import Telemetry, VehicleState, encode
from tests.conftest import ADMIN_PASSWORD, hub_settings
from tests.support.agents import scripted_agent
from tests.support.api import access_token, api_client
from tests.support.hub_server import running_hub
from tests.support.waiting import poll_until

# Finer than a microsecond, as a clock's float seconds are.
TIMES = [1_700_000_000.1234567, 1_700_000_000.2234567, 1_700_000_000.3234567]


@pytest.fixture(scope="module")
def stored(
    module_database_url: str, tmp_path_factory: pytest.TempPathFactory
) -> Iterator[httpx.Client]:
    """A hub on the given database holding three samples of vehicle v1 at ``TIMES``; one
    per module and database, as the tests only read it."""
    data_dir = tmp_path_factory.mktemp("hub")
    with running_hub(hub_settings(data_dir, database_url=module_database_url)) as base:
        token = access_token(base, "admin", ADMIN_PASSWORD)
        with api_client(base, token) as api:
            agent_token = api.post("/api/v1/vehicles/v1/agent-tokens").json()["token"]
            with scripted_agent(base, "v1", agent_token) as agent:
                for seq, at in enumerate(TIMES):
                    agent.send(encode(Telemetry(seq=seq, time=at, state=VehicleState())))
                poll_until(lambda: len(_times(api, 0, 1e10)) == 3, 10, "three samples stored")
            yield api


def _times(api: httpx.Client, start: object, end: object) -> list[float]:
    response = api.get(
        "/api/v1/vehicles/v1/telemetry", params={"start": str(start), "end": str(end)}
    )
    assert response.status_code == 200, response.text
    return [sample["time"] for sample in response.json()["samples"]]


def _iso(at: float, rounding: Callable[[float], float]) -> str:
    micros = rounding(at * 1e6) / 1e6
    return datetime.fromtimestamp(micros, UTC).isoformat().replace("+00:00", "Z")


def test_both_bounds_include_a_sample_at_its_exact_time(stored: httpx.Client) -> None:
    api = stored
    returned = _times(api, 0, 1e10)
    assert returned == TIMES  # the API gives the stored times back exactly
    for at in returned:
        assert _times(api, repr(at), repr(at)) == [at]
    assert _times(api, repr(TIMES[0]), repr(TIMES[2])) == TIMES
    assert _times(api, repr(TIMES[1]), repr(TIMES[2])) == TIMES[1:]
    assert _times(api, repr(TIMES[0]), repr(TIMES[1])) == TIMES[:2]


@pytest.mark.parametrize("rounding", [round, math.floor, math.ceil], ids=["round", "floor", "ceil"])
def test_date_time_bounds_printed_from_a_sample_include_it(
    stored: httpx.Client, rounding: Callable[[float], float]
) -> None:
    api = stored
    for at in TIMES:
        assert _times(api, _iso(at, rounding), _iso(at, rounding)) == [at]
    assert _times(api, _iso(TIMES[1], rounding), _iso(TIMES[2], rounding)) == TIMES[1:]
