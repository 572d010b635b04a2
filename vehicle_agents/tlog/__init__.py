"""The onboard telemetry log: one .tlog per flight (`recorder`), uploaded to the hub
after landing (`uploads`), and deleted once the hub has it (`pruning`)."""
