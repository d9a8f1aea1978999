"""``logger.tracking_uri`` of a server that is not there: one line in seconds, before the
run starts, instead of MLflow's minutes of silent retries. Localhost only, no network."""

from __future__ import annotations

import socket
import sys
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path

import pytest

from rtaw_marl.errors import ConfigError
from rtaw_marl.training.loggers import check_installed
from rtaw_marl.training.loggers.config import MLflowLoggerConfig
from rtaw_marl.training.loggers.reachable import check_http_server

pytestmark = pytest.mark.unit

#: A run that would take seconds, were it to start.
TINY = [
    "scenario=poc", "frames=512", "algo.frames_per_batch=256", "algo.minibatch_size=128",
    "collector.envs_per_worker=4",
]  # fmt: skip

#: What the refusal of ``logger.tracking_uri=URI`` ends with.
ADVICE = (
    ": start the server or correct the URI, or leave logger.tracking_uri unset for a store "
    "in the run folder"
)


def _refused(uri: str, reason: str) -> str:
    """The one line refusing ``logger.tracking_uri=uri``."""
    return f"logger.tracking_uri={uri} cannot be reached ({reason}){ADVICE}"


def _closed_port() -> int:
    """A localhost port nothing listens on: bound, then closed."""
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


@contextmanager
def _server(status: int) -> Iterator[str]:
    """A local HTTP server answering every GET with ``status``; yields its URI."""

    class Handler(BaseHTTPRequestHandler):
        def do_GET(self) -> None:
            self.send_response(status)
            self.end_headers()

        def log_message(self, *args: object) -> None:  # no lines on stderr
            pass

    server = ThreadingHTTPServer(("127.0.0.1", 0), Handler)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    try:
        yield f"http://127.0.0.1:{server.server_address[1]}"
    finally:
        server.shutdown()
        server.server_close()


def _uninstall(module: str, monkeypatch: pytest.MonkeyPatch) -> None:
    """Imports of ``module`` and its submodules fail as if it were not installed."""
    for name in [m for m in sys.modules if m == module or m.startswith(f"{module}.")]:
        monkeypatch.setitem(sys.modules, name, None)
    monkeypatch.setitem(sys.modules, module, None)


def test_a_refused_tracking_uri_fails_fast_on_the_command_line(cli, tmp_path: Path) -> None:
    """``rtaw-train logger=mlflow logger.tracking_uri=http://127.0.0.1:<closed>``: one
    line naming the option and the reason, exit 2, before the run folder exists."""
    uri = f"http://127.0.0.1:{_closed_port()}"
    run_dir = tmp_path / "run"
    start = time.monotonic()
    result = cli("train", *TINY, "logger=mlflow", f"logger.tracking_uri={uri}",
                 f"output_dir={run_dir}")  # fmt: skip
    took = time.monotonic() - start
    assert result.code == 2
    assert result.err == f"error: {_refused(uri, 'Connection refused')}\n"
    # Composing the config and importing torch take seconds; MLflow's retries took 259.
    assert took < 60, took
    assert not run_dir.exists()


def test_the_server_is_asked_before_mlflow_is_imported(monkeypatch: pytest.MonkeyPatch) -> None:
    """Without MLflow installed the refused server is still the error: asked first."""
    _uninstall("mlflow", monkeypatch)
    uri = f"http://127.0.0.1:{_closed_port()}"
    start = time.monotonic()
    with pytest.raises(ConfigError) as info:
        check_installed(MLflowLoggerConfig(tracking_uri=uri))
    assert time.monotonic() - start < 5
    assert str(info.value) == _refused(uri, "Connection refused")


@pytest.mark.parametrize("status", [200, 401, 404])
def test_a_server_that_answers_passes(status: int) -> None:
    """Any answer but 'not there behind the proxy' is a server; MLflow says the rest."""
    with _server(status) as uri:
        check_http_server(uri, "logger.tracking_uri")
        check_http_server(f"{uri}/some/prefix", "logger.tracking_uri")


def test_a_server_unavailable_behind_its_proxy_is_refused() -> None:
    with _server(503) as uri, pytest.raises(ConfigError) as info:
        check_http_server(uri, "logger.tracking_uri")
    assert str(info.value) == _refused(uri, "it answered 503 Service Unavailable")


def test_a_server_that_never_answers_is_refused_after_the_timeout() -> None:
    """A port that accepts connections but sends nothing: refused once the timeout ends."""
    with socket.socket() as listener:
        listener.bind(("127.0.0.1", 0))
        listener.listen()
        uri = f"http://127.0.0.1:{listener.getsockname()[1]}"
        start = time.monotonic()
        with pytest.raises(ConfigError) as info:
            check_http_server(uri, "logger.tracking_uri", timeout=0.3)
        assert time.monotonic() - start < 3
    assert str(info.value) == _refused(uri, "no answer in 0.3 s")


def test_a_malformed_uri_is_refused() -> None:
    with pytest.raises(ConfigError) as info:
        check_http_server("http://127.0.0.1:port", "logger.tracking_uri")
    assert str(info.value).startswith(
        "logger.tracking_uri=http://127.0.0.1:port cannot be reached (a malformed URI: "
        "nonnumeric port: 'port')"
    )


@pytest.mark.parametrize("uri", ["sqlite:///tmp/x/mlflow.db", "file:///tmp/x", "databricks", "x"])
def test_other_uris_are_not_asked(uri: str, monkeypatch: pytest.MonkeyPatch) -> None:
    """Only http(s) URIs name a server; the others pass without a request."""

    def no_request(*args: object, **kwargs: object) -> None:
        raise AssertionError("no request expected")

    monkeypatch.setattr(socket, "create_connection", no_request)
    check_http_server(uri, "logger.tracking_uri")
