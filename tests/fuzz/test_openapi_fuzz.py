"""schemathesis, with all its checks, against a running demo fleet, as an admin, an
operator, a viewer and an agent (each refused what its role may not do): no 5xx, no
status the OpenAPI document does not list, bodies that match their models, 405s whose
Allow header names the path's methods, and schema-valid data accepted: a 422 for it only
where the operation says why (x-refuses-schema-valid-requests, schemathesis.toml).

It runs the `schemathesis` CLI with a fixed seed and a bounded number of examples per
operation. Every role runs the examples, coverage and fuzzing phases, so every operation
is tried by every role (the coverage phase alone reaches each operation's boundaries and
each of its documented responses); the stateful phase, which chains operations through
their links, runs for one role a run: the admin's, who may call every link, unless
GCS_FUZZ_STATEFUL_ROLE names another (tests/README.md). The vehicle routes mostly name
the fleet's own vehicles (schemathesis.toml), so commands, missions and parameter writes
really reach the agents and the simulators.
"""

from __future__ import annotations

import os
import secrets
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import httpx
import pytest

from gcs.launcher import LocalFleet
from tests.conftest import _environment
from tests.support.api import access_token, api_client
from tests.support.processes import running_fleet

EXAMPLES_PER_OPERATION = 6
LOWER_ROLES = ["operator", "viewer"]
ROLES = ["admin", *LOWER_ROLES, "agent"]
STATELESS_PHASES = "examples,coverage,fuzzing"
STATEFUL_ROLE = os.environ.get("GCS_FUZZ_STATEFUL_ROLE", "admin")
SEED = 20261125
# A role's run takes one to three minutes on a busy 2-core machine (the coverage phase is
# most of it, whatever the examples per operation); the suite's 180 s would cut it short.
RUN_LIMIT_S = 420
CONFIG = Path(__file__).with_name("schemathesis.toml")
SKIPPED_PATHS = [
    # The fuzzer would end its own session, or disable its own account, and then fuzz
    # everything else unauthenticated.
    "/api/v1/auth/logout",
    "/api/v1/users/{username}",
    "/api/v1/auth/api-tokens/{token_id}",  # token ids are small: it would revoke its own
]


@pytest.fixture(scope="module")
def demo_fleet(tmp_path_factory: pytest.TempPathFactory) -> Iterator[LocalFleet]:
    # At the default 20 vehicle requests a second most of the fuzzer's commands would be
    # 429s; the limit has tests of its own, and here the commands should reach the fleet.
    with (
        _environment(GCS_COMMANDS_PER_SECOND="1000"),
        running_fleet(tmp_path_factory.mktemp("fuzz"), vehicles=2, speedup=5.0) as fleet,
    ):
        yield fleet


@pytest.fixture(scope="module")
def tokens(demo_fleet: LocalFleet) -> dict[str, str]:
    """A token per role, all taken before any run: fuzzing the login routes spends the
    login rate limit of this address."""
    base = demo_fleet.plan.hub_http
    admin = access_token(base, "admin", demo_fleet.plan.admin_password)
    tokens = {"admin": admin}
    with api_client(base, admin) as api:
        for role in LOWER_ROLES:
            password = secrets.token_urlsafe(18)
            user = {"username": f"fuzz-{role}", "password": password, "role": role}
            created = api.post("/api/v1/users", json=user)
            assert created.status_code == 201, created.text
            tokens[role] = access_token(base, f"fuzz-{role}", password)
        # An agent's token (a third one for sim_1; the fleet's own are left alone).
        enrolled = api.post("/api/v1/vehicles/sim_1/agent-tokens")
        assert enrolled.status_code == 201, enrolled.text
        tokens["agent"] = enrolled.json()["token"]
    return tokens


def _schemathesis(
    base: str, token: str, report: Path, phases: str
) -> subprocess.CompletedProcess[str]:
    command = [
        str(Path(sys.executable).with_name("schemathesis")),
        "--config-file",
        str(CONFIG),
        "run",
        f"{base}/openapi.json",
        "--checks",
        "all",
        "--max-examples",
        str(EXAMPLES_PER_OPERATION),
        "--phases",
        phases,
        "--seed",
        str(SEED),
        "--header",
        f"Authorization: Bearer {token}",
        "--no-color",
        "--report",
        "junit",
        "--report-junit-path",
        str(report),
    ]
    for path in SKIPPED_PATHS:
        command += ["--exclude-path", path]
    return subprocess.run(
        command, capture_output=True, text=True, timeout=RUN_LIMIT_S, cwd=report.parent
    )


@pytest.mark.slow
@pytest.mark.timeout(RUN_LIMIT_S + 60)
@pytest.mark.parametrize("role", ROLES)
def test_api_answers_what_its_document_says(
    demo_fleet: LocalFleet, tokens: dict[str, str], role: str, tmp_path: Path
) -> None:
    assert STATEFUL_ROLE in ROLES, f"GCS_FUZZ_STATEFUL_ROLE must be one of {ROLES}"
    base = demo_fleet.plan.hub_http
    phases = STATELESS_PHASES + (",stateful" if role == STATEFUL_ROLE else "")
    result = _schemathesis(base, tokens[role], tmp_path / "junit.xml", phases)
    summary = result.stdout[result.stdout.rfind("SUMMARY") :]
    print(f"\nschemathesis as {role} ({phases}):\n{summary}")  # the cases run, for the record (-s)
    assert "Test cases:" in summary, result.stdout[-3000:] + result.stderr[-3000:]
    assert result.returncode == 0, result.stdout[-12000:]
    # The fleet is still there and answering after the run.
    assert httpx.get(f"{base}/api/v1/health").json()["vehicles"] == 2
