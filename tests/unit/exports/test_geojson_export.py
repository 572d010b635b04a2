from __future__ import annotations

import json
from dataclasses import replace
from typing import Any

import pytest

from backend.exports import ExportEvent, geojson_chunks, sample_position
from tests.unit.exports.flight_data import T0, events, flight, samples


def _collection(chunks: list[str]) -> dict[str, Any]:
    document: dict[str, Any] = json.loads("".join(chunks))
    assert document["type"] == "FeatureCollection"
    return document


def _position(index: int) -> list[float]:
    sample = samples()[index]
    assert sample.lon is not None
    assert sample.lat is not None
    assert sample.alt_msl is not None
    return [round(sample.lon, 7), round(sample.lat, 7), sample.alt_msl]


@pytest.mark.parametrize("chunk_chars", [64 * 1024, 16])
def test_track_is_a_linestring_with_a_time_per_position(chunk_chars: int) -> None:
    flight_samples = samples()
    positioned = [s for s in flight_samples if sample_position(s) is not None]

    chunks = list(geojson_chunks(flight(), flight_samples, events(), chunk_chars=chunk_chars))
    track = _collection(chunks)["features"][0]

    if chunk_chars == 16:
        assert len(chunks) > 10
    assert track["type"] == "Feature"
    assert track["geometry"]["type"] == "LineString"
    coordinates = track["geometry"]["coordinates"]
    assert len(coordinates) == len(positioned) == len(flight_samples) - 3
    assert coordinates[0] == _position(3)
    assert coordinates[-1] == _position(59)
    properties = track["properties"]
    assert properties["times"] == [round(s.time, 3) for s in positioned]
    assert properties["vehicle_id"] == "alpha-1"
    assert properties["flight_id"] == 7
    assert properties["start_time"] == "2023-11-14T22:13:20.000Z"
    assert properties["end_time"] == "2023-11-14T22:13:30.000Z"


def test_events_are_points_at_the_nearest_position_in_time() -> None:
    features = _collection(list(geojson_chunks(flight(), samples(), events())))["features"]

    points = features[1:]
    assert [p["geometry"]["type"] for p in points] == ["Point"] * 4
    by_text = {p["properties"]["text"]: p for p in points}
    # before the first position, and at a time without one: the first position
    assert by_text["PreArm: before take-off"]["geometry"]["coordinates"] == _position(3)
    assert by_text["Armed"]["geometry"]["coordinates"] == _position(3)
    # 4.04 s is nearer sample 40 (4.0 s) than sample 41 (4.1 s)
    guided = by_text["Mode GUIDED"]
    assert guided["geometry"]["coordinates"] == _position(40)
    assert guided["properties"]["position_time_unix"] == T0 + 4.0
    assert guided["properties"]["kind"] == "mode"
    assert guided["properties"]["severity"] is None
    assert guided["properties"]["time"] == "2023-11-14T22:13:24.040Z"
    # after the last sample: the last position
    assert by_text["x" * 80]["geometry"]["coordinates"] == _position(59)


def test_a_single_position_gives_no_track_but_still_places_events() -> None:
    only_one = samples()[:4]
    event = ExportEvent(time=T0, kind="armed", severity=6, text="Armed")

    features = _collection(list(geojson_chunks(flight(), only_one, [event])))["features"]

    assert [f["geometry"]["type"] for f in features] == ["Point"]
    assert features[0]["geometry"]["coordinates"] == _position(3)


def test_no_positions_gives_an_empty_collection() -> None:
    document = _collection(list(geojson_chunks(flight(), samples()[:3], events())))

    assert document["features"] == []


def test_a_sample_without_altitude_is_a_2d_position() -> None:
    flight_samples = samples(6)
    flight_samples[4] = replace(flight_samples[4], alt_msl=None)

    track = _collection(list(geojson_chunks(flight(), flight_samples, [])))["features"][0]

    assert [len(c) for c in track["geometry"]["coordinates"]] == [3, 2, 3]
