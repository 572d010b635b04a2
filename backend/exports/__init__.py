"""Streaming flight exports: CSV, GeoJSON and MAVLink .tlog, from plain iterables."""

from backend.exports.csv_export import CSV_COLUMNS, csv_chunks
from backend.exports.geojson_export import geojson_chunks
from backend.exports.samples import (
    ExportEvent,
    ExportFlight,
    ExportSample,
    iso_utc,
    sample_position,
)
from backend.exports.tlog_export import tlog_chunks

__all__ = [
    "CSV_COLUMNS",
    "ExportEvent",
    "ExportFlight",
    "ExportSample",
    "csv_chunks",
    "geojson_chunks",
    "iso_utc",
    "sample_position",
    "tlog_chunks",
]
