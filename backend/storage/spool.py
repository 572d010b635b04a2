"""Rows that must not be lost while the database is unavailable (the audit log, the
command log): written straight through when it answers, else appended to a local file
and inserted, in order and with their own times, once it is back.

The file is JSON lines, one row each, flushed and fsynced before ``write`` returns, so a
hub that dies mid-outage still has them at its next start. Delivery is at least once: a
hub killed between the insert's commit and the file's rewrite inserts that batch again.

The file may be on the very disk that filled up and took the database with it (SQLite
on a full disk): then the rows wait in memory instead, behind those in the file, up to
``MEMORY_ROWS``; past that they are dropped and counted (``lost``), never silently.
"""

from __future__ import annotations

import contextlib
import json
import logging
import os
import threading
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from sqlalchemy import Engine, insert
from sqlalchemy.exc import SQLAlchemyError

from backend.storage.models import Base

log = logging.getLogger(__name__)

# Rows held in memory while the spool file cannot be written: a day of busy operations.
MEMORY_ROWS = 10_000


class RowSpool:
    def __init__(self, path: Path, engine: Engine, models: Iterable[type[Base]]) -> None:
        self.path = path
        self.engine = engine
        self.tables = {model.__tablename__: model for model in models}
        # Writers are worker threads; draining runs in another. The lock covers the file
        # and the count, never a database call, so a hanging database blocks no writer
        # that is already spooling.
        self._lock = threading.Lock()
        self._pending = self._count_lines()
        self._held: list[str] = []  # lines the file would not take, after its own
        self.lost = 0  # rows dropped with both the database and the file unavailable

    @property
    def pending(self) -> int:
        """Rows waiting for the database, in the file or held in memory."""
        return self._pending + len(self._held)

    def write(self, table: str, values: dict[str, Any]) -> None:
        """Insert one row now if the database takes it, else keep it for ``drain``.

        While earlier rows wait, new ones queue behind them, so rows reach the table in
        the order they were written."""
        if table not in self.tables:
            raise KeyError(f"no table {table!r} in this spool")
        if not self.pending:
            try:
                with self.engine.begin() as connection:
                    connection.execute(insert(self.tables[table]).values(**values))
                return
            except SQLAlchemyError as error:
                log.warning(
                    "database unavailable (%s): spooling %s rows to %s", error, table, self.path
                )
        line = json.dumps({"table": table, "values": values}, separators=(",", ":")) + "\n"
        with self._lock:
            if not self._held:  # else behind the held rows, to keep the order
                try:
                    self._append(line)
                    self._pending += 1
                    return
                except OSError as error:
                    log.error("spool file %s failed (%s): holding rows in memory", self.path, error)
            if len(self._held) >= MEMORY_ROWS:
                self.lost += 1
                log.error("%s row lost: database, spool file and memory all full", table)
                return
            self._held.append(line)

    def _append(self, line: str) -> None:
        self.path.parent.mkdir(parents=True, exist_ok=True)
        descriptor = os.open(self.path, os.O_WRONLY | os.O_CREAT | os.O_APPEND, 0o600)
        try:
            with os.fdopen(descriptor, "a", encoding="utf-8") as file:
                file.write(line)
                file.flush()
                os.fsync(file.fileno())
        except OSError:
            # A line cut short by the full disk would be read back as garbage: take it out.
            with contextlib.suppress(OSError):
                os.truncate(self.path, self._size_of(self._pending))
            raise

    def _size_of(self, lines: int) -> int:
        with self.path.open("rb") as file:
            return sum(len(line) for _, line in zip(range(lines), file, strict=False))

    def drain(self) -> int:
        """Insert every spooled row in one transaction; the number stored (0 while the
        database is still unavailable, which is logged at debug level only)."""
        with self._lock:
            lines = self._read_lines()
            held = list(self._held)
        if not lines and not held:
            return 0
        rows = [row for row in map(self._parse, [*lines, *held]) if row is not None]
        try:
            with self.engine.begin() as connection:
                for table, values in rows:
                    connection.execute(insert(self.tables[table]).values(**values))
        except SQLAlchemyError as error:
            log.debug("spooled rows wait: %s", error)
            return 0
        with self._lock:
            # Rows written meanwhile were appended after the ones just stored: keep those.
            del self._held[: len(held)]
            if not lines:
                log.info("stored %d held rows now that the database is back", len(rows))
                return len(rows)
            rest = self._read_lines()[len(lines) :]
            temporary = self.path.with_suffix(".tmp")
            descriptor = os.open(temporary, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
            with os.fdopen(descriptor, "w", encoding="utf-8") as file:
                file.writelines(rest)
                file.flush()
                os.fsync(file.fileno())
            os.replace(temporary, self.path)
            self._pending = len(rest)
        log.info("stored %d spooled rows now that the database is back", len(rows))
        return len(rows)

    def _parse(self, line: str) -> tuple[str, dict[str, Any]] | None:
        try:
            record = json.loads(line)
            table, values = record["table"], record["values"]
        except (ValueError, KeyError, TypeError):
            # Only the last line can be cut short (a crash mid-write); nothing to recover.
            log.error("unreadable spooled row dropped: %.200r", line)
            return None
        if table not in self.tables or not isinstance(values, dict):
            log.error("spooled row for an unknown table dropped: %.200r", line)
            return None
        return table, values

    def _read_lines(self) -> list[str]:
        with contextlib.suppress(FileNotFoundError), self.path.open(encoding="utf-8") as file:
            return file.readlines()
        return []

    def _count_lines(self) -> int:
        return len(self._read_lines())
