"""Weak passwords are refused for every account; the project's own passwords pass."""

from __future__ import annotations

import secrets

import pytest

from backend.auth.password_policy import password_problem
from backend.auth.secrets import generate_password


@pytest.mark.parametrize(
    "password",
    [
        "aaaaaaaa",
        "password",
        "aaaaaaaaaaaaaaaa",
        "passwordpassword",
        "password1234",
        "qwertyuiopasdf",
        "administrator",
        "dronedronedrone",
        "a" * 1024,
    ],
)
def test_short_common_and_patterned_passwords_are_refused(password: str) -> None:
    assert password_problem(password, "admin") is not None


def test_a_password_made_of_the_username_is_refused() -> None:
    assert password_problem("olivia.smith.1985", "olivia.smith.1985") is not None


@pytest.mark.parametrize(
    "password",
    [
        generate_password(),  # the first admin's, when none is set
        secrets.token_urlsafe(12),  # `gcs demo`'s admin password
        "correct horse battery",  # the test suite's
        "test-admin-password",
    ],
)
def test_the_projects_own_passwords_pass(password: str) -> None:
    assert password_problem(password, "admin") is None
