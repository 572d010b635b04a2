from __future__ import annotations

import csv
import io
from dataclasses import replace

from backend.exports import CSV_COLUMNS, ExportSample, csv_chunks, iso_utc
from tests.unit.exports.flight_data import samples


def _parse(chunks: list[str]) -> list[dict[str, str]]:
    return list(csv.DictReader(io.StringIO("".join(chunks), newline="")))


def _float_or_none(cell: str) -> float | None:
    return None if cell == "" else float(cell)


def test_rows_parse_back_to_the_samples() -> None:
    flight_samples = samples(1234)

    chunks = list(csv_chunks(flight_samples))
    rows = _parse(chunks)

    assert len(chunks) == 3  # 500 rows per chunk
    assert list(rows[0]) == CSV_COLUMNS
    assert len(rows) == len(flight_samples)
    for row, sample in zip(rows, flight_samples, strict=True):
        assert row["time_utc"] == iso_utc(sample.time)
        assert float(row["time_unix"]) == sample.time
        for name in ("lat", "lon", "alt_msl", "alt_rel", "heading_deg", "groundspeed"):
            assert _float_or_none(row[name]) == getattr(sample, name)
        for name in ("climb_rate", "battery_voltage", "battery_remaining"):
            assert _float_or_none(row[name]) == getattr(sample, name)
        assert row["mode"] == sample.mode
        assert row["armed"] == ("true" if sample.armed else "false")
        assert int(row["gps_fix"]) == sample.gps_fix
        assert row["satellites"] == ("" if sample.satellites is None else str(sample.satellites))


def test_iso_time_is_utc() -> None:
    rows = _parse(list(csv_chunks(samples(1))))

    assert rows[0]["time_utc"] == "2023-11-14T22:13:20.000Z"


def test_text_is_quoted_and_formulas_are_defused() -> None:
    base = samples(1)[0]
    odd: list[ExportSample] = [
        replace(base, mode='AUTO, "with" quotes\nand a newline'),
        replace(base, mode="=HYPERLINK(1)"),
    ]

    rows = _parse(list(csv_chunks(odd)))

    assert rows[0]["mode"] == 'AUTO, "with" quotes\nand a newline'
    assert rows[1]["mode"] == "'=HYPERLINK(1)"


def test_no_samples_gives_the_header_only() -> None:
    assert "".join(csv_chunks([])) == ",".join(CSV_COLUMNS) + "\r\n"


def test_non_finite_numbers_are_empty() -> None:
    sample = replace(samples(4)[3], groundspeed=float("nan"), climb_rate=float("inf"))

    row = _parse(list(csv_chunks([sample])))[0]

    assert row["groundspeed"] == ""
    assert row["climb_rate"] == ""
