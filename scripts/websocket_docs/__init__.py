"""The pieces scripts/gen_websocket_docs.py writes docs/websockets.md from."""
