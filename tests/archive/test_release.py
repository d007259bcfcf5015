"""A released certificate: one rule for the CLI and the station, signed with the stand's
Ed25519 key, checked by a customer with tools that are not ours (``openssl pkeyutl``;
``cryptography`` from a plain Python), and journaled the same from both front ends."""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from accounts import ADMIN_PASSWORD, with_accounts

from stand.actions import Actor, archive_run, release_certificate, signature_path
from stand.archive import file_digest
from stand.archive.audit import entries
from stand.archive.keys import stand_key
from stand.cli import main
from stand.report import render
from stand.solve import solve_recording

VOLATILE = ("id", "at_utc", "zone", "previous_sha256", "entry_sha256", "signature", "source")
"""What differs between two entries of the same change made at two moments."""


def _public_key(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> Path:
    capsys.readouterr()
    assert main(["audit", "key"]) == 0
    pem = tmp_path / "stand-key.pub.pem"
    pem.write_text(capsys.readouterr().out)
    return pem


def _released(tmp_path: Path, run: Path) -> Path:
    """The certificate of ``run`` released from the CLI on a lone stand (HTML)."""
    cert = tmp_path / "cert.html"
    url = f"sqlite:///{tmp_path / 'a.sqlite'}"
    assert main(["report", str(run), "-o", str(cert), "--release", "--archive", url]) == 0
    return cert


@pytest.mark.skipif(shutil.which("openssl") is None, reason="openssl is not installed")
def test_a_customer_checks_the_signature_with_openssl(
    tmp_path: Path, demo_run: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    cert = _released(tmp_path, demo_run)
    sig = signature_path(cert)
    assert sig.stat().st_size == 64  # the raw Ed25519 signature
    pem = _public_key(tmp_path, capsys)
    assert pem.read_text().strip() in cert.read_text()  # printed on it
    check = ["openssl", "pkeyutl", "-verify", "-pubin", "-inkey", str(pem), "-rawin",
             "-in", str(cert), "-sigfile", str(sig)]  # fmt: skip
    done = subprocess.run(check, capture_output=True, text=True)
    assert done.returncode == 0 and "Verified Successfully" in done.stdout, done
    altered = tmp_path / "altered.html"
    altered.write_text(cert.read_text().replace("Release", "Re1ease", 1))
    check[check.index(str(cert))] = str(altered)
    assert subprocess.run(check, capture_output=True).returncode == 1


def test_a_customer_checks_it_with_cryptography_from_a_plain_python(
    tmp_path: Path, demo_run: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """As docs/people.md shows: only the ``cryptography`` package, none of ours."""
    cert = _released(tmp_path, demo_run)
    pem = _public_key(tmp_path, capsys)
    code = (
        "import sys\n"
        "from cryptography.hazmat.primitives.serialization import load_pem_public_key\n"
        "key = load_pem_public_key(open(sys.argv[1], 'rb').read())\n"
        "key.verify(open(sys.argv[3], 'rb').read(), open(sys.argv[2], 'rb').read())\n"
        "print('signature OK')\n"
    )
    done = subprocess.run([sys.executable, "-I", "-c", code, str(pem), str(cert),
                           str(signature_path(cert))], capture_output=True, text=True)  # fmt: skip
    assert done.returncode == 0 and done.stdout.strip() == "signature OK", done.stderr


def test_a_release_from_the_cli_and_the_station_journal_the_same(
    tmp_path: Path, demo_run: Path
) -> None:
    """The same run archived and released by the same account, once from the CLI and once
    from the station (its printing replaced by a copy of the page: Chromium is not what is
    compared): the two archives' entries differ only in what a moment and a source
    change."""
    run = tmp_path / "demo.h5"
    shutil.copy(demo_run, run)
    result = solve_recording(str(run))
    page = render(result)
    kept = {}
    for source in ("cli", "station"):
        url = with_accounts(f"sqlite:///{tmp_path / source}.sqlite",
                            ("ana", "setter", "a-long-password"))  # fmt: skip
        if source == "cli":
            assert main(["archive", "import", str(run), "--archive", url, "--as", "ana",
                         "--as-password-file", _pw(tmp_path)]) == 0  # fmt: skip
        else:
            archive_run(result, url, Actor("ana", "setter", "station"))
        target = tmp_path / f"{source}.html"
        release_certificate(url, Actor("ana", "setter", source), page, file_digest(run),
                            "certificate of run 1 (demo)", [target],
                            lambda text, t=target: t.write_text(text))  # fmt: skip
        kept[source] = [{k: v for k, v in e.items() if k not in VOLATILE}
                        for e in entries(url) if e["action"] in ("run", "release")]  # fmt: skip
    cli, station = kept["cli"], kept["station"]
    assert [e["action"] for e in cli] == ["run", "release"]
    # the released page names its moment: its digest differs; all else is the same
    for e in (cli[1], station[1]):
        e.pop("new_sha256")
        e.pop("detail")
    assert cli == station


def _pw(tmp_path: Path) -> str:
    path = tmp_path / "pw"
    path.write_text("a-long-password\n")
    return str(path)


def test_an_operator_may_not_release_and_is_journaled(tmp_path: Path, demo_run: Path) -> None:
    from stand.errors import RefusedError

    url = with_accounts(f"sqlite:///{tmp_path / 'a.sqlite'}",
                        ("kim", "operator", "a-long-password"))  # fmt: skip
    target = tmp_path / "c.html"
    with pytest.raises(RefusedError, match="kim \\(operator\\) may not release"):
        release_certificate(url, Actor("kim", "operator", "station"), "<html>", "0" * 64, "x",
                            [target], target.write_text)  # fmt: skip
    assert not target.exists() and not signature_path(target).exists()
    assert entries(url)[-1]["action"] == "refused"


def test_a_release_that_cannot_be_journaled_leaves_no_file(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The journal entry fails (the archive refuses the write): the certificate written
    for it and its signature are taken back, so no released file exists without its
    entry."""
    import stand.actions.door as door_module

    url = f"sqlite:///{tmp_path / 'a.sqlite'}"
    target = tmp_path / "c.html"
    target.write_text("the old one")

    def broken(*_: object, **__: object) -> dict[str, object]:
        raise RuntimeError("disk gone")

    monkeypatch.setattr(door_module, "append", broken)
    with pytest.raises(RuntimeError, match="disk gone"):
        release_certificate(url, Actor("os:x", None, "cli"), "<html>", "0" * 64, "x",
                            [target], target.write_text)  # fmt: skip
    assert target.read_text() == "the old one" and not signature_path(target).exists()
    assert entries(url) == []


def test_the_key_id_on_the_certificate_is_the_stand_keys(tmp_path: Path, demo_run: Path) -> None:
    url = f"sqlite:///{tmp_path / 'a.sqlite'}"
    cert = tmp_path / "cert.html"
    assert main(["report", str(demo_run), "-o", str(cert), "--release", "--archive", url,
                 "--reason", "customer copy"]) == 0  # fmt: skip
    (entry,) = entries(url, action="release")
    assert entry["key_id"] == stand_key().id and stand_key().id in cert.read_text()
    assert ADMIN_PASSWORD not in cert.read_text()
