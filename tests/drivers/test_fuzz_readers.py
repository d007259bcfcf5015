"""Fuzzing every reader: whatever the bytes, nothing but a StandError escapes.

Bounded (40 examples each, the same every run; HYPOTHESIS_PROFILE=thorough for 2000 new
ones each) so the suite stays fast and cannot hang on a rare input.  The seeds are small
valid files (a second of the demo run) with bytes flipped, cut or replaced, and random text
in each text format.
"""

from __future__ import annotations

import functools
import os
import tempfile
from pathlib import Path

import h5py
import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from stand.drivers import Frames, Recording, read_recording, read_streams, write_recording
from stand.drivers.runs.logs import write_log
from stand.drivers.runs.seal import seal, seal_state
from stand.drivers.v1.build import StreamBuilder
from stand.errors import StandError
from stand.sim import load_scene, simulate

THOROUGH = os.environ.get("HYPOTHESIS_PROFILE") == "thorough"
FUZZ = settings(
    max_examples=2000 if THOROUGH else 40,
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture],
    # the same 40 examples every run: a random one once made libhdf5 loop for ever inside
    # h5py's attrs.get on a damaged run file (2026-11-22); such a file is now refused by the
    # time-limited child read (stand.drivers.runs.seal), but a suite that fails on a rare input
    # now and then is worse than one that explores on request: the thorough profile does
    derandomize=not THOROUGH,
)
TEXT_FORMATS = (".log", ".asc", ".trc", ".csv")


@functools.cache
def _frames() -> Frames:
    sc, p, _ = load_scene("demo")
    data = sc.model_dump()
    data["run"]["seconds"] = 1.0
    return simulate(type(sc).model_validate(data, strict=False), p).frames


@functools.cache
def _seed(ext: str) -> bytes:
    """A valid small file of this format, as bytes."""
    with tempfile.TemporaryDirectory() as d:
        path = Path(d) / f"seed{ext}"
        if ext == ".h5":
            write_recording(Recording("seed", _frames()), path)
        else:
            write_log(_frames(), path)
        return path.read_bytes()


def _read_all_ways(path: Path) -> None:
    """Read as the commands do: frames whole, and streams in blocks."""
    for read in (read_recording, lambda p: read_streams(p, lambda meta: StreamBuilder())):
        try:
            read(path)
        except StandError:
            pass


@st.composite
def _mutated(draw: st.DrawFn, ext: str) -> bytes:
    data = bytearray(_seed(ext))
    how = draw(st.sampled_from(["flip", "cut", "splice"]))
    if how == "flip":
        for pos in draw(st.lists(st.integers(0, len(data) - 1), min_size=1, max_size=8)):
            data[pos] ^= draw(st.integers(1, 255))
    elif how == "cut":
        del data[draw(st.integers(0, len(data) - 1)) :]
    else:
        at = draw(st.integers(0, len(data)))
        data[at:at] = draw(st.binary(min_size=1, max_size=64))
    return bytes(data)


@FUZZ
@given(ext=st.sampled_from([*TEXT_FORMATS, ".blf", ".h5"]), data=st.data())
def test_a_damaged_file_of_any_format_gives_a_stand_error_or_frames(
    ext: str, data: st.DataObject
) -> None:
    blob = data.draw(_mutated(ext))
    with tempfile.TemporaryDirectory() as d:
        path = Path(d) / f"run{ext}"
        path.write_bytes(blob)
        _read_all_ways(path)


@FUZZ
@given(
    ext=st.sampled_from(TEXT_FORMATS),
    lines=st.lists(
        st.one_of(
            st.text(max_size=80),
            st.from_regex(r"\([0-9.e+-]{1,12}\) [a-z0-9]{1,6} [0-9A-Fa-f]{1,9}#[0-9A-FRr]{0,20}"),
        ),
        max_size=20,
    ),
)
def test_random_text_in_a_text_log_gives_a_stand_error_or_frames(
    ext: str, lines: list[str]
) -> None:
    with tempfile.TemporaryDirectory() as d:
        path = Path(d) / f"run{ext}"
        path.write_text("\n".join(lines), encoding="utf-8", errors="surrogatepass")
        _read_all_ways(path)


ATTRIBUTES = ["format", "format_version", "frames_committed", "config_toml", "config_sha256",
              "start_time", "software", "complete"]  # fmt: skip
VALUES = st.one_of(
    st.integers(-(2**63), 2**63 - 1),
    st.floats(allow_nan=True),
    st.text(  # what an HDF5 attribute can hold: no surrogates, no NUL
        st.characters(blacklist_categories=("Cs",), blacklist_characters="\x00"), max_size=30
    ),
    st.booleans(),
    st.lists(st.integers(-5, 5), max_size=4),
)


@FUZZ
@given(changes=st.dictionaries(st.sampled_from(ATTRIBUTES), VALUES, min_size=1, max_size=3))
def test_any_run_file_attributes_give_a_stand_error_or_a_run(changes: dict[str, object]) -> None:
    """Sealed again after the edit, as a forger who knows the seal's form would: the
    attributes reach the readers' own checks in this process (an unsealed file is read by
    a child first, the damaged-file test's path, 0.3 s an example)."""
    with tempfile.TemporaryDirectory() as d:
        path = Path(d) / "run.h5"
        path.write_bytes(_seed(".h5"))
        with h5py.File(path, "a") as f:
            for k, v in changes.items():
                f.attrs[k] = np.asarray(v) if isinstance(v, list) else v
        seal(path)
        assert seal_state(path) == "intact"
        _read_all_ways(path)
