"""Is a tracking server there? One short HTTP request before a run starts.

A tracking client retries a server that refuses connections for minutes before it
gives up (MLflow: 259 s, silent, with ``http://127.0.0.1:9``), long after the user could
have been told. :func:`check_http_server` asks once, with a timeout of a few seconds,
and turns no answer into one line naming the option. Plain standard library (no
MLflow), so it runs before the tracking package is imported, or without it.
"""

from __future__ import annotations

import http.client
import ssl
import urllib.error
import urllib.parse
import urllib.request

from rtaw_marl.errors import ConfigError

__all__ = ["SERVER_TIMEOUT_S", "UNAVAILABLE", "check_http_server"]

#: How long the one request may take (seconds): a server on the network answers in
#: milliseconds; a few seconds allow for a slow link without making a typo costly.
SERVER_TIMEOUT_S = 3.0

#: HTTP statuses of a server that is not there behind its proxy or load balancer (bad
#: gateway, unavailable, gateway timeout): clients retry these as they retry a refused
#: connection. Any other answer, even 401 or 404, is a server that is there.
UNAVAILABLE = frozenset({502, 503, 504})


def check_http_server(uri: str, key: str, timeout: float = SERVER_TIMEOUT_S) -> None:
    """Refuse an ``http(s)://`` URI whose server does not answer within ``timeout``.

    Any other URI (``sqlite:///...``, a path, ``databricks``) passes unchecked. The
    request goes through the proxies the environment names (``HTTPS_PROXY``, ...), as
    the tracking client's would. Certificates are not verified: only whether the
    server is there is asked here; the client checks the certificate itself.

    Args:
        uri: The tracking URI.
        key: The config key that named it, for the message (``logger.tracking_uri``).
        timeout: Seconds to wait for the connection and for each read.

    Raises:
        ConfigError: The URI is malformed, the connection is refused or times out, the
            host is unknown, the reply is not HTTP, or the server answers 502, 503 or
            504; the message names ``key`` and the reason.
    """
    if urllib.parse.urlsplit(uri).scheme.lower() not in ("http", "https"):
        return
    context = ssl.create_default_context()
    context.check_hostname = False
    context.verify_mode = ssl.CERT_NONE
    opener = urllib.request.build_opener(urllib.request.HTTPSHandler(context=context))
    request = urllib.request.Request(uri, headers={"User-Agent": "rtaw_marl"})
    try:
        with opener.open(request, timeout=timeout):
            return
    except urllib.error.HTTPError as exc:  # the server answered
        exc.close()
        if exc.code not in UNAVAILABLE:
            return
        reason = f"it answered {exc.code} {exc.reason}"
    except (urllib.error.URLError, http.client.HTTPException, OSError, ValueError) as exc:
        reason = _reason(exc, timeout)
    raise ConfigError(
        f"{key}={uri} cannot be reached ({reason}): start the server or correct the "
        f"URI, or leave {key} unset for a store in the run folder"
    )


def _reason(exc: Exception, timeout: float) -> str:
    """One line for a failed request: ``Connection refused``, ``no answer in 3 s``."""
    cause = exc.reason if isinstance(exc, urllib.error.URLError) else exc
    if isinstance(cause, TimeoutError):
        return f"no answer in {timeout:g} s"
    if isinstance(cause, OSError) and cause.strerror:
        return cause.strerror
    text = (str(cause).strip().splitlines() or [type(cause).__name__])[0]
    if isinstance(cause, (http.client.InvalidURL, ValueError)):
        return f"a malformed URI: {text}"
    if isinstance(cause, http.client.HTTPException):
        return f"the reply is not HTTP: {type(cause).__name__}"
    return text
