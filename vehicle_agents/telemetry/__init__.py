"""What the agent reports from the flight controller's messages: the telemetry snapshot
(`snapshot`) with its parts (`positioning`, `landed`, `readiness`), and the events
(`statustext`, `mission_progress`, `shutters`). Pure: no I/O."""
