"""Each archived result published over MQTT, against a real broker (mosquitto, started here
on a free loopback port); skipped with the reason when mosquitto is not installed."""

from __future__ import annotations

import json
import shutil
import socket
import subprocess
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from stand.cli import main

ROOT = Path(__file__).resolve().parents[2]
MOSQUITTO = shutil.which("mosquitto") or (
    "/usr/sbin/mosquitto" if Path("/usr/sbin/mosquitto").exists() else None
)


@pytest.fixture
def broker(tmp_path: Path) -> Iterator[str]:
    if MOSQUITTO is None:
        pytest.skip("mosquitto is not installed (Debian: apt-get install mosquitto)")
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    conf = tmp_path / "mosquitto.conf"
    conf.write_text(f"listener {port} 127.0.0.1\nallow_anonymous true\npersistence false\n")
    proc = subprocess.Popen([MOSQUITTO, "-c", str(conf)], stdout=subprocess.DEVNULL,
                            stderr=subprocess.PIPE)  # fmt: skip
    try:
        end = time.monotonic() + 10
        while True:
            try:
                socket.create_connection(("127.0.0.1", port), timeout=0.5).close()
                break
            except OSError:
                assert proc.poll() is None and time.monotonic() < end, proc.stderr
                time.sleep(0.05)
        yield f"mqtt://127.0.0.1:{port}"
    finally:
        proc.terminate()
        proc.wait(10)


def _subscribe(url: str, topic: str, got: list[dict], ready: threading.Event) -> object:
    import paho.mqtt.client as mqtt
    from paho.mqtt.enums import CallbackAPIVersion

    host, port = url.removeprefix("mqtt://").split(":")
    client = mqtt.Client(CallbackAPIVersion.VERSION2)
    client.on_message = lambda c, u, msg: got.append(
        {"topic": msg.topic, "payload": json.loads(msg.payload)}
    )
    client.on_subscribe = lambda *a: ready.set()
    client.on_connect = lambda c, *a: c.subscribe(topic, qos=1)
    client.connect(host, int(port))
    client.loop_start()
    return client


@pytest.mark.realtime
def test_a_balanced_run_is_published_as_its_json(
    tmp_path: Path, broker: str, capsys: pytest.CaptureFixture[str]
) -> None:
    cfg = tmp_path / "cfg.toml"
    cfg.write_text((ROOT / "examples" / "demo-stand.toml").read_text()
                   + f'\n[plant]\nmqtt_url = "{broker}"\n')  # fmt: skip
    text = cfg.read_text().replace("[stand]\n", '[stand]\nid = "line-3/stand"\n', 1)
    cfg.write_text(text)
    got: list[dict] = []
    ready = threading.Event()
    client = _subscribe(broker, "stand/+/result", got, ready)
    assert ready.wait(10)
    url = f"sqlite:///{tmp_path / 'a.sqlite'}"
    argv = ["balance", "--scene", "demo", "--config", str(cfg), "--archive", url, "--json",
            "--out", str(tmp_path / "r.h5"), "--serial", "M-1"]  # fmt: skip
    assert main(argv) == 0
    out = json.loads(capsys.readouterr().out)
    end = time.monotonic() + 5
    while not got and time.monotonic() < end:
        time.sleep(0.05)
    client.loop_stop()  # type: ignore[attr-defined]
    assert len(got) == 1 and got[0]["topic"] == "stand/line-3_stand/result"
    message = got[0]["payload"]
    assert message["planes"] == out["planes"] and message["job"]["serial"] == "M-1"
    assert message["stand"]["id"] == "line-3/stand"


def test_a_broker_that_does_not_answer_is_a_note_not_a_failure(tmp_path: Path) -> None:
    from stand.config import load_config
    from stand.plant import publish_archived
    from stand.solve import solve_recording

    run = tmp_path / "r.h5"
    assert main(["simulate", "demo", "--out", str(run)]) == 0
    cfg = tmp_path / "cfg.toml"
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        dead = s.getsockname()[1]  # nothing listens once closed
    cfg.write_text((ROOT / "examples" / "demo-stand.toml").read_text()
                   + f'\n[plant]\nmqtt_url = "mqtt://127.0.0.1:{dead}"\n')  # fmt: skip
    said = publish_archived(solve_recording(str(run)), load_config(cfg)[0])
    assert said is not None and said.startswith("not published over MQTT") and str(dead) in said
