"""The TOML configuration: what is accepted, and one clear line for what is not."""

from __future__ import annotations

from pathlib import Path

import pytest

from stand.config import load_config
from stand.errors import ConfigError, StandError

ROOT = Path(__file__).resolve().parents[2]
DEMO = ROOT / "examples" / "demo-stand.toml"

MINIMAL = """\
[stand]
M1 = 8.0
M2 = 9.0
C1 = 4.5e4
C2 = 5.2e4

[rotor]
M3 = 60.0
J3 = 21.0
a = 0.15
b = 0.85
c = 0.70
d = 0.20
R1 = 0.09
R2 = 0.08
"""


def write(tmp_path: Path, text: str) -> Path:
    f = tmp_path / "stand.toml"
    f.write_text(text)
    return f


def test_the_shipped_demo_config_loads() -> None:
    cfg, p = load_config(DEMO)
    assert p.M3 == 60.0 and p.C2 == 5.2e4 and cfg.stand.reference_angle_deg == 0.0


def test_the_two_tables_alone_work_with_defaults(tmp_path: Path) -> None:
    cfg, p = load_config(write(tmp_path, MINIMAL))
    assert (p.H1, p.H2, cfg.stand.reference_angle_deg) == (0.0, 0.0, 0.0)


def test_integers_are_numbers(tmp_path: Path) -> None:
    _, p = load_config(write(tmp_path, MINIMAL.replace("M1 = 8.0", "M1 = 8")))
    assert p.M1 == 8.0


@pytest.mark.parametrize(
    ("edit", "where", "what"),
    [
        (("J3 = 21.0\n", ""), "[rotor.J3]", "missing (give it, or describe the shaft"),
        (("R2 = 0.08", 'R2 = "0.08"'), "[rotor.R2]", "valid number"),
        (("R2 = 0.08", "R2 = true"), "[rotor.R2]", "valid number"),
        (("C1 = 4.5e4", "C1 = inf"), "[stand.C1]", "finite"),
        (("C1 = 4.5e4", "C1 = nan"), "[stand.C1]", "finite"),
        (("M1 = 8.0", "M1 = 8.0\nmass = 3"), "[stand.mass]", "unknown key"),
        (("[rotor]", "[rotors]"), "[rotors]", "unknown table"),
        (("C1 = 4.5e4", "C1 = -4.5e4"), "[stand.C1]", "must be > 0"),
        (("M2 = 9.0", "M2 = -1.0"), "[stand.M2]", "must be >= 0"),
        (("a = 0.15", "a = -0.9"), "[rotor.b]", "centre of mass"),
        (("c = 0.70\nd = 0.20", "c = -0.9\nd = 1.2"), "[rotor.c]", "b + c"),
        (("J3 = 21.0", "J3 = 0.0"), "[rotor.J3]", "must be > 0"),
    ],
)
def test_bad_values_name_the_file_and_the_key(
    tmp_path: Path, edit: tuple[str, str], where: str, what: str
) -> None:
    f = write(tmp_path, MINIMAL.replace(*edit))
    with pytest.raises(ConfigError) as err:
        load_config(f)
    msg = str(err.value)
    assert msg.startswith(f"{f}: {where}: "), msg
    assert what in msg
    assert "\n" not in msg
    assert isinstance(err.value, StandError) and isinstance(err.value, ValueError)


def test_toml_syntax_error_names_the_file_and_line(tmp_path: Path) -> None:
    f = write(tmp_path, MINIMAL.replace("M2 = 9.0", "M2 = = 9.0"))
    with pytest.raises(ConfigError, match=r"stand\.toml: not valid TOML: .*line 3"):
        load_config(f)


def test_missing_and_binary_files(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="cannot read the configuration"):
        load_config(tmp_path / "nope.toml")
    f = tmp_path / "bin.toml"
    f.write_bytes(b"\xff\xfe\x00garbage")
    with pytest.raises(ConfigError, match="not UTF-8"):
        load_config(f)


def test_bus_table_goes_through_as_given_and_cli_options_override_it(tmp_path: Path) -> None:
    from stand.cli import build_parser
    from stand.cli.common import bus_kwargs

    text = MINIMAL + '\n[bus]\ninterface = "pcan"\nchannel = "PCAN_USBBUS1"\nbitrate = 500000\n'
    cfg, _ = load_config(write(tmp_path, text))
    assert cfg.bus == {"interface": "pcan", "channel": "PCAN_USBBUS1", "bitrate": 500000}
    args = build_parser("record").parse_args(
        [
            "record",
            "--out",
            "x.h5",
            "-b",
            "1000000",
            "--bus-kwargs",  # python-can's own option, as python -m can.logger takes it
            "receive_own_messages=True",
            "app_name=stand",
        ]
    )
    assert bus_kwargs(args, cfg.bus) == {
        "interface": "pcan",
        "channel": "PCAN_USBBUS1",
        "bitrate": 1000000,
        "receive_own_messages": True,
        "app_name": "stand",
    }
    assert load_config(DEMO)[0].bus is not None
    assert load_config(write(tmp_path, MINIMAL))[0].bus is None


def test_a_bus_value_that_is_not_a_plain_value_is_refused(tmp_path: Path) -> None:
    with pytest.raises(
        ConfigError, match=r"\[bus\.channel\]: expected text, a number or true/false"
    ):
        load_config(write(tmp_path, MINIMAL + "\n[bus]\nchannel = { x = 1 }\n"))


@pytest.mark.parametrize(("speed", "ok"), [("5e-324", False), ("0.5", False), ("1.0", True)])
def test_a_tolerance_speed_under_one_rpm_is_refused(tmp_path: Path, speed: str, ok: bool) -> None:
    text = MINIMAL + f"\n[tolerance]\ngrade_mm_s = 6.3\nmax_speed_rpm = {speed}\n"
    if ok:
        assert load_config(write(tmp_path, text))[0].tolerance is not None
    else:
        with pytest.raises(ConfigError, match=r"\[tolerance.max_speed_rpm\]"):
            load_config(write(tmp_path, text))


@pytest.mark.parametrize(
    ("table", "ok"),
    [
        ("delay_s = [1e300, 0]", False),  # used to give a plausible 5655.2 +- 3.0 g mm
        ("delay_s = [0.06, 0]", False),
        ("delay_s = [2.5e-4, -1e-4]", True),
        ("gain = [1e3, 1]", False),
        ("gain = [0.05, 1]", False),
        ("gain = [1.02, 0.97]", True),
    ],
)
def test_sensor_values_beyond_any_sensor_are_refused(tmp_path: Path, table: str, ok: bool) -> None:
    text = MINIMAL + f"\n[sensors]\n{table}\n"
    if ok:
        load_config(write(tmp_path, text))
    else:
        with pytest.raises(ConfigError, match=r"\[sensors\.(delay_s|gain)\.0\]"):
            load_config(write(tmp_path, text))


def test_python_can_s_own_bus_options_and_list_valued_bus_tables(tmp_path: Path) -> None:
    """--filter and --timing as python -m can.logger parses them; can_filters as a list in
    [bus], stored back as TOML that reads the same."""
    import tomllib

    from stand.cli import build_parser
    from stand.cli.common import bus_kwargs
    from stand.config import config_toml

    text = (
        MINIMAL
        + '\n[bus]\ninterface = "virtual"\ncan_filters = [{can_id = 0x101, can_mask = 0x7FF}]\n'
    )
    cfg, _ = load_config(write(tmp_path, text))
    assert cfg.bus == {"interface": "virtual", "can_filters": [{"can_id": 257, "can_mask": 2047}]}
    assert tomllib.loads(config_toml(cfg))["bus"] == cfg.bus
    argv = ["record", "--out", "x.h5", "--filter", "100:7FC", "--timing", "f_clock=8000000",
            "tseg1=5", "tseg2=2", "sjw=2", "brp=2", "nof_samples=1"]  # fmt: skip
    kw = bus_kwargs(build_parser("record").parse_args(argv), cfg.bus)
    assert kw["can_filters"] == [{"can_id": 0x100, "can_mask": 0x7FC}]
    assert type(kw["timing"]).__name__ == "BitTiming" and kw["interface"] == "virtual"


def test_an_updated_config_keeps_the_user_s_comments(tmp_path: Path) -> None:
    """calibrate wrote the config anew and dropped every comment the user had put in it."""
    from stand.config.edit import updated_toml
    from stand.config.schema import config_from_dict

    text = (ROOT / "examples" / "demo-stand.toml").read_text()
    cfg, _ = load_config(write(tmp_path, text))
    stand = cfg.stand.model_copy(update={"C1": 46123.5, "reference_angle_deg": 1.25})
    sensors = cfg.sensors.model_copy(update={"gain": [1.02, 0.98]})
    new = updated_toml(text, cfg.model_copy(update={"stand": stand, "sensors": sensors}))
    comments = [line.split("#", 1)[1] for line in text.splitlines() if "#" in line]
    assert all(c in new for c in comments)  # every comment, where it was
    import tomllib

    back, _ = config_from_dict(tomllib.loads(new), source="new")
    assert back.stand.C1 == 46123.5 and back.stand.reference_angle_deg == 1.25
    assert back.sensors.gain == [1.02, 0.98] and back.rotor == cfg.rotor
    # only what changed is written: the diff is the three values, no default spelled out
    import difflib

    added = [d for d in difflib.unified_diff(text.splitlines(), new.splitlines(), n=0, lineterm="")
             if d.startswith("+") and not d.startswith("+++")]  # fmt: skip
    keys = sorted(d[1:].split("=")[0].strip() for d in added if "=" in d)
    assert keys == ["C1", "gain", "reference_angle_deg"], added


@pytest.mark.parametrize(
    ("url", "ok"),
    [
        ("mqtt://broker", True),
        ("mqtts://10.0.0.5:8883/", True),
        ("mqtt://broker:65535", True),
        ("mqtt://broker:99999", False),  # passed the check before, failed at the first run
        ("mqtt://broker:0", False),
        ("mqtt://broker:65536", False),
        ("mqtt://broker:1883:1", False),
        ("http://broker", False),
        ("mqtt://10.0.0.5:1883", True),
        ("mqtt://broker.plant-3.example", True),
        ("mqtt://bro ker", False),
        ("mqtt://user@broker", False),  # credentials do not belong in a config's URL
        ("mqtt://broker?x=1", False),
        ("mqtt://-broker", False),
        ("mqtt://", False),
    ],
)
def test_the_mqtt_url_is_a_url_with_a_port_that_exists(tmp_path: Path, url: str, ok: bool) -> None:
    text = MINIMAL + f'\n[plant]\nmqtt_url = "{url}"\n'
    if ok:
        assert load_config(write(tmp_path, text))[0].plant.mqtt_url == url
    else:
        with pytest.raises(ConfigError, match=r"\[plant.mqtt_url\]"):
            load_config(write(tmp_path, text))
