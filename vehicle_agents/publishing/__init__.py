"""What the agent publishes to the hub through the outbox: numbered telemetry snapshots
and numbered events."""
