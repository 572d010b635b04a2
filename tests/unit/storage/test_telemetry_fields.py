"""One list of stored telemetry fields: the ORM model's columns. Everything that copies,
reads back, charts or exports them must carry each one, so a field added in one place and
not the others fails here."""

from __future__ import annotations

import dataclasses
import types
import typing
from typing import Any, get_args

import pytest

from backend.api.logs.common import Metric
from backend.api.schemas import Sample
from backend.exports import CSV_COLUMNS, ExportSample, csv_chunks, tlog_chunks
from backend.storage.logbook import SERIES_COLUMNS
from backend.storage.models import TELEMETRY_KEY_COLUMNS, TELEMETRY_STATE_COLUMNS, TelemetryRow
from protocol.messages import VehicleState
from tests.unit.exports.flight_data import flight

STATE = TELEMETRY_STATE_COLUMNS
COLUMNS = TelemetryRow.__table__.columns


def _nullable(annotation: Any) -> bool:
    return type(None) in get_args(annotation)


def _base(annotation: Any) -> type:
    """``float`` for ``float | None``."""
    if isinstance(annotation, types.UnionType):
        (base,) = (arg for arg in get_args(annotation) if arg is not type(None))
        return typing.cast(type, base)
    return typing.cast(type, annotation)


def test_the_model_is_the_list() -> None:
    assert set(STATE) | set(TELEMETRY_KEY_COLUMNS) == {column.name for column in COLUMNS}
    assert ("time", *STATE) == SERIES_COLUMNS  # what the logbook reads back
    # The CSV keeps its own column order (ExportSample's), a published format.
    assert CSV_COLUMNS[:2] == ["time_utc", "time_unix"]
    assert sorted(CSV_COLUMNS[2:]) == sorted(STATE)


def test_every_mirror_has_every_field_with_the_same_type() -> None:
    stored = {name: (COLUMNS[name].type.python_type, COLUMNS[name].nullable) for name in STATE}
    export_hints = typing.get_type_hints(ExportSample)
    mirrors = {
        "ExportSample": {
            name: (_base(hint), _nullable(hint))
            for name, hint in export_hints.items()
            if name != "time"
        },
        "api Sample": {
            name: (_base(info.annotation), _nullable(info.annotation))
            for name, info in Sample.model_fields.items()
            if name != "time"
        },
    }
    for mirror, fields in mirrors.items():
        assert fields == stored, mirror
    # The agent sends each (its snapshot holds more than is stored).
    sent = VehicleState.model_fields
    for name in STATE:
        assert name in sent, name
        assert _base(sent[name].annotation) is stored[name][0], name


def test_charted_metrics_are_stored_numbers() -> None:
    for metric in get_args(Metric):
        assert metric in STATE
        assert COLUMNS[metric].type.python_type is float


_OTHER_VALUE: dict[type, Any] = {float: 12.5, int: 7, bool: False, str: "LOITER"}


@pytest.mark.parametrize("name", STATE)
def test_every_field_reaches_the_csv_and_tlog_exports(name: str) -> None:
    base = ExportSample(
        time=1_700_000_000.0,
        lat=47.397742,
        lon=8.545594,
        alt_msl=488.25,
        alt_rel=10.0,
        heading_deg=90.0,
        groundspeed=5.0,
        climb_rate=1.0,
        battery_voltage=15.2,
        battery_remaining=80.0,
        mode="GUIDED",
        armed=True,
        gps_fix=3,
        satellites=12,
    )
    changed = dataclasses.replace(
        base, **{name: _OTHER_VALUE[_base(COLUMNS[name].type.python_type)]}
    )
    assert getattr(changed, name) != getattr(base, name)
    assert list(csv_chunks([changed])) != list(csv_chunks([base]))
    assert list(tlog_chunks(flight(), [changed], [])) != list(tlog_chunks(flight(), [base], []))
