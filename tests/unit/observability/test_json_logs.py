"""GCS_LOG_FORMAT=json: each log record is one line of JSON a log shipper can parse."""

from __future__ import annotations

import io
import json
import logging

from backend.observability.logs import JsonFormatter, use_json_logs


def test_a_record_is_one_json_line_with_its_exception() -> None:
    stream = io.StringIO()
    handler = logging.StreamHandler(stream)
    logger = logging.getLogger("test.json_logs")
    logger.addHandler(handler)
    logger.propagate = False
    try:
        use_json_logs([logger])
        assert isinstance(handler.formatter, JsonFormatter)
        try:
            raise ValueError("broken")
        except ValueError:
            logger.exception("agent %s said:\nline two", "v1")
    finally:
        logger.removeHandler(handler)
    lines = stream.getvalue().splitlines()
    assert len(lines) == 1
    entry = json.loads(lines[0])
    assert entry["level"] == "ERROR"
    assert entry["logger"] == "test.json_logs"
    assert entry["message"] == "agent v1 said:\nline two"
    assert "ValueError: broken" in entry["exception"]
    assert entry["time"].endswith("Z")
