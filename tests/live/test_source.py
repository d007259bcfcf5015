"""What a live measurement reads (``stand.live.source``): a scene of one protocol measured
with a config of another is refused on the command line, and taken with the scene's own
sensors by the station's simulated sources (its runs store the config they were read
with)."""

from __future__ import annotations

from pathlib import Path

import pytest

from stand.drivers.canopen.layout import PdoLayout
from stand.drivers.scan.layout import ScanLayout
from stand.errors import UsageError
from stand.live import live_source

DEMO = str(Path(__file__).resolve().parents[2] / "examples" / "demo-stand.toml")


@pytest.mark.parametrize(
    ("scene", "kind", "protocol"),
    [("demo-canopen", PdoLayout, "canopen"), ("demo-scan", ScanLayout, "scan")],
)
def test_the_station_takes_the_scenes_sensors(scene: str, kind: type, protocol: str) -> None:
    with pytest.raises(UsageError, match=f"sends protocol {protocol} frames"):
        live_source(scene, DEMO, "balance")
    src = live_source(scene, DEMO, "station", scene_hardware=True)
    assert src.acquisition is not None and isinstance(src.acquisition.layout, kind)
    assert f'protocol = "{protocol}"' in src.config_toml
    assert src.cfg.rotor.type == "demo-auger"  # the rest is the config's own
    assert (src.modules is not None) == (protocol == "canopen")


def test_a_scene_of_the_configs_protocol_keeps_the_config_text() -> None:
    src = live_source("demo", DEMO, "station", scene_hardware=True)
    assert src.acquisition is not None and src.acquisition.name == "v1"
    assert src.config_toml == Path(DEMO).read_text()
