"""The OPC UA result server on its own: the stand as a machine of OPC 40001-1 with its
results by OPC 40001-101, for a line's MES (:mod:`stand.plant.opcua.server`)."""

from __future__ import annotations

import argparse
import asyncio
import signal
import sys
from pathlib import Path
from typing import Any

from stand.archive import Archive, url_for
from stand.cli.common import actor_of, add_actor_arguments, add_archive_argument
from stand.config import default_stand_id, load_config, rotor_types_in
from stand.errors import UsageError
from stand.files import first_line
from stand.plant import Access, ResultServer


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "trust", nargs="?", choices=("trust",),
        help="trust FILE: trust an OPC UA client application's certificate (or its CA) on "
        "the encrypted endpoint (an administrator's change, journaled)",
    )  # fmt: skip
    p.add_argument("file", nargs="?", metavar="FILE", help="with trust: the certificate (PEM/DER)")
    p.add_argument("--port", type=int, default=4840, help="TCP port (default: 4840)")
    p.add_argument(
        "--host",
        default="127.0.0.1",
        help="address to serve on (default: 127.0.0.1; beyond this machine needs --user and "
        "--password-file)",
    )
    p.add_argument("--config", metavar="CFG", help="the stand's config: its [stand] id, archive")
    p.add_argument("--stand", metavar="ID", help="this stand's runs (default: the config's id)")
    p.add_argument(
        "--config-dir",
        metavar="DIR",
        help="the station's rotor types (its "
        "*.toml): the job orders the MES may send (default: the --config's only)",
    )
    add_archive_argument(p)
    p.add_argument("--user", help="the one user a client must log in as")
    p.add_argument("--password-file", metavar="FILE", help="the user's password (first line)")
    p.add_argument(
        "--anonymous-read", action="store_true",
        help="let anonymous clients on this machine read though the stand has accounts "
        "(off by default: once accounts exist, clients log in)",
    )  # fmt: skip
    add_actor_arguments(p)
    p.add_argument("--reason", help="with trust: why, for the audit trail")
    p.add_argument(
        "--cert-dir", metavar="DIR",
        help="where the server's certificate and key are kept, made on first start (beyond "
        "this machine only; default: opcua/ in the user's data folder)",
    )  # fmt: skip


def read_access(args: argparse.Namespace) -> Any:
    """The options' user and password (:class:`stand.plant.opcua.Access`)."""

    password = first_line(args.password_file, "a password") if args.password_file else None
    if bool(args.user) != bool(password):
        raise UsageError("stand opcua: --user and --password-file go together")
    return Access(args.user, password)


def _trust(args: argparse.Namespace) -> int:
    """``stand opcua trust FILE``: the client trusted for the server's certificate folder."""
    from stand.actions.keys import trust_opcua_client
    from stand.plant.opcua.security import cert_folder

    if not args.file:
        raise UsageError("stand opcua trust FILE: name the client's certificate (PEM or DER)")
    cfg = load_config(args.config)[0] if args.config else None
    url = url_for(args.archive, cfg)
    folder = cert_folder(Path(args.cert_dir) if args.cert_dir else None)
    made, entry = trust_opcua_client(url, actor_of(args, url), folder, args.file,
                                     reason=args.reason)  # fmt: skip
    print(
        f"trusted {made.name} in {made.parent} (audit entry {entry}); clients with it "
        "connect from their next session"
    )
    return 0


def run(args: argparse.Namespace) -> int:
    if args.trust:
        return _trust(args)
    if args.file:
        raise UsageError(f"stand opcua: {args.file!r}: a file goes with trust (stand opcua "
                         "trust FILE)")  # fmt: skip
    if not 0 < args.port < 65536:
        raise UsageError(f"--port must be 1 to 65535, got {args.port}")
    cfg = None
    if args.config:
        cfg = load_config(args.config)[0]
    stand = args.stand or (cfg.stand.stand_id() if cfg is not None else default_stand_id())
    url = url_for(args.archive, cfg)
    Archive(url).close()  # an archive that is no database: said now, not served on
    if args.config_dir and not Path(args.config_dir).is_dir():
        raise UsageError(f"--config-dir {args.config_dir}: not a folder")
    one = [cfg.rotor.type or Path(args.config).stem] if cfg is not None else []
    server = ResultServer(
        url,
        stand,
        args.host,
        args.port,
        read_access(args),
        cert_dir=Path(args.cert_dir) if args.cert_dir else None,
        rotor_types=(lambda: rotor_types_in(Path(args.config_dir)))
        if args.config_dir
        else (lambda: one),
        anonymous_read=args.anonymous_read,
    )

    async def main() -> None:
        loop = asyncio.get_running_loop()
        for sig in (signal.SIGINT, signal.SIGTERM):
            loop.add_signal_handler(sig, server.stop)
        task = asyncio.create_task(server.serve())
        while not server.ready.is_set() and not task.done():
            await asyncio.sleep(0.05)
        if server.ready.is_set():
            print(f"OPC UA on {server.endpoint} (Ctrl-C stops)", file=sys.stderr)
        await task

    asyncio.run(main())
    return 0
