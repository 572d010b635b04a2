"""A flight as an RFC 7946 GeoJSON FeatureCollection, written incrementally.

Layout::

    {"type": "FeatureCollection", "features": [
      {"type": "Feature",
       "geometry": {"type": "LineString", "coordinates": [[lon, lat, alt_msl], ...]},
       "properties": {"kind": "track", "vehicle_id": ..., "flight_id": ...,
                      "start_time": ISO, "end_time": ISO | null,
                      "times": [unix seconds of each coordinate, ...]}},
      {"type": "Feature", "geometry": {"type": "Point", "coordinates": [lon, lat, alt]},
       "properties": {"kind": ..., "severity": ..., "text": ..., "time": ISO,
                      "time_unix": ..., "position_time_unix": ...}},
      ...
    ]}

* Only samples with a position (:func:`sample_position`) make coordinates; a sample
  without ``alt_msl`` makes a 2D ``[lon, lat]`` position.
* A LineString needs at least two positions, so the track Feature is only written
  when the flight has two or more; otherwise the collection holds just the events.
* An event has no position of its own: its Point is placed at the positioned sample
  nearest to it in time (``position_time_unix`` says which), and events are left out
  when the flight has no position at all.

Memory: the coordinates stream straight through. The ``times`` array has to follow
them (it lives in the properties, written after the geometry), so it is kept as a
packed ``array('d')``: 8 bytes per position, under 3 MB for ten hours at 10 Hz.
Events are few; they are read into a list and sorted by time. Samples are expected
in time order, as the hub stores them.
"""

from __future__ import annotations

import json
from array import array
from collections.abc import Iterable, Iterator
from dataclasses import dataclass

from backend.exports.samples import (
    ExportEvent,
    ExportFlight,
    ExportSample,
    finite,
    iso_utc,
    sample_position,
)

CHUNK_CHARS = 64 * 1024

Position = list[float]


def _dumps(value: object) -> str:
    return json.dumps(value, separators=(",", ":"), allow_nan=False)


def _position(sample: ExportSample, lat_lon: tuple[float, float]) -> Position:
    lat, lon = lat_lon
    position = [round(lon, 7), round(lat, 7)]
    if (alt := finite(sample.alt_msl)) is not None:
        position.append(round(alt, 2))
    return position


@dataclass
class _PlacedEvent:
    event: ExportEvent
    position: Position
    position_time: float


class _EventPlacer:
    """Gives each event the position of the positioned sample nearest to it in time."""

    def __init__(self, events: Iterable[ExportEvent]) -> None:
        self._pending = sorted(events, key=lambda event: event.time)
        self._next = 0
        self._previous: tuple[float, Position] | None = None
        self.placed: list[_PlacedEvent] = []

    def feed(self, time: float, position: Position) -> None:
        while self._next < len(self._pending) and self._pending[self._next].time <= time:
            event = self._pending[self._next]
            self._next += 1
            if self._previous is not None and event.time - self._previous[0] < time - event.time:
                self._place(event, *self._previous)
            else:
                self._place(event, time, position)
        self._previous = (time, position)

    def finish(self) -> list[_PlacedEvent]:
        if self._previous is not None:
            for event in self._pending[self._next :]:
                self._place(event, *self._previous)
        self._next = len(self._pending)
        return self.placed

    def _place(self, event: ExportEvent, time: float, position: Position) -> None:
        self.placed.append(_PlacedEvent(event, position, time))


class _Chunks:
    def __init__(self, size: int) -> None:
        self._parts: list[str] = []
        self._chars = 0
        self._size = size

    def write(self, text: str) -> None:
        self._parts.append(text)
        self._chars += len(text)

    @property
    def full(self) -> bool:
        return self._chars >= self._size

    def take(self) -> str:
        text = "".join(self._parts)
        self._parts.clear()
        self._chars = 0
        return text


def _track_properties_opening(flight: ExportFlight) -> str:
    """The track's properties object up to the opening of its ``times`` array."""
    properties = {
        "kind": "track",
        "vehicle_id": flight.vehicle_id,
        "flight_id": flight.id,
        "autopilot": flight.autopilot,
        "vehicle_type": flight.vehicle_type,
        "start_time": iso_utc(flight.start_time),
        "end_time": iso_utc(flight.end_time) if flight.end_time is not None else None,
    }
    return _dumps(properties)[:-1] + ',"times":['


def _event_feature(placed: _PlacedEvent) -> str:
    event = placed.event
    return _dumps(
        {
            "type": "Feature",
            "geometry": {"type": "Point", "coordinates": placed.position},
            "properties": {
                "kind": event.kind,
                "severity": event.severity,
                "text": event.text,
                "time": iso_utc(event.time),
                "time_unix": event.time,
                "position_time_unix": placed.position_time,
            },
        }
    )


def geojson_chunks(
    flight: ExportFlight,
    samples: Iterable[ExportSample],
    events: Iterable[ExportEvent],
    chunk_chars: int = CHUNK_CHARS,
) -> Iterator[str]:
    """The FeatureCollection described in the module docstring, in chunks of text."""
    out = _Chunks(chunk_chars)
    placer = _EventPlacer(events)
    times: array[float] = array("d")
    first: Position | None = None
    out.write('{"type":"FeatureCollection","features":[')
    for sample in samples:
        lat_lon = sample_position(sample)
        if lat_lon is None:
            continue
        position = _position(sample, lat_lon)
        placer.feed(sample.time, position)
        times.append(round(sample.time, 3))
        if first is None:
            first = position
            continue
        if len(times) == 2:
            out.write('{"type":"Feature","geometry":{"type":"LineString","coordinates":[')
            out.write(_dumps(first))
        out.write("," + _dumps(position))
        if out.full:
            yield out.take()
    features = 0
    if len(times) >= 2:
        out.write(']},"properties":' + _track_properties_opening(flight))
        for index, time in enumerate(times):
            out.write(_dumps(time) if index == 0 else "," + _dumps(time))
            if out.full:
                yield out.take()
        out.write("]}}")
        features = 1
    for placed in placer.finish():
        out.write(("," if features else "") + _event_feature(placed))
        features += 1
        if out.full:
            yield out.take()
    out.write("]}")
    yield out.take()
