"""Object stores behind remote inputs: the URLs taken, the store for one, fetches with retries.

obstore (the ``remote`` extra) talks to S3, GCS and HTTP servers; credentials and endpoints
come from each provider's usual chain and never appear in a message: errors name the URL
without user, password or query, and say the problem in our own words.
"""

from __future__ import annotations

import os
import re
import threading
import time
from datetime import timedelta
from typing import TYPE_CHECKING, Any, NamedTuple
from urllib.parse import urlsplit

from medkit_replay.errors import InputError
from medkit_replay.inputs.remote.fetch import (
    SPEED_LIMIT_ENV,
    SPEED_TIME_ENV,
    Stalled,
    Stopped,
    fetch_ranges,
    low_speed,
)

if TYPE_CHECKING:
    from collections.abc import Iterator

    from obstore.store import ClientConfig, GCSConfig, RetryConfig, S3CredentialProvider

SCHEMES = ("s3", "gs", "http", "https")
EXTRA_HINT = "pip install 'medkit-replay[remote]'"
ATTEMPTS = 5
"""Tries of one range request: a dropped connection or a short body is asked for again."""
BACKOFF_S = 0.1
"""Wait before the second try; doubled before each further one."""
SLOW_BUDGET = 2
"""An object is given up once its reads have spent this many times the low-speed time (see
inputs.remote.fetch) under the speed limit, in all: two stalled tries, or many slow ones (a
server trickling small reads that each end before the time). A minute or so by default."""
SLOW_GRACE_S = 1.0
"""A try that ends sooner is never counted as slow (a small read over a long round trip)."""
_STATUS = re.compile(r"status code: (\d{3})|\b(\d{3}) (?:Forbidden|Not Found|Unauthorized)")


class RemoteError(InputError):
    """A remote object cannot be had: not found, access denied, or the connection keeps failing."""


class Location(NamedTuple):
    """A remote input named by a URL.

    Attributes:
        scheme: ``s3``, ``gs``, ``http`` or ``https``.
        bucket: the bucket, or ``host[:port]`` of an HTTP server.
        key: the object or prefix inside it (no leading slash).
        display: the URL as reports and messages show it (nothing secret in it).
    """

    scheme: str
    bucket: str
    key: str
    display: str

    def child(self, name: str) -> Location:
        """The location of ``name`` under this prefix."""
        key = f"{self.key.rstrip('/')}/{name}" if self.key.strip("/") else name
        return self._replace(key=key, display=f"{self.scheme}://{self.bucket}/{key}")


def parse_location(text: str) -> Location:
    """A URL given as an input, checked.

    Raises:
        InputError: an unknown scheme, no bucket or host, or credentials or a query in an
            http(s) URL (they would be sent in the clear or shown in reports).
    """
    parts = urlsplit(text)
    scheme = parts.scheme.lower()
    host = parts.hostname or ""
    bucket = f"{host}:{parts.port}" if parts.port else host
    key = parts.path.lstrip("/")
    display = f"{scheme}://{bucket}/{key}"
    if scheme not in SCHEMES or not bucket:
        raise InputError("not a remote input (s3://, gs://, http:// or https:// URL)", path=display)
    if parts.username or parts.password or parts.query or parts.fragment:
        raise InputError(
            "a user, password, query or fragment in the URL is not supported (credentials "
            "come from the provider's usual chain: environment variables and profiles)",
            path=display,
        )
    return Location(scheme, bucket, key, display)


def _obstore() -> Any:
    try:
        import obstore  # noqa: PLC0415  # only for remote inputs
    except ImportError:
        raise InputError(f"reading remote inputs needs the 'remote' extra: {EXTRA_HINT}") from None
    return obstore


_RETRY: RetryConfig = {
    "max_retries": 3,
    "backoff": {
        "init_backoff": timedelta(milliseconds=100),
        "max_backoff": timedelta(seconds=2),
        "base": 2,
    },
    "retry_timeout": timedelta(seconds=60),
}


def _client(*, allow_http: bool) -> ClientConfig:
    return {
        "connect_timeout": timedelta(seconds=10),
        "timeout": timedelta(seconds=60),
        "allow_http": allow_http,
    }


def _s3_store(bucket: str) -> object:
    """An S3 store configured as the AWS tools would be.

    Keys, region and endpoint from the environment (``AWS_ACCESS_KEY_ID``, ``AWS_REGION``,
    ``AWS_ENDPOINT_URL`` for MinIO and other S3-compatible servers, ...); without keys in
    the environment, from the AWS profiles (``AWS_PROFILE``, ``~/.aws``) when boto3 is
    installed; else from the instance, container or web identity, as obstore finds them.
    """
    from obstore.store import S3Store  # noqa: PLC0415

    endpoint = os.environ.get("AWS_ENDPOINT_URL_S3") or os.environ.get("AWS_ENDPOINT_URL") or ""
    client = _client(allow_http=endpoint.lower().startswith("http://"))
    provider = None if "AWS_ACCESS_KEY_ID" in os.environ else _profile_credentials()
    if provider is not None:
        return S3Store(
            bucket, client_options=client, retry_config=_RETRY, credential_provider=provider
        )
    return S3Store(bucket, client_options=client, retry_config=_RETRY)


def _profile_credentials() -> S3CredentialProvider | None:
    """Credentials from the AWS profiles through boto3 (None: no boto3, or none found)."""
    try:
        from obstore.auth.boto3 import Boto3CredentialProvider  # noqa: PLC0415
    except ImportError:
        return None
    try:
        return Boto3CredentialProvider()
    except Exception:  # no credentials in any profile: obstore's own chain decides
        return None


def _gcs_store(bucket: str) -> object:
    """A GCS store configured as Google's tools would be.

    Credentials from obstore's chain (``GOOGLE_SERVICE_ACCOUNT``,
    ``GOOGLE_APPLICATION_CREDENTIALS``, the gcloud application default credentials, the
    instance's service account). A GCS-compatible server is named by
    ``STORAGE_EMULATOR_HOST`` as for Google's client libraries (an emulator: no credentials
    are sent), or by obstore's own ``GOOGLE_BASE_URL`` or a service account file's
    ``gcs_base_url`` (credentials as usual).
    """
    from obstore.store import GCSStore  # noqa: PLC0415

    # GCS itself is https; a base URL is only ever the user's own setting, and may name an
    # emulator on http:// (allow_http permits that scheme, it never downgrades https).
    client = _client(allow_http=True)
    emulator = os.environ.get("STORAGE_EMULATOR_HOST", "")
    if not emulator or os.environ.get("GOOGLE_BASE_URL"):
        return GCSStore(bucket, client_options=client, retry_config=_RETRY)
    if "://" not in emulator:  # host:port, as Google's client libraries take it
        emulator = f"http://{emulator}"
    config: GCSConfig = {"base_url": emulator.rstrip("/"), "skip_signature": True}
    return GCSStore(bucket, config=config, client_options=client, retry_config=_RETRY)


def open_store(location: Location) -> object:
    """The obstore store holding ``location`` (its bucket, or the HTTP server's root).

    Raises:
        InputError: the ``remote`` extra is not installed.
    """
    _obstore()
    if location.scheme == "s3":
        return _s3_store(location.bucket)
    if location.scheme == "gs":
        return _gcs_store(location.bucket)
    from obstore.store import HTTPStore  # noqa: PLC0415

    return HTTPStore.from_url(
        f"{location.scheme}://{location.bucket}",
        client_options=_client(allow_http=location.scheme == "http"),
        retry_config=_RETRY,
    )


def _problem(exc: BaseException) -> tuple[bool, str]:
    """(final, what went wrong in our words) for an obstore exception; never its text."""
    from obstore.exceptions import (  # noqa: PLC0415
        PermissionDeniedError,
        UnauthenticatedError,
    )

    if isinstance(exc, FileNotFoundError):
        return True, "not found (HTTP 404)"
    if isinstance(exc, PermissionDeniedError | UnauthenticatedError):
        return True, "access denied (HTTP 403)"
    match = _STATUS.search(str(exc))
    status = int(match[1] or match[2]) if match else 0
    if status in (401, 403):
        return True, f"access denied (HTTP {status})"
    if status == 404:
        return True, "not found (HTTP 404)"
    if status == 416:
        return True, "the object is shorter than it was (HTTP 416)"
    if 400 <= status < 500:
        return True, f"refused (HTTP {status})"
    if status:
        return False, f"server error (HTTP {status})"
    return False, "connection failed"


class Tally:
    """Bytes fetched for one input (summed over its threads and its passes)."""

    def __init__(self, display: str) -> None:
        self.display = display
        self.fetched = 0
        self.sizes: dict[str, int] = {}  # object key -> size
        self._lock = threading.Lock()

    @property
    def size(self) -> int:
        """Bytes of the objects read (each counted once)."""
        return sum(self.sizes.values())

    def add(self, count: int) -> None:
        with self._lock:
            self.fetched += count


class RemoteObject:
    """One object of a store: its size, ranges of it fetched with retries, counted in a tally."""

    def __init__(self, store: object, location: Location, tally: Tally) -> None:
        self.store = store
        self.location = location
        self.tally = tally
        self.deadline = low_speed()
        self._slow_s = 0.0  # time its tries spent under the speed limit, in all
        self._slow_problem = ""
        self._slow_lock = threading.Lock()
        self.size = self._head()
        tally.sizes[location.key] = self.size

    def _fail(self, problem: str) -> RemoteError:
        return RemoteError(problem, path=self.location.display)

    def _head(self) -> int:
        obstore = _obstore()
        try:
            meta = obstore.head(self.store, self.location.key)
        except Exception as exc:
            raise self._fail(_problem(exc)[1]) from None
        return int(meta["size"])

    def fetch(self, start: int, end: int, stop: threading.Event | None = None) -> bytes:
        """Bytes ``[start, end)`` (``end`` within the object), asked for again when cut short.

        Args:
            stop: once set, no further try is made (the reader was closed: Ctrl-C, an error).

        Raises:
            RemoteError: not found, access denied, stopped, or still failing after ATTEMPTS
                tries.
        """
        return bytes(self.fetch_many([start], [end], stop)[0])

    def fetch_many(
        self, starts: list[int], ends: list[int], stop: threading.Event | None = None
    ) -> list[bytes]:
        """The bytes of each range ``[starts[i], ends[i])`` (within the object, not
        overlapping), in one try that sends the requests concurrently; the ranges that fail
        or come back cut short are asked for again, as :meth:`fetch` does. A try that stalls
        (under the low-speed deadline) is ended and tried again, until the object's reads
        have spent SLOW_BUDGET low-speed times under the speed limit.

        Raises:
            RemoteError: as :meth:`fetch`, for any of the ranges.
        """
        obstore = _obstore()
        got: list[bytes | None] = [None] * len(starts)
        todo = list(range(len(starts)))
        problem = ""
        pause = stop if stop is not None else threading.Event()  # waits between tries
        for attempt in range(ATTEMPTS):
            if attempt and pause.wait(BACKOFF_S * 2 ** (attempt - 1)):
                raise self._fail("reading stopped")
            self._check_speed()
            ranges = [(starts[k], ends[k]) for k in todo]  # coalesced by the caller as it wanted
            began = time.monotonic()
            try:
                key, deadline = self.location.key, self.deadline
                parts = fetch_ranges(obstore, self.store, key, ranges, deadline, pause)
            except Stalled:
                problem = f"stalled: {self.deadline}"
                self._slow(time.monotonic() - began, problem)
                continue
            except Stopped:
                raise self._fail("reading stopped") from None
            except Exception as exc:
                final, problem = _problem(exc)
                if final:
                    raise self._fail(problem) from None
                continue
            took, fetched = time.monotonic() - began, sum(map(len, parts))
            self.tally.add(fetched)
            if took > SLOW_GRACE_S and fetched < self.deadline.bytes_per_s * took:
                self._slow(took, f"too slow: {self.deadline.slower()}")
            short = []
            for k, part in zip(todo, parts, strict=True):
                if len(part) == ends[k] - starts[k]:
                    got[k] = part
                else:
                    short.append(k)
                    problem = f"the server sent {len(part)} of {ends[k] - starts[k]} bytes"
            if not short:
                return [part for part in got if part is not None]
            todo = short
        raise self._fail(f"{problem}; gave up after {ATTEMPTS} tries")

    def _slow(self, seconds: float, problem: str) -> None:
        """Count a try's time under the speed limit (``problem`` says how it was slow)."""
        with self._slow_lock:
            self._slow_s += seconds
            self._slow_problem = problem

    def _check_speed(self) -> None:
        """Before a try: give up once the object's reads spent their slow budget.

        Raises:
            RemoteError: they have spent SLOW_BUDGET low-speed times under the speed limit.
        """
        with self._slow_lock:
            spent, problem = self._slow_s, self._slow_problem
        if spent >= SLOW_BUDGET * self.deadline.seconds:
            raise self._fail(
                f"{problem}; gave up after {spent:.0f} s under that speed (raise the limits "
                f"with {SPEED_TIME_ENV} or {SPEED_LIMIT_ENV})"
            )


def list_objects(store: object, location: Location) -> Iterator[tuple[str, int]]:
    """(key, size) of every object under a prefix of a bucket (not for HTTP: no listing).

    Raises:
        RemoteError: the prefix cannot be listed.
    """
    obstore = _obstore()
    prefix = location.key.rstrip("/")
    try:
        for batch in obstore.list(store, f"{prefix}/" if prefix else None):
            for meta in batch:
                yield str(meta["path"]), int(meta["size"])
    except Exception as exc:
        raise RemoteError(f"cannot be listed: {_problem(exc)[1]}", path=location.display) from None
