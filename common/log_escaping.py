"""Control characters in logged values are escaped, so a value cannot forge a log line.

Shared by the hub and the agent (whose logs hold its peers' texts: the hub's error
replies, the flight controller's STATUSTEXT reasons); standard library only.

A user name such as ``"x\\n2026-01-01 00:00:00,000 INFO backend.audit: audit: admin ..."``
went into the hub's log verbatim through the audit logger and wrote a line that looked
like the hub's own. A filter on every handler escapes each value (the arguments, and the
message itself for f-strings) before any formatter sees it, whatever logger it came from:
the audit log, uvicorn's access log (a path may hold ``%0A``), an agent's refusal text.
The arguments stay in place, so formatters that read them (uvicorn's) keep working.
"""

from __future__ import annotations

import logging
import re
from collections.abc import Iterable, Mapping
from typing import Any

# C0 and C1 controls and DEL, the Unicode line and paragraph separators, and the bidi
# controls that can make a line read differently from what it holds.
_CONTROL = re.compile("[\x00-\x1f\x7f-\x9f\u2028\u2029\u202a-\u202e\u2066-\u2069]")
_NAMED = {"\n": "\\n", "\r": "\\r", "\t": "\\t"}


def _escape_one(match: re.Match[str]) -> str:
    char = match.group()
    if char in _NAMED:
        return _NAMED[char]
    code = ord(char)
    return f"\\x{code:02x}" if code <= 0xFF else f"\\u{code:04x}"


def escape_control_characters(text: str) -> str:
    return _CONTROL.sub(_escape_one, text)


class _Escaped:
    """An argument that is not a string or a number, escaped however it is formatted."""

    def __init__(self, value: object) -> None:
        self.value = value

    def __str__(self) -> str:
        return escape_control_characters(str(self.value))

    def __repr__(self) -> str:
        return escape_control_characters(repr(self.value))


def _escaped(value: Any) -> Any:
    if isinstance(value, str):
        return escape_control_characters(value)
    if value is None or isinstance(value, int | float):
        return value  # kept as they are, so %d and %.1f still format them
    return _Escaped(value)


class EscapeControlCharacters(logging.Filter):
    def filter(self, record: logging.LogRecord) -> bool:
        # Escaping is idempotent: a record that passes several handlers is not garbled.
        if isinstance(record.msg, str):
            record.msg = escape_control_characters(record.msg)
        if isinstance(record.args, Mapping):
            record.args = {key: _escaped(value) for key, value in record.args.items()}
        elif isinstance(record.args, tuple):
            record.args = tuple(_escaped(value) for value in record.args)
        return True


def escape_control_characters_in_logs(loggers: Iterable[logging.Logger] | None = None) -> None:
    """Put the filter on every handler of the root logger and of every named logger
    (uvicorn configures its own handlers); call it once logging is configured."""
    if loggers is None:
        named = logging.root.manager.loggerDict.values()
        loggers = [logging.root, *(item for item in named if isinstance(item, logging.Logger))]
    for logger in loggers:
        for handler in logger.handlers:
            if not any(isinstance(f, EscapeControlCharacters) for f in handler.filters):
                handler.addFilter(EscapeControlCharacters())
