"""``medkit-replay serve``: replay once, then answer ros2_medkit's gateway REST/SSE API over it.

The web stack (Starlette, uvicorn: the ``serve`` extra) is loaded only here, after the replay.
"""

from __future__ import annotations

import math
import shutil
import signal
import socket
import sys
import tempfile
from contextlib import nullcontext
from pathlib import Path
from typing import TYPE_CHECKING

import click

from medkit_replay.commands import (
    config_option,
    foreign_clips,
    input_argument,
    local_paths,
    path_option,
)
from medkit_replay.errors import MedkitReplayError, Terminated

if TYPE_CHECKING:
    from collections.abc import Iterable

    from medkit_replay.gateway.recording import ServedRecording


def _finite(_ctx: click.Context, param: click.Parameter, value: float | None) -> float | None:
    if value is not None and (not math.isfinite(value) or value < 0):
        raise click.BadParameter("must be a finite number, 0 or more", param=param)
    return value


@click.command()
@input_argument("inputs")
@config_option()
@path_option(
    "--graph",
    "graph_file",
    help="The robot's node graph: the entities served (otherwise the recording's node names).",
)
@path_option(
    "--evidence",
    "evidence_dir",
    kind="folder",
    help="Write the black-box recordings here, as analyze does, and serve them as bulk data "
    "(by default they go to a temporary folder removed when the server stops).",
)
@click.option(
    "--host",
    default="127.0.0.1",
    show_default=True,
    metavar="ADDRESS",
    help="Address to listen on.",
)
@click.option(
    "--port", default=8080, show_default=True, type=click.IntRange(0, 65535),
    help="Port to listen on (0: any free port, printed).",
)  # fmt: skip
@click.option(
    "--at", "at_sec", type=float, default=None, callback=_finite, metavar="SECONDS",
    help="The moment answered when a request names none (default: the end of the recording).",
)  # fmt: skip
@click.option(
    "--speed", type=float, default=1.0, show_default=True, callback=_finite,
    help="Pace of /faults/stream: 1 as recorded, 2 twice as fast, 0 as fast as possible.",
)  # fmt: skip
@click.option(
    "--cors", "cors", multiple=True, metavar="ORIGIN",
    help="Allow this browser origin (repeatable), e.g. http://localhost:5173 for the web UI.",
)  # fmt: skip
@click.option("--quiet", is_flag=True, help="No progress bar.")
def serve(
    inputs: tuple[Path | str, ...],
    configs: tuple[Path, ...],
    graph_file: Path | None,
    evidence_dir: Path | None,
    host: str,
    port: int,
    at_sec: float | None,
    speed: float,
    cors: tuple[str, ...],
    quiet: bool,
) -> None:
    """Replay INPUT... once, then serve the gateway's read-only API over it at any moment.

    The web UI, the Foxglove extension, the MCP adapter and the generated clients take
    http://HOST:PORT (or http://HOST:PORT/at/SECONDS for one moment); every fault route
    also takes ?at=SECONDS. Ctrl-C or SIGTERM stops the server.

    Exit status: 0 stopped by Ctrl-C or SIGTERM; 2 bad usage, an input that cannot be read,
    an invalid config, or an address that cannot be listened on.

    \b
    Examples:
      medkit-replay serve mission/ --config robot_params.yaml
      medkit-replay serve mission/ --port 8080 --cors http://localhost:5173
      medkit-replay serve mission/ --config capture.yaml --evidence clips/ --at 95
    """
    # Checked before the replay: the web stack is there, the address can be taken.
    try:
        import uvicorn  # noqa: PLC0415

        from medkit_replay.gateway.app import MAX_REQUEST_HEAD_BYTES, build_app  # noqa: PLC0415
    except ImportError as err:
        raise MedkitReplayError(
            f"serve needs the 'serve' extra (pip install 'medkit-replay[serve]'): {err}"
        ) from None
    listener = _listen(host, port)
    staging = None
    try:
        if evidence_dir is None:
            staging = Path(tempfile.mkdtemp(prefix="medkit-replay-serve-"))
        served = _replay(inputs, configs, graph_file, evidence_dir or staging, at_sec, quiet)
        bound = listener.getsockname()
        where = f"http://{_url_host(bound[0])}:{bound[1]}"
        moment = "the end" if at_sec is None else f"{at_sec:g} s"
        click.echo(
            f"Serving {len(served.result.faults):,} faults, {len(served.result.events):,} "
            f"events at {where}/api/v1 (answers at {moment}; {where}/at/SECONDS for another "
            "moment); Ctrl-C stops",
            err=True,
        )
        app = build_app(served, speed=speed, cors=cors)
        config = uvicorn.Config(
            app,
            log_level="warning",
            # h11 cuts off a request head still arriving past the app's bound (httptools
            # would ignore the setting); the app answers 431 to a larger complete one.
            http="h11",
            h11_max_incomplete_event_size=MAX_REQUEST_HEAD_BYTES,
            timeout_graceful_shutdown=1,
            lifespan="off",
        )
        # uvicorn hands Ctrl-C and SIGTERM (docker stop, systemd) on once it has shut down:
        # the ways to stop, not failures.
        try:
            uvicorn.Server(config).run(sockets=[listener])
        except KeyboardInterrupt:
            pass
        except Terminated as stop:
            if stop.signum != signal.SIGTERM:
                raise
        click.echo("Stopped.", err=True)
    finally:
        listener.close()
        if staging is not None:
            shutil.rmtree(staging, ignore_errors=True)


def _listen(host: str, port: int) -> socket.socket:
    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    listener = socket.socket(family, socket.SOCK_STREAM)
    try:
        listener.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        # Accepted connections inherit it: without it a response sent in two writes (headers,
        # body) waits on the client's delayed ACK, 40 ms a request.
        listener.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        listener.bind((host, port))
        listener.listen(128)
    except OSError as err:
        listener.close()
        raise MedkitReplayError(f"cannot listen on {host}:{port}: {err.strerror or err}") from None
    return listener


def _url_host(host: str) -> str:
    return f"[{host}]" if ":" in host else host


def _replay(
    inputs: tuple[Path | str, ...],
    configs: tuple[Path, ...],
    graph_file: Path | None,
    clips_dir: Path | None,
    at_sec: float | None,
    quiet: bool,
) -> ServedRecording:
    """The replay with its fault history, and what the server answers from."""
    from medkit_replay.config.referenced import config_files  # noqa: PLC0415
    from medkit_replay.evidence import EvidenceOptions, load_graph  # noqa: PLC0415
    from medkit_replay.evidence.folder import refuse_folder_overlap  # noqa: PLC0415
    from medkit_replay.gateway.recording import served_recording  # noqa: PLC0415
    from medkit_replay.history import FaultHistory  # noqa: PLC0415
    from medkit_replay.pipeline import replay  # noqa: PLC0415

    read = [*local_paths(inputs), *config_files(configs)]
    if graph_file is not None:
        read.append(graph_file)
    if clips_dir is not None:
        refuse_folder_overlap(clips_dir, read)
    graph = load_graph(graph_file) if graph_file is not None else None
    history = FaultHistory()
    bar = None
    if not quiet:
        from medkit_replay.outputs.console import progress_bar  # noqa: PLC0415

        bar = progress_bar(sys.stderr)
    with bar if bar is not None else nullcontext():
        result = replay(
            list(inputs),
            list(configs),
            progress=bar,
            evidence=EvidenceOptions(graph=graph, directory=clips_dir),
            history=history,
        )
    if result.evidence_refused:
        raise foreign_clips(result.evidence_refused, outputs=False)
    from medkit_replay.outputs.console import warn  # noqa: PLC0415
    from medkit_replay.text import printable  # noqa: PLC0415

    for line in result.warnings:  # recorded text: shown escaped, as the summary shows it
        warn(printable(line))
    retained = retain_on_clear(configs)  # the files the replay read, read again
    return served_recording(result, history, graph, at_sec, retain_on_clear=retained)


def retain_on_clear(configs: Iterable[Path]) -> bool:
    """``snapshots.retain_on_clear`` as a replay with these config files applies it."""
    from medkit_replay.config.params import load_parameters  # noqa: PLC0415
    from medkit_replay.config.release import release_of  # noqa: PLC0415
    from medkit_replay.config.snapshots import snapshot_config  # noqa: PLC0415

    params = load_parameters(configs)
    snapshots, _ = snapshot_config(params.node("fault_manager"), release_of(params))
    return snapshots.retain_on_clear
