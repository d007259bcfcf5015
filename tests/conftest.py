import os
import sys
from pathlib import Path

import pytest
from hypothesis import HealthCheck, settings

settings.register_profile(
    "default", max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow]
)
settings.register_profile("thorough", max_examples=5000, deadline=None)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "default"))

RUN_FILES_BEFORE = pytest.StashKey[set[Path]]()
"""The run files in the folder the suite runs in, when it started."""


JS = Path(__file__).resolve().parent / "js"
NODE_CLIENTS_SAID = "STAND_TESTS_NODE_CLIENTS"
"""Where the controlling process tells its workers why the Node.js clients are missing."""


def pytest_configure(config: pytest.Config) -> None:
    """Install the Node.js clients of other implementations (``tests/js``) exactly as
    its ``package-lock.json`` pins them (``npm ci``), once, by the controlling process
    before any worker starts, where npm is there and they are not installed yet; why not,
    otherwise, for the skips to say."""
    if hasattr(config, "workerinput"):
        return
    os.environ[NODE_CLIENTS_SAID] = _install_node_clients() or ""
    _compile_sources()


def _compile_sources() -> None:
    """Byte-compile the project's own modules once, before the workers start.  Where the
    environment forbids Python to write them at import (``PYTHONDONTWRITEBYTECODE``, as on
    the machines CI runs on), every process the tests start (the workers, CLI
    subprocesses, station servers, the time-limited child reads of unsealed run files)
    compiled the same modules again: 0.5 to 0.7 s a process (``import stand.station``:
    1.4 s against 2.1 s)."""
    import compileall

    for folder in ("stand", "drivers", "calib"):
        compileall.compile_dir(str(JS.parents[1] / folder), quiet=1, workers=0)


def _install_node_clients() -> str | None:
    """None once ``tests/js``'s packages are installed as the lock pins them; else why not."""
    import shutil
    import subprocess

    lock, done = JS / "package-lock.json", JS / "node_modules" / ".package-lock.json"
    if done.is_file() and done.stat().st_mtime >= lock.stat().st_mtime:
        return None
    if shutil.which("node") is None or shutil.which("npm") is None:
        return "Node.js and npm are not installed (apt-get install nodejs npm)"
    try:
        out = subprocess.run(["npm", "ci", "--prefix", str(JS), "--no-audit", "--no-fund",
                              "--loglevel=error"], capture_output=True, text=True,
                             timeout=600)  # fmt: skip
    except (OSError, subprocess.TimeoutExpired) as exc:
        return f"npm ci --prefix tests/js did not run ({exc})"
    if out.returncode != 0:
        last = (out.stderr.strip().splitlines() or ["no message"])[-1]
        return f"npm ci --prefix tests/js failed (exit {out.returncode}: {last[:200]})"
    return None


def pytest_xdist_auto_num_workers(config: pytest.Config) -> int:
    """``-n auto``: one worker more than every two cores (3 on a 2-core machine).  The
    ``realtime`` tests play scenes in real time and mostly wait on the clock (a stand's
    cycle, a live run: a few percent of a core each), so a worker beyond the cores keeps
    the cores busy while they wait.  Measured on the 2-core machine: see README."""
    cores = os.cpu_count() or 1
    return cores + max(1, cores // 2)


def pytest_sessionstart(session: pytest.Session) -> None:
    session.config.stash[RUN_FILES_BEFORE] = set(Path.cwd().glob("run-*.h5"))


def pytest_sessionfinish(session: pytest.Session, exitstatus: int) -> None:
    """Tests write into their own temporary folders, never a run file into the folder the
    suite runs in (a command's default ``run-<time>.h5`` lands there): the whole session
    fails if one did (judged once, by the controlling process, after every worker)."""
    if hasattr(session.config, "workerinput"):
        return
    left = set(Path.cwd().glob("run-*.h5")) - session.config.stash.get(RUN_FILES_BEFORE, set())
    if left:
        names = ", ".join(sorted(p.name for p in left))
        print(f"\nFAILED: tests left run files in {Path.cwd()}: {names}", file=sys.stderr)
        session.exitstatus = pytest.ExitCode.TESTS_FAILED


@pytest.fixture(scope="session")
def demo_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The demo scene simulated once for the whole session (read-only: copy to change it)."""
    from stand.cli import main

    path = tmp_path_factory.mktemp("demo") / "demo.h5"
    assert main(["simulate", "demo", "--out", str(path)]) == 0
    return path


@pytest.fixture(scope="session", autouse=True)
def _private_archive(tmp_path_factory: pytest.TempPathFactory) -> None:
    """The default archive (the user's data directory, via XDG_DATA_HOME) in a folder of
    the test session's own: balance and measure archive every run."""
    os.environ["XDG_DATA_HOME"] = str(tmp_path_factory.mktemp("xdg-data"))


def _pg_bin() -> Path | None:
    """The folder of PostgreSQL's server programs (Debian's package, or on PATH)."""
    import glob
    import shutil

    found = shutil.which("initdb")
    if found:
        return Path(found).resolve().parent
    versions = sorted(glob.glob("/usr/lib/postgresql/*/bin/initdb"))
    return Path(versions[-1]).parent if versions else None


@pytest.fixture(scope="session")
def postgres_url(tmp_path_factory: pytest.TempPathFactory):  # type: ignore[no-untyped-def]
    """A PostgreSQL server of the test session's own (a new cluster in a temporary folder,
    on a Unix socket there, stopped at the end): its SQLAlchemy URL."""
    import pwd
    import shutil
    import socket
    import subprocess

    bin_dir = _pg_bin()
    if bin_dir is None:
        pytest.skip("PostgreSQL's server is not installed (Debian: apt-get install postgresql)")
    as_user: list[str] = []
    if os.geteuid() == 0:  # initdb refuses root: run the server as Debian's postgres user
        try:
            pwd.getpwnam("postgres")
        except KeyError:
            pytest.skip("running as root and there is no 'postgres' user to run the server as")
        as_user = ["runuser", "-u", "postgres", "--"]
    import tempfile

    # not under pytest's own temporary root: that is private to root, and the server's
    # user must reach its folder (and a Unix socket path is at most 107 bytes)
    folder = Path(tempfile.mkdtemp(prefix="stand-pg-"))
    folder.chmod(0o777)
    data = folder / "data"
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    run = lambda *cmd: subprocess.run(  # noqa: E731
        [*as_user, *cmd], check=True, capture_output=True, text=True, timeout=120
    )
    run(str(bin_dir / "initdb"), "-D", str(data), "-U", "stand", "-A", "trust", "--no-sync")
    log = folder / "server.log"
    opts = f"-k {folder} -p {port} -c listen_addresses='' -c fsync=off"
    run(str(bin_dir / "pg_ctl"), "-D", str(data), "-l", str(log), "-o", opts, "-w", "start")
    try:
        yield f"postgresql+psycopg://stand@/postgres?host={folder}&port={port}"
    finally:
        subprocess.run(
            [*as_user, str(bin_dir / "pg_ctl"), "-D", str(data), "-m", "immediate", "stop"],
            capture_output=True,
            timeout=60,
        )
        shutil.rmtree(folder, ignore_errors=True)


def pytest_terminal_summary(terminalreporter, exitstatus, config):  # type: ignore[no-untyped-def]
    """At the run's end, what this machine could not test and how to enable it: each skip
    reason (they name the package to install) with how many tests it left out."""
    from collections import Counter

    skipped = terminalreporter.stats.get("skipped", [])
    reasons: Counter[str] = Counter()
    for report in skipped:
        longrepr = report.longrepr
        reason = longrepr[2] if isinstance(longrepr, tuple) else str(longrepr)
        reasons[reason.removeprefix("Skipped: ")] += 1
    if not reasons:
        return
    terminalreporter.section("not tested on this machine, and how to enable it")
    for reason, n in reasons.most_common():
        terminalreporter.write_line(f"{n:4d} test{'s' if n > 1 else ' '}  {reason}")
    terminalreporter.write_line(
        "(.ci/run installs every system package the tests use: sudo apt-get install "
        "postgresql mosquitto chromium chromium-driver poppler-utils nodejs npm gettext; "
        "then npm ci --prefix tests/js)"
    )
