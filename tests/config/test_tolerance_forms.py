"""``[tolerance]`` in every form a customer writes, and ``[[rotor.keys]]``: each accepted,
each ambiguity and nonsense refused in one line naming the key."""

from __future__ import annotations

from pathlib import Path

import pytest
from test_config import MINIMAL, write

from stand.cli import main
from stand.config import load_config
from stand.errors import ConfigError

FORMS = {
    "grade": "grade_mm_s = 6.3\nmax_speed_rpm = 1500.0",
    "grade in bearing planes": (
        "grade_mm_s = 6.3\nmax_speed_rpm = 1500\nbearing_planes_m = [0.1, 1.8]"
    ),
    "per plane": 'per_plane_g_mm = [15.0, 20.0]\nsource = "drawing 4711 C"',
    "static and couple": "static_g_mm = 900.0\ncouple_g_mm2 = 4e5",
    "api": "api_journal_kg = [28.0, 32.0]\nmax_speed_rpm = 1500",
    "later check": 'grade_mm_s = 2.5\nmax_speed_rpm = 3000\nacceptance = "later_check"',
}


@pytest.mark.parametrize("body", FORMS.values(), ids=list(FORMS))
def test_every_form_is_accepted(tmp_path: Path, body: str) -> None:
    cfg, _ = load_config(write(tmp_path, MINIMAL + "\n[tolerance]\n" + body + "\n"))
    assert cfg.tolerance is not None


REFUSED = {  # body -> what the one line must say
    "": "no tolerance form",
    "max_speed_rpm = 1500": "no tolerance form",
    "grade_mm_s = 6.3": "no tolerance form",
    "grade_mm_s = 6.3\nmax_speed_rpm = 1500\nper_plane_g_mm = [1, 2]": "more than one",
    "grade_mm_s = 6.3\nmax_speed_rpm = 1500\napi_journal_kg = [30, 30]": "one form per rotor",
    "grade_mm_s = 6.3\nmax_speed_rpm = 1500\nstatic_g_mm = 5": "does not belong",
    "per_plane_g_mm = [1, 2]\nbearing_planes_m = [0, 1]": "grade and API forms only",
    "per_plane_g_mm = [1]": "per_plane_g_mm",
    "per_plane_g_mm = [0, 2]": "per_plane_g_mm",
    "per_plane_g_mm = [1e300, 2]": "per_plane_g_mm",
    "static_g_mm = -1\ncouple_g_mm2 = 4": "static_g_mm",
    "grade_mm_s = 1e-300\nmax_speed_rpm = 1500": "grade_mm_s",
    "grade_mm_s = 6.3\nmax_speed_rpm = 1e300": "max_speed_rpm",
    'grade_mm_s = 6.3\nmax_speed_rpm = 1500\nacceptance = "someday"': "acceptance",
    "grade_mm_s = 6.3\nmax_speed_rpm = 1500\nbearing_planes_m = [1.0, 0.2]": "bearing A",
    "grade_mm_s = 6.3\nmax_speed_rpm = 1500\nbearing_planes_m = [0, 900]": "outside the rotor",
    "grade_mm_s = 6.3\nmax_speed_rpm = 1500\nbearing_planes_m = [-5, 9]": "bearing A at -5 m",
    "api_journal_kg = [300, 300]\nmax_speed_rpm = 1500": "rotor's M3 is 60",
    "api_journal_kg = [30, 30]\nmax_speed_rpm = 0.5": "max_speed_rpm",
}


@pytest.mark.parametrize("body", REFUSED, ids=range(len(REFUSED)))
def test_ambiguous_and_nonsense_forms_are_refused(tmp_path: Path, body: str) -> None:
    with pytest.raises(ConfigError, match="tolerance") as err:
        load_config(write(tmp_path, MINIMAL + "\n[tolerance]\n" + body + "\n"))
    assert REFUSED[body] in str(err.value) and "\n" not in str(err.value)


KEY = """
[[rotor.keys]]
{where}
angle_deg = 30.0
width_mm = 10.0
height_mm = 8.0
length_mm = {length}
radius_mm = 40.0
convention = "half"
"""


@pytest.mark.parametrize(
    ("where", "length", "says"),
    [
        ("plane = 1", 240, None),
        ("position_m = 0.5", 240, None),
        ("", 240, "plane or its position_m"),
        ("plane = 1\nposition_m = 0.5", 240, "plane or its position_m"),
        ("plane = 3", 240, "rotor.keys"),
        ("position_m = 90.0", 240, "lies outside the rotor"),
        ("plane = 1", 10000, "more than a tenth"),
    ],
)
def test_keys_are_checked_against_the_rotor(
    tmp_path: Path, where: str, length: float, says: str | None
) -> None:
    text = MINIMAL + KEY.format(where=where, length=length)
    if says is None:
        (key,) = load_config(write(tmp_path, text))[0].rotor.keys
        assert key.mass_kg == pytest.approx(0.15072)
        return
    with pytest.raises(ConfigError, match=r"rotor\.keys") as err:
        load_config(write(tmp_path, text))
    assert says in str(err.value)


def test_a_key_beyond_the_rotor_and_keys_heavier_than_it_are_refused(tmp_path: Path) -> None:
    """A key at 5 m radius on a rotor whose largest correction radius is 90 mm; sixteen keys
    that weigh more together than a tenth of the rotor, each alone light enough."""
    far = MINIMAL + KEY.format(where="plane = 1", length=240).replace(
        "radius_mm = 40.0", "radius_mm = 5000.0"
    )
    with pytest.raises(ConfigError, match=r"rotor\.keys\[0\]\.radius_mm.*largest correction"):
        load_config(write(tmp_path, far))
    many = MINIMAL + KEY.format(where="plane = 1", length=2000) * 16  # 1.256 kg each
    with pytest.raises(ConfigError, match=r"rotor\.keys\[4\].*together"):
        load_config(write(tmp_path, many))


def test_a_bad_form_is_one_line_and_exit_2_from_the_cli(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    cfg = write(tmp_path, MINIMAL + "\n[tolerance]\nper_plane_g_mm = [1, 2]\nstatic_g_mm = 3\n")
    assert main(["simulate", "demo", "--out", str(tmp_path / "r.h5"), "--config", str(cfg)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "tolerance" in err[0] and "Traceback" not in err[0]
