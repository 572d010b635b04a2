"""Exporters consume their samples lazily: a long flight is never held in memory."""

from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator
from typing import Any

import pytest

from backend.exports import ExportSample, csv_chunks, geojson_chunks, tlog_chunks
from tests.unit.exports.flight_data import flight, sample

FLIGHT_SAMPLES = 100_000


class CountingSamples:
    """A one-shot generator of samples that counts how many were taken."""

    def __init__(self, count: int) -> None:
        self.count = count
        self.taken = 0

    def __iter__(self) -> Iterator[ExportSample]:
        for index in range(self.count):
            self.taken += 1
            yield sample(index)


Exporter = Callable[[Iterable[ExportSample]], Iterator[Any]]

EXPORTERS: dict[str, Exporter] = {
    "csv": csv_chunks,
    "geojson": lambda samples: geojson_chunks(flight(), samples, []),
    "tlog": lambda samples: tlog_chunks(flight(), samples, []),
}


@pytest.mark.parametrize("name", EXPORTERS)
def test_first_chunk_comes_before_the_samples_run_out(name: str) -> None:
    samples = CountingSamples(FLIGHT_SAMPLES)
    chunks = EXPORTERS[name](iter(samples))

    first = next(chunks)

    assert first
    assert 0 < samples.taken < FLIGHT_SAMPLES // 10
