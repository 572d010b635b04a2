"""Databases on the machine's PostgreSQL server for the storage tests: each a copy of one
database migrated once per test process (CREATE DATABASE ... TEMPLATE), so that neither a
test's own `migrate` nor its hub's runs the migrations again (0.5-1 s a database)."""

from __future__ import annotations

import atexit
import functools
import os
import uuid
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

import psycopg
import pytest

from backend.storage.database import make_engine, migrate

# The server the storage tests use (trust auth); GCS_TEST_POSTGRES_ADDRESS points them
# elsewhere, as host:port.
POSTGRES_ADDRESS = os.environ.get("GCS_TEST_POSTGRES_ADDRESS", "127.0.0.1:5432")
POSTGRES_ADMIN = f"postgresql://postgres@{POSTGRES_ADDRESS}/postgres"


def postgres_admin() -> psycopg.Connection[Any]:
    """A connection to the server. Where it cannot be reached, the test is skipped,
    saying why; except in CI (CI=true), where the server must be there and a test that
    needs it fails loudly instead of passing as a skip."""
    try:
        return psycopg.connect(POSTGRES_ADMIN, autocommit=True, connect_timeout=5)
    except psycopg.OperationalError as error:
        if os.environ.get("CI", "").lower() == "true":
            raise
        pytest.skip(f"PostgreSQL is not reachable at {POSTGRES_ADDRESS}: {error}".strip())


def _url(name: str) -> str:
    return f"postgresql+psycopg://postgres@{POSTGRES_ADDRESS}/{name}"


def _drop(name: str) -> None:
    with psycopg.connect(POSTGRES_ADMIN, autocommit=True) as admin:
        admin.execute(f"DROP DATABASE IF EXISTS {name} WITH (FORCE)")


@functools.cache
def migrated_postgres_template() -> str:
    """The name of a database migrated to the newest revision, made once per test process
    (its own: several test runs share the server, perhaps on branches with other
    migrations) and dropped when the process ends. Nothing stays connected to it, as
    CREATE DATABASE ... TEMPLATE requires."""
    name = f"gcs_template_{uuid.uuid4().hex[:10]}"
    with postgres_admin() as admin:
        admin.execute(f"CREATE DATABASE {name}")
    atexit.register(_drop, name)
    engine = make_engine(_url(name))
    try:
        migrate(engine)
    finally:
        engine.dispose()
    return name


@contextmanager
def scratch_postgres() -> Iterator[str]:
    """A new database on the real PostgreSQL server, already migrated (a copy of the
    template: the migrations then find nothing to do); yields its SQLAlchemy URL."""
    name = f"gcs_test_{uuid.uuid4().hex[:10]}"
    with postgres_admin() as admin:
        template = migrated_postgres_template()
        admin.execute(f"CREATE DATABASE {name} TEMPLATE {template}")
    try:
        yield _url(name)
    finally:
        _drop(name)
