"""The link to the hub: the authenticated WebSocket (`link`), the outbox it drains
(`outbox`, kept on disk while the hub is unreachable), plain HTTP requests (`http`:
.tlogs and photos), and the vehicle id the agent presents (`identity`)."""
