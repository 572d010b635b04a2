"""The password hash keeps its production strength; the test suite's cheap cost is
refused outside development."""

from __future__ import annotations

import pytest
from argon2 import PasswordHasher, extract_parameters
from pydantic import ValidationError

from backend.auth.secrets import hash_password, verify_password
from backend.settings import HubSettings

STRONG_PASSWORD = "an admin password nobody guesses 7"


def test_the_production_default_is_argon2s_standard_cost() -> None:
    settings = HubSettings(admin_password=STRONG_PASSWORD)
    assert settings.password_hash_cost == "standard"
    parameters = extract_parameters(hash_password("x", settings.password_hash_cost))
    default = PasswordHasher()
    # argon2-cffi's default, RFC 9106's low-memory profile: 64 MiB, 3 passes, 4 lanes.
    assert parameters.memory_cost == default.memory_cost >= 64 * 1024
    assert parameters.time_cost == default.time_cost >= 3
    assert parameters.parallelism == default.parallelism
    assert parameters.type.name == "ID"


def test_the_test_cost_is_refused_in_production() -> None:
    with pytest.raises(ValidationError, match="GCS_PASSWORD_HASH_COST is only for the test suite"):
        HubSettings(admin_password=STRONG_PASSWORD, password_hash_cost="test")
    development = HubSettings(environment="development", password_hash_cost="test")
    assert development.password_hash_cost == "test"


def test_either_cost_verifies_the_others_hashes() -> None:
    """A hash records its parameters: moving between costs locks nobody out."""
    cheap, strong = hash_password("pw", "test"), hash_password("pw", "standard")
    assert extract_parameters(cheap).memory_cost < extract_parameters(strong).memory_cost
    assert verify_password(cheap, "pw", "standard")
    assert verify_password(strong, "pw", "test")
    assert not verify_password(cheap, "wrong", "standard")
    assert not verify_password(None, "pw", "test")
