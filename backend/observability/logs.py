"""Structured logs: one JSON object a line (GCS_LOG_FORMAT=json), for a log shipper.

Set on every handler once the server has configured logging, as the control-character
filter is (common/log_escaping.py); JSON's own escaping keeps a line one line.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Iterable
from typing import Any

import orjson


class JsonFormatter(logging.Formatter):
    def format(self, record: logging.LogRecord) -> str:
        entry: dict[str, Any] = {
            "time": time.strftime("%Y-%m-%dT%H:%M:%S", time.gmtime(record.created))
            + f".{int(record.msecs):03d}Z",
            "level": record.levelname,
            "logger": record.name,
            "message": record.getMessage(),
        }
        if record.exc_info:
            entry["exception"] = self.formatException(record.exc_info)
        return orjson.dumps(entry, default=str).decode()


def use_json_logs(loggers: Iterable[logging.Logger] | None = None) -> None:
    """Every handler of these loggers (default: the root and every named one) writes JSON."""
    if loggers is None:
        named = logging.root.manager.loggerDict.values()
        loggers = [logging.root, *(item for item in named if isinstance(item, logging.Logger))]
    for logger in loggers:
        for handler in logger.handlers:
            handler.setFormatter(JsonFormatter())
