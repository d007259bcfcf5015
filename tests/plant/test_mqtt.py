"""Each archived result published over MQTT, against a real broker (mosquitto, started here
on a free loopback port); skipped with the reason when mosquitto is not installed."""

from __future__ import annotations

import contextlib
import json
import shutil
import socket
import subprocess
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from foreign import ajv

from stand.cli import main
from stand.plant.mqtt import SCHEMA_FILE

ROOT = Path(__file__).resolve().parents[2]
MOSQUITTO = shutil.which("mosquitto") or (
    "/usr/sbin/mosquitto" if Path("/usr/sbin/mosquitto").exists() else None
)


@contextlib.contextmanager
def mosquitto(tmp_path: Path, settings: str) -> Iterator[int]:
    """A real mosquitto on a free loopback port with ``settings`` beside its listener;
    its port, once it takes connections."""
    if MOSQUITTO is None:
        pytest.skip("mosquitto is not installed (Debian: apt-get install mosquitto)")
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    conf = tmp_path / "mosquitto.conf"
    conf.write_text(f"listener {port} 127.0.0.1\npersistence false\n{settings}")
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
        yield port
    finally:
        proc.terminate()
        proc.communicate(timeout=10)  # and its stderr pipe closed: never left to the GC


@pytest.fixture
def broker(tmp_path: Path) -> Iterator[str]:
    with mosquitto(tmp_path, "allow_anonymous true\n") as port:
        yield f"mqtt://127.0.0.1:{port}"


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
    assert message["run_file"] == "r.h5"  # its name and digest: no folder of the stand
    assert str(tmp_path) not in json.dumps(message)
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


GOOD: dict = {"schema": "urn:rotor-stand:mqtt-result:3", "run_id": 3, "result_id": "3",
        "stand": "s", "verdict": "pass", "run_file": "r.h5", "file_sha256": "0" * 64,
        "result": {"rpm": 900.0, "planes": [
            {"plane": k, "unbalance_g_mm": 1.0, "angle_deg": 0.0, "uncertainty_g_mm": 0.1}
            for k in (1, 2)], "supports": [], "warnings": [],
                   "job": {"serial": None, "order": None, "operator": None,
                           "rotor_type": None},
                   "provenance": {"software": "x", "run_file": "r.h5",
                                  "config_sha256": "0" * 64}}}  # fmt: skip
"""A payload the schema takes."""


def test_a_payload_that_breaks_the_schema_is_caught() -> None:
    """The validation can fail: a payload without its run id, or with a folder in it."""
    import jsonschema

    good = json.loads(json.dumps(GOOD))
    validate(good)
    bads = [{k: v for k, v in good.items() if k != "run_id"}, good | {"run_file": "/home/ops/r.h5"},
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
    bads = [{k: v for k, v in good.items() if k != "run_id"}, good | {"run_file": "/home/ops/r.h5"},
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


def _pki(d: Path) -> dict[str, Path]:
    """A plant's CA, the broker's certificate for 127.0.0.1 and the stand's client
    certificate, both signed by it, and a stranger's certificate it did not sign (PEM,
    ``cryptography``)."""
    import datetime as dt
    import ipaddress

    from cryptography import x509
    from cryptography.hazmat.primitives import hashes, serialization
    from cryptography.hazmat.primitives.asymmetric import ec
    from cryptography.x509.oid import NameOID

    now = dt.datetime.now(dt.UTC)

    def make(name: str, issuer: Any, ca: bool, sign_key: Any = None) -> tuple[Any, Any]:
        key = ec.generate_private_key(ec.SECP256R1())
        subject = x509.Name([x509.NameAttribute(NameOID.COMMON_NAME, name)])
        b = (x509.CertificateBuilder().subject_name(subject)
             .issuer_name(subject if issuer is None else issuer.subject)
             .public_key(key.public_key()).serial_number(x509.random_serial_number())
             .not_valid_before(now - dt.timedelta(minutes=5))
             .not_valid_after(now + dt.timedelta(days=1))
             .add_extension(x509.BasicConstraints(ca=ca, path_length=None),
                            critical=True))  # fmt: skip
        if name == "127.0.0.1":
            b = b.add_extension(x509.SubjectAlternativeName(
                [x509.IPAddress(ipaddress.ip_address("127.0.0.1"))]), critical=False)  # fmt: skip
        return b.sign(sign_key or key, hashes.SHA256()), key

    ca, ca_key = make("plant CA", None, True)
    files = {}
    for name, cn, issuer, by in (("server", "127.0.0.1", ca, ca_key),
                                 ("client", "stand S-1", ca, ca_key),
                                 ("stranger", "stranger", None, None)):  # fmt: skip
        cert, key = make(cn, issuer, False, by)
        files[name] = d / f"{name}.pem"
        files[name].write_bytes(cert.public_bytes(serialization.Encoding.PEM))
        files[f"{name}-key"] = d / f"{name}.key"
        files[f"{name}-key"].write_bytes(key.private_bytes(
            serialization.Encoding.PEM, serialization.PrivateFormat.PKCS8,
            serialization.NoEncryption()))  # fmt: skip
    files["ca"] = d / "ca.pem"
    files["ca"].write_bytes(ca.public_bytes(serialization.Encoding.PEM))
    return files


@pytest.mark.realtime
def test_a_plant_broker_with_a_password_and_client_certificates(tmp_path: Path) -> None:
    """mosquitto with a password file, TLS and required client certificates: the stand
    publishes with `[plant]`'s password file, CA and client certificate; without the
    password, with a wrong one, or with a certificate the CA did not sign it is a note
    (the run kept), never a message; the URL never carries the password."""
    import os
    import shutil

    from stand.config import load_config
    from stand.plant import publish_archived
    from stand.solve import solve_recording

    if MOSQUITTO is None or shutil.which("mosquitto_passwd") is None:
        pytest.skip("mosquitto is not installed (Debian: apt-get install mosquitto)")
    pki = _pki(tmp_path)
    users = tmp_path / "users"
    subprocess.run(["mosquitto_passwd", "-b", "-c", str(users), "stand-s1", "broker-secret-9"],
                   check=True, capture_output=True)  # fmt: skip
    settings = (("user root\n" if os.geteuid() == 0 else "")
                + f"allow_anonymous false\npassword_file {users}\ncafile {pki['ca']}\n"
                f"certfile {pki['server']}\nkeyfile {pki['server-key']}\n"
                "require_certificate true\n")  # fmt: skip
    with mosquitto(tmp_path, settings) as port:
        run = tmp_path / "r.h5"
        assert main(["simulate", "demo", "--out", str(run)]) == 0
        result = solve_recording(str(run))
        demo = (ROOT / "examples" / "demo-stand.toml").read_text()

        def said(password: str, cert: str) -> str | None:
            (tmp_path / "pw").write_text(f"stand-s1\n{password}\n")
            cfg = tmp_path / "cfg.toml"
            cfg.write_text(demo + f'\n[plant]\nmqtt_url = "mqtts://127.0.0.1:{port}"\n'
                           f'mqtt_password_file = "{tmp_path / "pw"}"\n'
                           f'mqtt_ca_file = "{pki["ca"]}"\nmqtt_cert_file = "{pki[cert]}"\n'
                           f'mqtt_key_file = "{pki[cert + "-key"]}"\n')  # fmt: skip
            return publish_archived(result, 1, load_config(cfg)[0])

        ok = said("broker-secret-9", "client")
        assert ok is not None and ok.startswith("published on stand/"), ok
        for password, cert in (("wrong-secret", "client"), ("broker-secret-9", "stranger")):
            note = said(password, cert)
            assert note is not None and note.startswith("not published over MQTT"), note
            assert str(tmp_path) not in note and "broker-secret" not in note


@pytest.mark.parametrize(
    ("plant", "says"),
    [
        ('mqtt_url = "mqtt://b:1883"\nmqtt_ca_file = "ca.pem"', "need mqtts://"),
        ('mqtt_url = "mqtts://b"\nmqtt_cert_file = "c.pem"', "go together"),
        ('mqtt_password_file = "pw"', "need mqtt_url"),
        ('mqtt_url = "mqtt://user:pass@b:1883"', "mqtt_url"),
    ],
)
def test_the_broker_s_files_are_checked_with_the_config(
    tmp_path: Path, plant: str, says: str
) -> None:
    from stand.config import load_config
    from stand.errors import ConfigError

    cfg = tmp_path / "cfg.toml"
    cfg.write_text((ROOT / "examples" / "demo-stand.toml").read_text() + f"\n[plant]\n{plant}\n")
    with pytest.raises(ConfigError, match=says):
        load_config(cfg)
