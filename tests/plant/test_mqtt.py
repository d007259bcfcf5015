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
from foreign import ajv

from stand.cli import main
from stand.plant.mqtt import SCHEMA_FILE

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
        proc.communicate(timeout=10)  # and its stderr pipe closed: never left to the GC


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
    heads: list[dict] = []
    heard = threading.Event()
    head_client = _subscribe(broker, "stand/+/audit-head", heads, heard)
    assert heard.wait(10)
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
    validate(message)
    result = message["result"]
    assert result["planes"] == out["planes"] and result["job"]["serial"] == "M-1"
    assert result["stand"]["id"] == "line-3/stand" == message["stand"]
    assert message["run_file"] == str((tmp_path / "r.h5").resolve())
    assert message["verdict"] == "fail" and message["result_id"] == str(message["run_id"])
    # the audit trail's head beside it: the one the anchor keeps, which verify takes back
    from stand.archive.audit import anchored_head

    end = time.monotonic() + 5
    while not heads and time.monotonic() < end:
        time.sleep(0.05)
    head_client.loop_stop()  # type: ignore[attr-defined]
    assert [h["topic"] for h in heads] == ["stand/line-3_stand/audit-head"]
    kept = heads[0]["payload"]
    assert kept["head"] == anchored_head(url) and kept["stand"] == "line-3/stand"
    assert "/" not in json.dumps(kept).replace("line-3/stand", "")  # no path in it
    capsys.readouterr()
    assert main(["audit", "verify", "--archive", url, "--head", kept["head"]]) == 0
    # the check run: its own message, its own run id, linked in the archive
    got.clear()
    client.loop_start()  # type: ignore[attr-defined]
    check = ["balance", "--scene", "demo", "--config", str(cfg), "--archive", url, "--json",
             "--out", str(tmp_path / "c.h5"), "--serial", "M-1", "--check",
             str(tmp_path / "r.h5")]  # fmt: skip
    assert main(check) == 0
    capsys.readouterr()
    end = time.monotonic() + 5
    while not got and time.monotonic() < end:
        time.sleep(0.05)
    client.loop_stop()  # type: ignore[attr-defined]
    assert len(got) == 1
    second = got[0]["payload"]
    validate(second)
    by_ajv = ajv(SCHEMA_FILE, [message, second], tmp_path)  # a validator written elsewhere
    assert by_ajv == {"compiled": True, "results": [{"valid": True, "errors": []}] * 2}
    assert main(["history", "--archive", url, "--json"]) == 0
    first, checked = json.loads(capsys.readouterr().out)["runs"]
    assert (first["id"], first["file_sha256"]) == (message["run_id"], message["file_sha256"])
    assert (checked["id"], checked["checks_run"]) == (second["run_id"], first["id"])


def validate(message: dict) -> None:
    """The payload against its published JSON Schema, by jsonschema (written from the JSON
    Schema specification, not by this project), and the docs' copy is that schema."""
    import jsonschema

    from stand.plant.mqtt import SCHEMA

    schema = json.loads(SCHEMA_FILE.read_text())
    jsonschema.Draft202012Validator.check_schema(schema)
    jsonschema.Draft202012Validator(schema).validate(message)
    assert message["schema"] == SCHEMA == schema["$id"]


def test_the_docs_publish_the_payload_s_schema() -> None:
    """docs/plant.md carries the schema the package ships, key for key."""

    text = (ROOT / "docs" / "plant.md").read_text()
    block = text.split("<!-- mqtt-result.schema.json -->", 1)[1].split("```json", 1)[1]
    assert json.loads(block.split("```", 1)[0]) == json.loads(SCHEMA_FILE.read_text())


GOOD: dict = {"schema": "urn:rotor-stand:mqtt-result:2", "run_id": 3, "result_id": "3",
        "stand": "s", "verdict": "pass", "run_file": "/r.h5", "file_sha256": "0" * 64,
        "result": {"rpm": 900.0, "planes": [
            {"plane": k, "unbalance_g_mm": 1.0, "angle_deg": 0.0, "uncertainty_g_mm": 0.1}
            for k in (1, 2)], "supports": [], "warnings": [],
                   "job": {"serial": None, "order": None, "operator": None,
                           "rotor_type": None},
                   "provenance": {"software": "x", "run_file": "/r.h5",
                                  "config_sha256": "0" * 64}}}  # fmt: skip
"""A payload the schema takes."""


def test_a_payload_that_breaks_the_schema_is_caught() -> None:
    """The validation can fail: a payload without its run id, or with a relative path."""
    import jsonschema

    good = json.loads(json.dumps(GOOD))
    validate(good)
    bads = [{k: v for k, v in good.items() if k != "run_id"}, good | {"run_file": "r.h5"},
            good | {"verdict": "maybe"}]  # fmt: skip
    for bad in bads:
        with pytest.raises(jsonschema.ValidationError):
            validate(bad)


def test_ajv_compiles_the_schema_strictly_and_refuses_what_jsonschema_refuses(
    tmp_path: Path,
) -> None:
    """Ajv (JavaScript) in strict mode compiles the published schema (strictRequired,
    strictTypes, no unknown keywords) and judges the good payload and the three bad ones
    as jsonschema does."""
    good = json.loads(json.dumps(GOOD))
    bads = [{k: v for k, v in good.items() if k != "run_id"}, good | {"run_file": "r.h5"},
            good | {"verdict": "maybe"}]  # fmt: skip
    out = ajv(SCHEMA_FILE, [good, *bads], tmp_path)
    assert out["compiled"] is True, out
    assert [r["valid"] for r in out["results"]] == [True, False, False, False], out
    lax = tmp_path / "lax.json"  # the schema before: provenance requires keys it lacks
    schema = json.loads(SCHEMA_FILE.read_text())
    schema["properties"]["result"]["properties"]["provenance"].pop("properties")
    lax.write_text(json.dumps(schema))
    refused = ajv(lax, [], tmp_path)
    assert refused["compiled"] is False and "strictRequired" in refused["error"]


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
    said = publish_archived(solve_recording(str(run)), 1, load_config(cfg)[0])
    assert said is not None and said.startswith("not published over MQTT") and str(dead) in said
