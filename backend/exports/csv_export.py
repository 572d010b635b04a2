"""A flight's samples as CSV (RFC 4180), streamed in chunks of rows."""

from __future__ import annotations

import csv
import io
import math
from collections.abc import Iterable, Iterator
from dataclasses import fields

from backend.exports.samples import ExportSample, iso_utc

ROWS_PER_CHUNK = 500

_SAMPLE_FIELDS = [field.name for field in fields(ExportSample) if field.name != "time"]
CSV_COLUMNS = ["time_utc", "time_unix", *_SAMPLE_FIELDS]

# Spreadsheets run cells starting with these as formulas; the mode name is the only
# text the vehicle controls, so it is defused the way OWASP recommends.
_FORMULA_PREFIXES = ("=", "+", "-", "@", "\t", "\r")


def _cell(value: object) -> object:
    if value is None:
        return ""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return repr(value) if math.isfinite(value) else ""
    if isinstance(value, str) and value.startswith(_FORMULA_PREFIXES):
        return "'" + value
    return value


def _row(sample: ExportSample) -> list[object]:
    return [
        iso_utc(sample.time),
        repr(sample.time),
        *(_cell(getattr(sample, name)) for name in _SAMPLE_FIELDS),
    ]


def csv_chunks(
    samples: Iterable[ExportSample], rows_per_chunk: int = ROWS_PER_CHUNK
) -> Iterator[str]:
    """The header, then one row per sample: empty cells for unknowns, booleans as true/false.

    Times are given twice, as ISO 8601 UTC for people and unix seconds for programs.
    Lines end in CRLF as RFC 4180 says; open the result with ``newline=""``.
    """
    buffer = io.StringIO()
    writer = csv.writer(buffer)
    writer.writerow(CSV_COLUMNS)
    rows = 0
    for sample in samples:
        writer.writerow(_row(sample))
        rows += 1
        if rows >= rows_per_chunk:
            yield buffer.getvalue()
            buffer.seek(0)
            buffer.truncate()
            rows = 0
    yield buffer.getvalue()
