"""Which passwords the hub accepts: long enough, and not guessable from lists of common
passwords, words, names and keyboard patterns (zxcvbn, Dropbox's estimator).

Checked for every account, whatever its role, when it is created or its password set.
"""

from __future__ import annotations

from zxcvbn import zxcvbn

MIN_LENGTH = 12
# zxcvbn's score 3: more than 10^8 guesses, "safely unguessable" against a slow hash such
# as the hub's argon2. Scores 0-2 are the common passwords, words and patterns.
MIN_SCORE = 3
# zxcvbn refuses longer input (its time grows faster than linearly with the length);
# what follows the first 72 characters cannot make a password weak there any weaker.
CHECKED_PREFIX = 72
# Words that belong to this system, so guessed first by an attacker who knows it.
CONTEXT_WORDS = ("gcs", "fleet", "drone", "hub", "ardupilot", "px4", "mavlink")


def password_problem(password: str, username: str | None = None) -> str | None:
    """Why ``password`` is refused, or None if it is acceptable."""
    if len(password) < MIN_LENGTH:
        return f"must be at least {MIN_LENGTH} characters"
    context = [*CONTEXT_WORDS, *([username] if username else [])]
    verdict = zxcvbn(password[:CHECKED_PREFIX], user_inputs=context)
    if verdict["score"] >= MIN_SCORE:
        return None
    feedback = verdict["feedback"]
    reason = feedback.get("warning") or "it is too easy to guess"
    hints = " ".join(feedback.get("suggestions") or [])
    return f"is too common or easy to guess: {reason.rstrip('.')}. {hints}".strip()
