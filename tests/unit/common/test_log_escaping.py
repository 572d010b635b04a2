"""The log filter escapes control characters in every value, whatever the formatter."""

from __future__ import annotations

import io
import logging
from collections.abc import Iterator

import pytest
from uvicorn.logging import AccessFormatter

from common.log_escaping import EscapeControlCharacters, escape_control_characters_in_logs


@pytest.fixture
def logged() -> Iterator[tuple[logging.Logger, io.StringIO]]:
    """A logger with a real stream handler and the hub's format, then the filter."""
    stream = io.StringIO()
    handler = logging.StreamHandler(stream)
    handler.setFormatter(logging.Formatter("%(asctime)s %(levelname)s %(name)s: %(message)s"))
    logger = logging.getLogger("test.log_escaping")
    logger.addHandler(handler)
    logger.setLevel(logging.INFO)
    logger.propagate = False
    escape_control_characters_in_logs([logger])
    yield logger, stream
    logger.removeHandler(handler)


def test_every_value_stays_on_its_line(logged: tuple[logging.Logger, io.StringIO]) -> None:
    logger, stream = logged
    forged = "\n2031-01-01 00:00:00,000 INFO backend.audit: forged"
    logger.info("audit: %s %s -> %s", "anonymous", "x" + forged, "denied")
    logger.info("named %(who)s", {"who": "y\r" + forged})
    logger.info("error: %s", ValueError("z" + forged))
    logger.info(f"f-string {forged} \u2028 \u202e \x1b[31m")  # as code may do
    logger.info("numbers %d %.1f", 3, 2.5)
    lines = stream.getvalue().splitlines()
    assert len(lines) == 5
    assert "x\\n2031-01-01" in lines[0]
    assert "y\\r\\n2031" in lines[1]
    assert "z\\n2031" in lines[2]
    assert "\\u2028 \\u202e \\x1b[31m" in lines[3]
    assert lines[4].endswith("numbers 3 2.5")


def test_uvicorns_access_formatter_still_formats() -> None:
    record = logging.LogRecord(
        "uvicorn.access",
        logging.INFO,
        __file__,
        1,
        '%s - "%s %s HTTP/%s" %d',
        ("127.0.0.1:5", "GET", "/a\nb", "1.1", 200),
        None,
    )
    assert EscapeControlCharacters().filter(record)
    formatter = AccessFormatter('%(client_addr)s "%(request_line)s" %(status_code)s', False)
    assert formatter.format(record) == '127.0.0.1:5 "GET /a\\nb HTTP/1.1" 200 OK'
