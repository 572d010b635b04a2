"""Property-based fuzzing of the REST API from its own OpenAPI schema (schemathesis).

A bounded number of examples per operation keeps this inside the suite's time budget;
the checks are: no 5xx, and every response matches the documented schema.
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest
import schemathesis
from hypothesis import HealthCheck, given, settings
from schemathesis.checks import not_a_server_error
from schemathesis.specs.openapi.checks import response_schema_conformance

from tests.conftest import ADMIN_PASSWORD, hub_settings
from tests.helpers import access_token, running_hub

EXAMPLES_PER_OPERATION = 25


@pytest.fixture(scope="module")
def fuzzed_hub(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[str, str]]:
    data_dir: Path = tmp_path_factory.mktemp("fuzz")
    # Generous limits: the fuzzer is one client hammering every route from one address.
    settings_ = hub_settings(data_dir, login_attempts_per_minute=10_000, commands_per_second=10_000)
    with running_hub(settings_) as base:
        yield base, access_token(base, "admin", ADMIN_PASSWORD)


SKIPPED_OPERATIONS = {
    # The fuzzer would end its own session, or disable its own account, and then fuzz
    # everything else unauthenticated.
    "POST /api/v1/auth/logout",
    "PATCH /api/v1/users/{username}",
}


def test_api_survives_fuzzing(fuzzed_hub: tuple[str, str]) -> None:
    base, token = fuzzed_hub
    api = schemathesis.openapi.from_url(f"{base}/openapi.json")
    failures: list[str] = []
    fuzzed = 0
    for result in api.get_all_operations():
        operation = result.ok()
        label = f"{operation.method.upper()} {operation.path}"
        if label in SKIPPED_OPERATIONS:
            continue

        @given(case=operation.as_strategy())
        @settings(
            max_examples=EXAMPLES_PER_OPERATION,
            deadline=None,
            database=None,
            suppress_health_check=list(HealthCheck),
        )
        def exercise(case: schemathesis.Case) -> None:
            case.call_and_validate(
                base_url=base,
                headers={"Authorization": f"Bearer {token}"},
                checks=[not_a_server_error, response_schema_conformance],
            )

        try:
            exercise()
        except Exception as failure:  # collect every operation's problem, then report
            failures.append(f"{label}: {failure}")
        fuzzed += 1
    assert fuzzed >= 20
    assert failures == [], "\n\n".join(failures)
