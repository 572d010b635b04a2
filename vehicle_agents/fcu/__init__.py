"""The MAVLink link to the flight controller and the exchanges on it.

`link` (the connection, its reader thread, the cache of the latest message per type) and
`messages` (what its users share); `commands` (one command, retries, COMMAND_ACK),
`missions`, `params` (with `param_encoding` and `param_metadata`), `modes` and
`available_modes`; `streams` asks for the telemetry the agent needs (`stream_plan`,
`stream_watch`, and `rate_merger`, shared with the forward); `events` turns the link's
ups and downs into flight-log events; `dialect` fixes the MAVLink dialect, `results`
names MAV_RESULTs. Nothing here knows the hub.
"""
