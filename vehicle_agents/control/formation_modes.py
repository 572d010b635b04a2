"""Whose mode the vehicle is in during a formation: a mode change the agent did not make
(the RC transmitter's switch, another GCS) takes it out of the formation at once."""

from __future__ import annotations


class ModeWatch:
    """Whose mode the vehicle is in during a formation: the agent's, or a pilot's.

    The agent may change only one thing, the mode it found at the join to the guided
    mode. Any other change (away from guided once in it, or from the join's mode to
    anything but guided before the agent's switch) is the RC pilot's or another GCS's,
    and takes the vehicle out. A second formation on the same vehicles shows why both
    halves matter: the followers are already in their slots, so the operator can act
    within the pre-stream's half second, before the agent has asked for guided and
    before a guided heartbeat has come; the agent must not then switch the pilot's
    LOITER back to GUIDED."""

    def __init__(self, guided: str | None, join_mode: str | None) -> None:
        self.guided = guided
        self.join_mode = join_mode
        self.seen_guided = join_mode is not None and join_mode == guided

    def observe(self, mode: str | None) -> str | None:
        """The reason to leave, if ``mode`` (a heartbeat's) is someone else's doing."""
        if mode is None:
            return None
        if mode == self.guided:
            self.seen_guided = True
            return None
        if self.join_mode is None:
            self.join_mode = mode  # the first heartbeat since the join
            return None
        if self.seen_guided or mode != self.join_mode:
            return f"the vehicle changed to {mode} (RC or another GCS): out of the formation"
        return None

    def needs_switch(self, mode: str | None) -> bool:
        """Whether the agent should ask for guided: the vehicle is still in the mode it
        was in at the join (a pilot's change would have taken it out already)."""
        return mode != self.guided and not self.seen_guided
