"""Each archived result published over MQTT (paho-mqtt), for the plant's line systems.

``[plant] mqtt_url = "mqtt://broker:1883"``: one message per archived run on the topic
``stand/<stand id>/result``, QoS 1 (the broker confirms it), retained (a system that
subscribes later gets the latest).  The message (:func:`payload`) joins the other views:
its ``schema``, the archive's run id (``stand history``'s ``id``), the OPC UA ResultId,
the stand id, the overall verdict, the run file's name and SHA-256, and the result's own
JSON form (:func:`stand.solve.result_json.to_json`) under ``result``, every file in it
named by its name alone (no folder of the stand's machine).

A plant's broker takes the stand with its own credentials and certificates: ``[plant]
mqtt_password_file`` (the user name on its first line, the password on its second; never
in the URL), ``mqtt_ca_file`` (the CA the broker's certificate is checked against, else
the system's) and ``mqtt_cert_file`` + ``mqtt_key_file`` (the stand's client
certificate), through paho's ``username_pw_set`` and ``tls_set``.  Its
JSON Schema is :data:`SCHEMA_FILE` (published in ``docs/``).  A broker that does not
answer costs at most :data:`TIMEOUT_S` and is said in a warning: the run and its archive
row are kept whatever happens.

Beside it, retained too, the audit trail's head on ``stand/<stand id>/audit-head``
(:func:`head_payload`: the newest entry's ``id:sha256`` the anchor beside the stand's key
keeps, and the key's id), so that the plant keeps a head outside the stand: given back
to ``stand audit verify --head``, it finds entries deleted or rewritten since.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any
from urllib.parse import urlsplit

from stand.archive import file_digest, verdict
from stand.archive.audit import anchored_head
from stand.archive.keys import stand_key
from stand.config import Config
from stand.errors import ArchiveError, KeyFileError, RecordingError, UsageError
from stand.files import check_input, without_folders
from stand.solve import Result, json_text, to_json

TIMEOUT_S = 5.0
"""How long to wait for the broker to take a result [s]."""
SCHEMA = "urn:rotor-stand:mqtt-result:3"
"""The payload's ``schema`` field: its JSON Schema's ``$id``."""
SCHEMA_FILE = Path(__file__).resolve().parent / "mqtt-result.schema.json"
"""The payload's JSON Schema (draft 2020-12), shipped with the package."""


def payload(result: Result, run_id: int) -> dict[str, Any]:
    """The message of one archived run (``run_id``, the archive's)."""
    out = _named(to_json(result))
    run_file = Path(result.provenance.run_file or "").resolve()
    return {
        "schema": SCHEMA,
        "run_id": run_id,
        "result_id": str(run_id),
        "stand": result.provenance.stand_id or None,
        "verdict": verdict(out),
        "run_file": run_file.name,
        "file_sha256": file_digest(run_file),
        "result": out,
    }


def _named(x: Any) -> Any:
    """``x`` (JSON) with every absolute path in its texts cut to the file's name."""
    if isinstance(x, str):
        return without_folders(x)
    if isinstance(x, dict):
        return {k: _named(v) for k, v in x.items()}
    if isinstance(x, list):
        return [_named(v) for v in x]
    return x


HEAD_SCHEMA = "urn:rotor-stand:audit-head:1"
"""The audit head message's ``schema`` field."""


def topic(stand_id: str, what: str = "result") -> str:
    """``stand/<stand id>/result`` (or ``/audit-head``; MQTT's wildcards and separators
    kept out of the id)."""
    safe = "".join("_" if c in "/+#" else c for c in stand_id) or "stand"
    return f"stand/{safe}/{what}"


def head_payload(stand_id: str | None, head: str) -> dict[str, Any]:
    """The audit head message: the stand, the head (``id:sha256``) and the key's id."""
    return {"schema": HEAD_SCHEMA, "stand": stand_id, "head": head, "key_id": stand_key().id}


def credentials(path: str) -> tuple[str, str]:
    """The broker's user name and password from ``path`` (first and second line; a FIFO or
    a folder refused before it is opened).  UsageError naming the file."""
    try:
        lines = check_input(path).read_text(encoding="utf-8").splitlines()
    except (RecordingError, OSError, UnicodeDecodeError) as exc:
        raise UsageError(f"[plant] mqtt_password_file {path}: cannot be read ({exc})") from exc
    if len(lines) < 2 or not lines[0].strip() or not lines[1]:
        raise UsageError(f"[plant] mqtt_password_file {path}: the user name on the first line, "
                         "the password on the second")  # fmt: skip
    return lines[0].strip(), lines[1]


def _secure(client: Any, plant: Any, tls: bool) -> None:
    """The plant's credentials and certificates on ``client`` (``plant``: the ``[plant]``
    table, or None)."""
    if plant is not None and plant.mqtt_password_file:
        client.username_pw_set(*credentials(plant.mqtt_password_file))
    if tls:
        ca = None if plant is None else plant.mqtt_ca_file
        cert = None if plant is None else plant.mqtt_cert_file
        key = None if plant is None else plant.mqtt_key_file
        client.tls_set(ca_certs=ca, certfile=cert, keyfile=key)


def publish(result: Result, run_id: int, url: str, head: str | None = None,
            plant: Any = None) -> str:  # fmt: skip
    """Publish one archived result (and the audit trail's ``head`` after it, when given);
    the result's topic.  ``plant``: the ``[plant]`` table, for the broker's credentials and
    certificates.  ArchiveError (naming the broker) if it is not taken."""
    import paho.mqtt.client as mqtt
    from paho.mqtt.enums import CallbackAPIVersion, MQTTProtocolVersion

    u = urlsplit(url)
    tls = u.scheme == "mqtts"
    host, port = u.hostname or "localhost", u.port or (8883 if tls else 1883)
    where = f"{u.scheme}://{host}:{port}"
    name = topic(result.provenance.stand_id or "stand")
    client = mqtt.Client(
        CallbackAPIVersion.VERSION2, client_id="", protocol=MQTTProtocolVersion.MQTTv311
    )
    try:
        _secure(client, plant, tls)
        client.connect(host, port, keepalive=30)
        client.loop_start()
        messages = [(name, json_text(payload(result, run_id)))]
        if head is not None:
            stand = result.provenance.stand_id or None
            messages.append((topic(stand or "stand", "audit-head"),
                             json_text(head_payload(stand, head))))  # fmt: skip
        for subject, text in messages:
            info = client.publish(subject, text, qos=1, retain=True)
            info.wait_for_publish(TIMEOUT_S)
            if not info.is_published():
                raise ArchiveError(f"the broker did not take {subject} within {TIMEOUT_S:g} s",
                                   url=where)  # fmt: skip
    except (OSError, ValueError, RuntimeError) as exc:  # ssl.SSLError is an OSError
        raise ArchiveError(f"cannot publish the result ({without_folders(str(exc))})",
                           url=where) from exc  # fmt: skip
    finally:
        client.disconnect()  # first: it wakes the network thread, which loop_stop joins
        client.loop_stop()  # (the other way round waits out the 30 s keepalive)
    return name


def publish_archived(result: Result, run_id: int, cfg: Config,
                     archive_url: str | None = None) -> str | None:  # fmt: skip
    """Publish an archived result (``run_id``, the archive's; the audit head of
    ``archive_url`` after it) when the config names a broker; a note (never an error) when
    it could not be: the run is archived and kept."""
    plant = getattr(cfg, "plant", None)
    if plant is None or not plant.mqtt_url:
        return None
    try:
        head = None if archive_url is None else anchored_head(archive_url)
        return f"published on {publish(result, run_id, plant.mqtt_url, head, plant)}"
    except (ArchiveError, KeyFileError, UsageError) as exc:
        return f"not published over MQTT: {exc}"
