"""Passwords (argon2) and bearer tokens (random, stored as SHA-256)."""

from __future__ import annotations

import functools
import hashlib
import secrets
from typing import Literal

from argon2 import PasswordHasher
from argon2.exceptions import InvalidHashError, VerificationError

# "standard" is argon2-cffi's default (RFC 9106's low-memory profile: 64 MiB, 3 passes).
# "test" is argon2's least cost, for the test suite only: the settings refuse it in
# production. A hash records its own parameters, so either verifies the other's hashes.
PasswordCost = Literal["standard", "test"]
HASHERS: dict[PasswordCost, PasswordHasher] = {
    "standard": PasswordHasher(),
    "test": PasswordHasher(time_cost=1, memory_cost=8, parallelism=1),
}


@functools.cache
def _dummy_hash(cost: PasswordCost) -> str:
    """Verified against when the user does not exist, so a wrong username costs as much
    time as a wrong password and timing does not reveal which accounts exist."""
    return HASHERS[cost].hash(secrets.token_urlsafe(16))


TOKEN_PREFIXES = {"session": "gcs_s_", "access": "gcs_a_", "api": "gcs_p_", "agent": "gcs_v_"}
USER_TOKEN_PREFIXES = tuple(prefix for kind, prefix in TOKEN_PREFIXES.items() if kind != "agent")


def hash_password(password: str, cost: PasswordCost = "standard") -> str:
    return HASHERS[cost].hash(password)


def verify_password(
    password_hash: str | None, password: str, cost: PasswordCost = "standard"
) -> bool:
    try:
        return (
            HASHERS[cost].verify(password_hash or _dummy_hash(cost), password)
            and password_hash is not None
        )
    except (VerificationError, InvalidHashError):
        return False


def new_token(kind: str) -> str:
    """A 256-bit random token; the prefix lets secret scanners and humans spot it."""
    return TOKEN_PREFIXES[kind] + secrets.token_urlsafe(32)


def token_digest(token: str) -> str:
    return hashlib.sha256(token.encode()).hexdigest()


def generate_password() -> str:
    return secrets.token_urlsafe(18)
