"""The Q-DAS export read by readers nobody here wrote from the stand's code.

``aqdefreader`` (PyPI, successfactory) reads every value, placeholder and attribute of the
file as the archive holds them; a second reader, written here from AQDEF's key table alone
(each key's type and length, :data:`KEY_TABLE`, not from ``stand.plant.qdas.export``), checks
every key line and every field of every value set against its type and length.
"""

from __future__ import annotations

import contextlib
import io
import re
from pathlib import Path
from typing import Any

import pytest

from stand.cli import main

pytest.importorskip("aqdefreader", reason="aqdefreader (the test extra) is not installed")

KEY_TABLE: dict[str, tuple[str, int | None]] = {
    "K0001": ("F", 22), "K0002": ("I", 5), "K0004": ("D", None), "K0005": ("S", None),
    "K0006": ("AN", 14), "K0007": ("I", 10), "K0008": ("I", 10), "K0009": ("AN", 255),
    "K0010": ("I", 10), "K0011": ("S", None), "K0012": ("I", 10), "K0014": ("AN", 40),
    "K0053": ("AN", 20), "K0054": ("AN", 30), "K0100": ("I", 5), "K1001": ("AN", 30),
    "K1002": ("AN", 80), "K1081": ("AN", 24), "K1082": ("AN", 40), "K1900": ("AN", 255),
    "K2001": ("AN", 20), "K2002": ("AN", 80), "K2004": ("I", 3), "K2008": ("I", 5),
    "K2022": ("I", 2), "K2110": ("F", 22), "K2111": ("F", 22), "K2120": ("I", 3),
    "K2142": ("AN", 20),
}  # fmt: skip
"""AQDEF's keys as its key table gives them (type, longest length): AN text, I integer,
F number, D date ``DD.MM.YYYY/HH:MM:SS``, S events or parameters.  Written from the
published table (e.g. Hexagon's list of the K-fields Q-DAS supports), not from the code."""
POSITIONAL = ("K0001", "K0002", "K0004", "K0005", "K0006", "K0007", "K0008", "K0010",
              "K0011", "K0012")  # fmt: skip
"""The fields of a value set, in order."""


def _typed(key: str, value: str) -> None:
    kind, length = KEY_TABLE[key]
    assert length is None or len(value) <= length, (key, value)
    if value == "":
        return
    if kind == "I":
        assert re.fullmatch(r"-?\d+", value), (key, value)
    elif kind == "F":
        assert re.fullmatch(r"-?\d+(\.\d+)?", value), (key, value)
    elif kind == "D":
        assert re.fullmatch(r"\d\d\.\d\d\.\d{4}/\d\d:\d\d:\d\d", value), (key, value)
    else:
        value.encode("cp1252")  # AN: Windows-1252 text


def check_key_table(data: bytes) -> int:
    """Every line's key known, every value within its type and length; the fields checked."""
    checked = 0
    for line in data.decode("cp1252").split("\r\n"):
        if not line:
            continue
        if "\x0f" in line or "\x14" in line:
            for value_set in line.split("\x0f"):
                fields = value_set.split("\x14")
                assert len(fields) <= len(POSITIONAL)
                for key, value in zip(POSITIONAL, fields, strict=False):
                    _typed(key, value)
                    checked += 1
            continue
        key, _, value = line.partition(" ")
        field, _, index = key.partition("/")
        assert field in KEY_TABLE and (index == "" or index.isdigit()), line
        _typed(field, value)
        checked += 1
    return checked


@pytest.fixture(scope="module")
def exported(tmp_path_factory: pytest.TempPathFactory) -> tuple[bytes, list[Any], str]:
    from test_qdas import STAND, _archive

    from stand.archive.query import Filters, history

    tmp = tmp_path_factory.mktemp("foreign")
    url = f"sqlite:///{tmp / 'a.sqlite'}"
    _archive(url)
    out = tmp / "auger.dfq"
    argv = ["export", "qdas", "--rotor-type", "auger", "--archive", url, "-o", str(out),
            "--stand", STAND, "--runs", "--timezone", "UTC"]  # fmt: skip
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        assert main(argv) == 0
    runs = history(url, Filters(rotor_type="auger", kind="production", stand=STAND))
    return out.read_bytes(), [r for r in runs if r["serial"]], url


def test_aqdefreader_reads_every_value_placeholder_and_attribute(
    exported: tuple[bytes, list[Any], str],
) -> None:
    """One line per run (`--runs`): aqdefreader's characteristic k holds, in order, the
    values of every run that has one there (a first run: its initial; its residual only if
    it passed; a check: its residual), each with its attribute; the placeholders (255) are
    no value to it, never a 0.  The file is decoded in its code page (Windows-1252) and the
    lines handed to the reader's parser (its own encoding guess is chardet's)."""
    from aqdefreader.file import DfqFile

    data, runs, _ = exported
    with contextlib.redirect_stdout(io.StringIO()):  # it prints as it reads
        dfq = DfqFile(data.decode("cp1252").splitlines())
    assert dfq.part_count() == 1
    part = dfq.get_part(0)
    want: list[list[tuple[float, int]]] = [[] for _ in range(8)]
    for r in runs:
        first = r["checks_run"] is None
        for i, p in enumerate(r["planes"]):
            angle_attr = 129 if p["unbalance_g_mm"] <= p["uncertainty_g_mm"] else 0
            pair = [(p["unbalance_g_mm"], 0), (p["angle_deg"], angle_attr)]
            if first:
                want[4 * i] += pair[:1]
                want[4 * i + 1] += pair[1:]
            if not first or r["verdict"] == "pass":
                want[4 * i + 2] += pair[:1]
                want[4 * i + 3] += pair[1:]
    for k in range(8):
        got = part.get_characteristic_by_index(k + 1).get_measurements()
        assert len(got) == len(want[k]), k
        decimals = 1 if k % 2 else 2
        for m, (value, attr) in zip(got, want[k], strict=True):
            assert m.attribute == attr
            # written with `decimals` places (the archive's own rounding to 1e-3 adds 5e-4);
            # an angle of 359.96 deg is written 0.0
            err = abs(m.value - value)
            assert min(err, abs(err - 360.0)) <= 0.5 * 10**-decimals + 5e-4, (k, m.value, value)
    assert sum(len(w) for w in want) == sum(
        len(part.get_characteristic_by_index(k + 1).get_measurements()) for k in range(8)
    )


def test_every_key_and_field_has_the_type_and_length_of_the_key_table(
    exported: tuple[bytes, list[Any], str],
) -> None:
    """A reader written from the key table: every key known, every value within its type
    and length (8 value sets x 3 fields x 95 lines, and the keys)."""
    data, _, _ = exported
    assert check_key_table(data) > 95 * 8 * 3


@pytest.mark.parametrize(
    ("serial", "order", "says"),
    [
        ("S" * 41, "O-1", "K0014 (part ident) holds at most 40 characters"),
        ("S-1", "O" * 21, "K0053 (order) holds at most 20 characters"),
    ],
)
def test_an_ident_too_long_for_its_key_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], serial: str, order: str, says: str
) -> None:
    """A serial over K0014's 40 characters or an order over K0053's 20: one line naming the
    key, nothing written (never cut: two rotors would become one)."""
    from test_qdas import _result

    from stand.archive import Archive, rows
    from stand.sim import load_scene

    sc, p, _ = load_scene("demo")
    r = _result(sc, p, 1, 5000.0, serial, 2, order=order)
    url = f"sqlite:///{tmp_path / 'a.sqlite'}"
    with Archive(url) as archive:
        archive.add(*rows(r, "a" * 64, None))
    out = tmp_path / "x.dfq"
    assert main(["export", "qdas", "--rotor-type", "auger", "--archive", url, "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and says in err and not out.exists()
