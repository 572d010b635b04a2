"""The agents' WebSocket sessions: authenticate, hello, then telemetry in and commands out.

`session.AgentSession` is one agent's session; the handshake, the frames it receives, the
acks and resend requests it sends, and what a restarted agent left unrecorded are each in
their own module here."""
