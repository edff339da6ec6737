"""``infuse serve``: live characters over WebSocket, HTTP and VMC (see docs/live.md)."""
