"""The client's models (gcs_client/models.py) are generated from the hub's OpenAPI document
and the wire protocol, and kept in step with them, as the dashboard's types are."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[3]
GENERATOR = ROOT / "scripts" / "gen_client_models.py"


def generator_module():  # type: ignore[no-untyped-def]
    spec = importlib.util.spec_from_file_location("gen_client_models", GENERATOR)
    assert spec is not None
    assert spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return module


def test_the_generated_models_match_the_hub_and_the_protocol() -> None:
    generated = generator_module().current()
    committed = (ROOT / "gcs_client" / "models.py").read_text()
    assert generated == committed, (
        "gcs_client/models.py is stale: run .venv/bin/python scripts/gen_client_models.py"
    )


def test_the_models_read_what_the_hub_and_the_feed_send() -> None:
    from gcs_client import models
    from protocol.messages import VehicleState, VehicleSummary

    state = VehicleState(lat=47.4, lon=8.5, alt_rel=12.5, armed=True, battery_remaining=80)
    summary = VehicleSummary(
        id="sim_1",
        autopilot="ardupilot",
        vehicle_type="multirotor",
        modes=["GUIDED"],
        connected=True,
        last_seen=1.0,
        state=state,
    )
    frame = '{"type": "fleet", "vehicles": [' + summary.model_dump_json() + "]}"
    read = models.FEEDMESSAGE_ADAPTER.validate_json(frame)
    assert isinstance(read, models.FleetSnapshot)
    [vehicle] = read.vehicles
    assert vehicle.state is not None
    assert (vehicle.state.alt_rel, vehicle.state.armed) == (12.5, True)
    # A field a newer hub adds is kept, not refused.
    newer = models.VehicleState.model_validate({"mode": "LAND", "wind_speed": 3.0})
    assert newer.model_extra == {"wind_speed": 3.0}
    # A command is picked by its name, with its tag filled in.
    assert models.COMMAND_ADAPTER.validate_python({"name": "land"}) == models.LandCommand()


def test_the_api_document_and_the_readme_point_to_the_client() -> None:
    from backend.openapi_document import openapi_document

    assert "docs/client.md" in openapi_document()["info"]["description"]
    assert (ROOT / "docs" / "client.md").is_file()
    assert "| Python client | `gcs_client/`" in (ROOT / "README.md").read_text()
