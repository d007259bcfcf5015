"""The operator station: a local web application at the stand (see stand.station)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from stand.archive import Archive, url_for
from stand.cli.common import DEFAULT_TARGET_PCT, TOLERANCE_SHARE
from stand.config import data_folder
from stand.config.paths import SHIPPED_ROTORS
from stand.errors import RecordingError, UsageError
from stand.files import check_input
from stand.i18n.language import LANGUAGES
from stand.plant import ResultServer, check_bind, read_token
from stand.solve.pipeline import precision_targets
from stand.station import Station
from stand.station.pages import serve


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--config-dir",
        metavar="DIR",
        help="the rotor types: one configuration (NAME.toml) each (default: the built-in "
        "demo auger)",
    )
    p.add_argument(
        "--runs-dir",
        metavar="DIR",
        help="where runs and their reports are written (default: runs/ in the user's data "
        "folder, beside the archive)",
    )
    p.add_argument("--archive", metavar="URL", help="the archive (default: the user's archive)")
    p.add_argument("--host", default="127.0.0.1", help="address to serve on (default: %(default)s)")
    p.add_argument("--port", type=int, default=8080, help="port (default: %(default)s)")
    p.add_argument("--token", help="required with a --host beyond this machine")
    p.add_argument("--token-file", metavar="FILE", help="the token, in a file's first line")
    p.add_argument("--no-browser", action="store_true", help="do not open a browser")
    p.add_argument(
        "--server-name",
        action="append",
        default=[],
        metavar="NAME",
        help="a name the station is reached by (its Host: header), beside its bind address; "
        "repeat for several (another Host: is refused)",
    )
    p.add_argument(
        "--session-hours",
        type=float,
        default=8.0,
        metavar="H",
        help="a session ends this long after its log-in, used or not (a shift; default: 8)",
    )
    p.add_argument("--certfile", metavar="PEM", help="serve HTTPS: the station's certificate")
    p.add_argument("--keyfile", metavar="PEM", help="serve HTTPS: its private key")
    p.add_argument(
        "--opcua",
        action="store_true",
        help="also serve the results over OPC UA (stand opcua), on --opcua-port",
    )
    p.add_argument("--opcua-port", type=int, default=4840, help="(default: %(default)s)")
    p.add_argument(
        "--anonymous-read", action="store_true",
        help="with --opcua: let anonymous OPC UA clients on this machine read though the "
        "stand has accounts (off by default: once accounts exist, clients log in)",
    )  # fmt: skip
    p.add_argument(
        "--lang",
        choices=tuple(LANGUAGES),
        default="en",
        help="the screens' language where the account names none (default: en)",
    )
    p.add_argument(
        "--max-seconds",
        type=float,
        default=120.0,
        help="the longest run, precise or not [s] (default: %(default)s)",
    )


def _check_tls(certfile: str | None, keyfile: str | None) -> None:
    """Both or neither, each a readable PEM file (one line naming which, exit 2)."""
    if (certfile is None) != (keyfile is None):
        raise UsageError("stand station: HTTPS takes --certfile and --keyfile together")
    for opt, path in (("--certfile", certfile), ("--keyfile", keyfile)):
        if path is None:
            continue
        try:
            with check_input(path).open("rb") as f:  # a FIFO refused before it is opened
                head = f.read(4096)
        except RecordingError as exc:
            raise UsageError(f"{opt} {exc}") from exc
        except OSError as exc:
            raise UsageError(f"{opt} {path}: cannot be read ({exc.strerror or exc})") from exc
        if b"-----BEGIN " not in head:
            raise UsageError(f"{opt} {path}: not a PEM file")


def _check_port(host: str, port: int, what: str) -> None:
    """Refuse in one line a port another program holds (uvicorn would say it in its own
    words, after the station had started); the port is free again when this returns."""
    import os
    import socket

    try:
        socket.create_server((host, port)).close()  # SO_REUSEADDR, as uvicorn binds
    except OSError as exc:
        why = os.strerror(exc.errno) if exc.errno else str(exc)
        raise UsageError(f"stand station: {what} {port} on {host} cannot be had ({why}): "
                         "another station or program holds it, or choose another"
                         ) from exc  # fmt: skip


def run(args: argparse.Namespace) -> int:

    token = read_token(args.token, args.token_file)
    check_bind(args.host, token)
    _check_tls(args.certfile, args.keyfile)
    if not 0.05 <= args.session_hours <= 24:
        raise UsageError(f"--session-hours must be within 0.05 to 24, got {args.session_hours}")
    if not 0 < args.port < 65536:
        raise UsageError(f"--port must be 1 to 65535, got {args.port}")
    if not args.max_seconds > 0:
        raise UsageError(f"--max-seconds must be > 0, got {args.max_seconds}")
    config_dir = Path(args.config_dir or SHIPPED_ROTORS)
    if not config_dir.is_dir():
        raise UsageError(f"--config-dir {config_dir}: not a folder")

    url = args.archive or Station.rotor_types_archive(config_dir) or url_for(None)
    Archive(url).close()  # not a database, or none to reach: one line before serving
    _check_port(args.host, args.port, "--port")
    if args.opcua:
        _check_port("127.0.0.1", args.opcua_port, "--opcua-port")
    runs = Path(args.runs_dir) if args.runs_dir else data_folder() / "runs"

    def targets(cfg: object, params: object, U: object) -> tuple[float, float]:
        return precision_targets(
            cfg, params, U,  # type: ignore[arg-type]
            tolerance_share=TOLERANCE_SHARE, default_pct=DEFAULT_TARGET_PCT,
        )  # fmt: skip

    station = Station(config_dir, runs, url, targets, max_seconds=args.max_seconds)
    station.default_language = args.lang
    station.sessions.lifetime_s = args.session_hours * 3600.0
    if args.opcua:  # beside the screens, on this machine only (stand opcua --host: beyond)

        def state() -> str:  # a cycle, or a plane turned to the mark, is the machine executing
            busy = station.snapshot().phase == "measuring" or station.drive.turning
            return "Executing" if busy else "NotExecuting"

        def mode() -> str:  # a simulated rotor is a rehearsal: nothing is produced
            return "Setup" if station.snapshot().simulated else "Processing"

        ua = ResultServer(url, station.stand_id(), "127.0.0.1", args.opcua_port, state=state,
                          rotor_types=station.rotor_types, anonymous_read=args.anonymous_read,
                          mode=mode)  # fmt: skip
        ua.run_in_thread()
        print(f"OPC UA on {ua.endpoint}", file=sys.stderr)
    scheme = "https" if args.certfile else "http"
    where = f"{scheme}://{args.host}:{args.port}/" + (" (type the token once)" if token else "")
    print(f"station at {where} (rotor types in {config_dir}; runs in {runs}; Ctrl-C ends)",
          file=sys.stderr)  # fmt: skip
    serve(station, host=args.host, port=args.port, token=token, show=not args.no_browser,
          names=args.server_name, certfile=args.certfile, keyfile=args.keyfile)  # fmt: skip
    return 0
