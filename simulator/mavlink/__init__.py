"""The simulated vehicle's MAVLink face: the telemetry it sends (`telemetry`), the
per-connection schedule and the requests that change it (`streams`), the commands and
protocols it answers (`commands`), and MAVLink FTP (`ftp_server`)."""
