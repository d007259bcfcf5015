"""Each archived result published over MQTT (paho-mqtt), for the plant's line systems.

``[plant] mqtt_url = "mqtt://broker:1883"``: one message per archived run on the topic
``stand/<stand id>/result``, QoS 1 (the broker confirms it), retained (a system that
subscribes later gets the latest).  The message (:func:`payload`) joins the other views:
its ``schema``, the archive's run id (``stand history``'s ``id``), the OPC UA ResultId,
the stand id, the overall verdict, the run file's absolute path and SHA-256, and the
result's own JSON form (:func:`stand.solve.result_json.to_json`) under ``result``.  Its
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
from stand.errors import ArchiveError, KeyFileError
from stand.solve import Result, json_text, to_json

TIMEOUT_S = 5.0
"""How long to wait for the broker to take a result [s]."""
SCHEMA = "urn:rotor-stand:mqtt-result:2"
"""The payload's ``schema`` field: its JSON Schema's ``$id``."""
SCHEMA_FILE = Path(__file__).resolve().parent / "mqtt-result.schema.json"
"""The payload's JSON Schema (draft 2020-12), shipped with the package."""


def payload(result: Result, run_id: int) -> dict[str, Any]:
    """The message of one archived run (``run_id``, the archive's)."""
    out = to_json(result)
    run_file = Path(result.provenance.run_file or "").resolve()
    return {
        "schema": SCHEMA,
        "run_id": run_id,
        "result_id": str(run_id),
        "stand": result.provenance.stand_id or None,
        "verdict": verdict(out),
        "run_file": str(run_file),
        "file_sha256": file_digest(run_file),
        "result": out,
    }


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


def publish(result: Result, run_id: int, url: str, head: str | None = None) -> str:
    """Publish one archived result (and the audit trail's ``head`` after it, when given);
    the result's topic.  ArchiveError (naming the broker) if it is not taken."""
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
    if tls:
        client.tls_set()
    try:
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
    except (OSError, ValueError, RuntimeError) as exc:
        raise ArchiveError(f"cannot publish the result ({exc})", url=where) from exc
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
        return f"published on {publish(result, run_id, plant.mqtt_url, head)}"
    except (ArchiveError, KeyFileError) as exc:
        return f"not published over MQTT: {exc}"
