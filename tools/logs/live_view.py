"""A live view of a flight: the log's viewable channels over Foxglove's WebSocket protocol.

`silbridge fly --live [HOST:PORT]` (and `fc --live`) start a foxglove-sdk
WebSocket server (protocol foxglove.websocket.v1) in the process that writes
the log, and the log writer's viewable channels (tools/logs/viz_log.py) publish
every message to it as well: the same topics, schemas and bytes as in the
.mcap file, stamped with sim time. Foxglove connects with "Open connection"
-> Foxglove WebSocket -> ws://HOST:PORT. The server binds 127.0.0.1 by
default (port 8765, Foxglove's default; port 0 picks a free one); binding
another address exposes the flight to that network. With a live view the
writer cuts its batches at every capture flush (128 FC cycles), so the view
trails the flight by about that much.
"""

from __future__ import annotations

DEFAULT_HOST = "127.0.0.1"
DEFAULT_PORT = 8765


class LiveViewError(ValueError):
    user_facing = True


def parse_address(text: str | None) -> tuple[str, int]:
    """'HOST:PORT', ':PORT', 'PORT' or None/'' -> (host, port); defaults 127.0.0.1:8765."""
    if not text:
        return DEFAULT_HOST, DEFAULT_PORT
    host, sep, port = text.rpartition(":")
    if not sep:
        host, port = "", text
    try:
        p = int(port)
    except ValueError:
        raise LiveViewError(f"--live wants HOST:PORT or PORT, got {text!r}") from None
    if not 0 <= p <= 65535:
        raise LiveViewError(f"--live port {p} is out of range 0..65535")
    return host.strip("[]") or DEFAULT_HOST, p


class _Channel:
    __slots__ = ("_log",)

    def __init__(self, channel):
        self._log = channel.log

    def log(self, data: bytes, log_time_ns: int) -> None:
        self._log(data, log_time=log_time_ns)


class LiveView:
    """A foxglove-sdk WebSocket server of its own (own Context: nothing else leaks in)."""

    def __init__(self, host: str = DEFAULT_HOST, port: int = DEFAULT_PORT):
        import foxglove
        self._fg = foxglove
        self._ctx = foxglove.Context()
        try:
            self.server = foxglove.start_server(name="silbridge", host=host, port=port,
                                                context=self._ctx)
        except Exception as exc:  # noqa: BLE001 - the SDK raises its own error types
            raise LiveViewError(f"cannot serve the live view on {host}:{port}: {exc}; "
                                "choose another port with --live HOST:PORT") from exc
        self.host = host
        self.port = self.server.port
        self._channels = []

    @property
    def url(self) -> str:
        return f"ws://{self.host}:{self.port}"

    def channel(self, topic: str, schema_name: str, schema_encoding: str, schema_data: bytes,
                message_encoding: str) -> _Channel:
        fg = self._fg
        ch = fg.Channel(topic, schema=fg.Schema(name=schema_name, encoding=schema_encoding,
                                                data=schema_data),
                        message_encoding=message_encoding, context=self._ctx)
        self._channels.append(ch)
        return _Channel(ch)

    def close(self) -> None:
        for ch in self._channels:
            ch.close()
        self._channels = []
        self.server.stop()
