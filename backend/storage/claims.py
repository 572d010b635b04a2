"""Claims in the shared database: a compare-and-set on one row per vehicle, which makes
a pilot's lease exclusive across hubs (backend/manual_control/claims.py) and says which
hub drives a survey (backend/survey/ownership.py); in storage because both features use it.

A claim is granted when the row is absent, expired, or already the same holder's (a
renewal); otherwise it names who holds it. The conditional UPDATE is atomic in both
SQLite and PostgreSQL (under PostgreSQL's READ COMMITTED, a second UPDATE waiting on the
row's lock re-checks the condition once the first commits), and the INSERT of a row
nobody has yet is decided by the primary key: of two hubs that race, one wins. No
consensus of our own: the database's row lock is the arbiter.

Expiry is on the hubs' wall clocks (Unix time), which must agree to well within the
lease's time to live (NTP does: milliseconds against seconds).
"""

from __future__ import annotations

from sqlalchemy import Engine, Table, delete, insert, or_, select, update
from sqlalchemy.exc import IntegrityError

from backend.storage.models import LeaseClaimRow

_TABLE: Table = LeaseClaimRow.__table__  # type: ignore[assignment]


class LeaseClaimStore:
    def __init__(self, engine: Engine) -> None:
        self._engine = engine

    def claim(
        self, vehicle_id: str, holder: str, hub_id: str, now: float, ttl_s: float
    ) -> str | None:
        """None if ``holder`` now has the vehicle until ``now + ttl_s``; else who has it."""
        table = _TABLE
        values = {"holder": holder, "hub_id": hub_id, "expires_at": now + ttl_s}
        with self._engine.begin() as connection:
            taken = connection.execute(
                update(table)
                .where(
                    table.c.vehicle_id == vehicle_id,
                    or_(table.c.holder == holder, table.c.expires_at < now),
                )
                .values(**values)
            )
            if taken.rowcount:
                return None
            try:
                with connection.begin_nested():
                    connection.execute(insert(table).values(vehicle_id=vehicle_id, **values))
                return None
            except IntegrityError:
                pass
            other = connection.execute(
                select(table.c.holder).where(table.c.vehicle_id == vehicle_id)
            ).scalar()
        return str(other) if other is not None else "another operator"

    def release(self, vehicle_id: str, holder: str) -> None:
        table = _TABLE
        with self._engine.begin() as connection:
            connection.execute(
                delete(table).where(table.c.vehicle_id == vehicle_id, table.c.holder == holder)
            )

    def holder(self, vehicle_id: str, now: float) -> str | None:
        table = _TABLE
        with self._engine.connect() as connection:
            found = connection.execute(
                select(table.c.holder).where(
                    table.c.vehicle_id == vehicle_id, table.c.expires_at >= now
                )
            ).scalar()
        return None if found is None else str(found)
