"""One kept-alive HTTP connection to a model server, with a bound on every wait.

Every failure of a request (refused, dropped, an answer that never comes) becomes a :class:`ServerError`
that names the server and what to do; a benchmark run turns it into the task's error and goes on.
"""

from __future__ import annotations

import http.client
import json
import socket
import threading
from typing import Any
from urllib.parse import urlsplit

from ....errors import SmartLLMError, UserError

#: How long a request may go without an answer before the task fails (a 70B model evaluating a
#: 3,000-token prompt on a GPU takes seconds; on CPUs, minutes).
DEFAULT_TIMEOUT = 300.0


class ServerError(SmartLLMError):
    """A model server failed a request: unreachable, an error status, or no answer in time."""


class Connection:
    """One kept-alive HTTP connection to one server, with a bound on every wait."""

    def __init__(self, url: str, timeout: float):
        parts = urlsplit(url if "://" in url else f"http://{url}")
        if parts.scheme not in ("http", "https") or not parts.hostname:
            raise UserError(f"--endpoint {url!r} is not an http(s) URL such as http://127.0.0.1:8080")
        self.url, self.timeout = f"{parts.scheme}://{parts.netloc}", timeout
        self._host, self._port, self._https = parts.hostname, parts.port, parts.scheme == "https"
        self._base = parts.path.rstrip("/")
        self._conn: http.client.HTTPConnection | None = None
        self._closed = False  # by close(): no request is sent again
        self._lock = threading.Lock()

    def call(self, method: str, path: str, body: dict[str, Any] | None = None) -> tuple[int, Any]:
        """The status and the decoded JSON answer; a dropped kept-alive connection is opened again once."""
        for attempt in (0, 1):
            try:
                conn = self._conn or self._open()
                conn.request(method, self._base + path, body=None if body is None else json.dumps(body),
                             headers={"Content-Type": "application/json"})
                answer = conn.getresponse()
                raw = answer.read()
                break
            except TimeoutError as exc:
                self._drop()
                raise ServerError(f"the server at {self.url} gave no answer in {self.timeout:g} s "
                                  "(stalled or overloaded); raise --server-timeout for a slow model") from exc
            except (ConnectionError, http.client.HTTPException, OSError) as exc:
                self._drop()
                if attempt == 0 and isinstance(exc, (http.client.RemoteDisconnected, BrokenPipeError,
                                                     ConnectionResetError)):
                    continue  # the server closed an idle kept-alive connection
                raise ServerError(f"the server at {self.url} cannot be reached ({exc}); is it running?") from exc
        try:
            return answer.status, json.loads(raw) if raw else None
        except ValueError:
            return answer.status, raw.decode("utf-8", errors="replace")

    def _open(self) -> http.client.HTTPConnection:
        kind = http.client.HTTPSConnection if self._https else http.client.HTTPConnection
        conn = kind(self._host, self._port, timeout=self.timeout)
        conn.connect()  # its socket exists before close() can see it
        with self._lock:
            if not self._closed:
                self._conn = conn
                return conn
        conn.close()
        raise ServerError(f"the connection to the server at {self.url} was closed (the run is ending)")

    def close(self) -> None:
        """Close the connection for good; a request waiting on it in another thread (a worker, when Ctrl-C
        ends a run) fails at once rather than at the timeout, and is not sent again."""
        with self._lock:
            self._closed = True
        self._drop()

    def _drop(self) -> None:
        with self._lock:
            conn, self._conn = self._conn, None
        if conn is not None:
            if conn.sock is not None:
                try:
                    conn.sock.shutdown(socket.SHUT_RDWR)  # wakes a thread waiting on it
                except OSError:
                    pass
            conn.close()
