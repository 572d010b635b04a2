"""The hub: live fleet state, command dispatch, storage and the REST/WebSocket API."""
