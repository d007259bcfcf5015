"""Each archived result published over MQTT (paho-mqtt), for the plant's line systems.

``[plant] mqtt_url = "mqtt://broker:1883"``: the result's own JSON form
(:func:`stand.solve.result_json.to_json`) on the topic ``stand/<stand id>/result``, QoS 1 (the
broker confirms it), retained (a system that subscribes later gets the latest).  A broker
that does not answer costs at most :data:`TIMEOUT_S` and is said in a warning: the run and
its archive row are kept whatever happens.
"""

from __future__ import annotations

from typing import Any
from urllib.parse import urlsplit

from stand.errors import ArchiveError
from stand.solve import Result, json_text, to_json

TIMEOUT_S = 5.0
"""How long to wait for the broker to take a result [s]."""


def topic(stand_id: str) -> str:
    """``stand/<stand id>/result`` (MQTT's wildcards and separators kept out of the id)."""
    safe = "".join("_" if c in "/+#" else c for c in stand_id) or "stand"
    return f"stand/{safe}/result"


def publish(result: Result, url: str) -> str:
    """Publish one result; its topic.  ArchiveError (naming the broker) if it is not taken."""
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
        info = client.publish(name, json_text(to_json(result)), qos=1, retain=True)
        info.wait_for_publish(TIMEOUT_S)
        if not info.is_published():
            raise ArchiveError(f"the broker did not take the result within {TIMEOUT_S:g} s",
                               url=where)  # fmt: skip
    except (OSError, ValueError, RuntimeError) as exc:
        raise ArchiveError(f"cannot publish the result ({exc})", url=where) from exc
    finally:
        client.disconnect()  # first: it wakes the network thread, which loop_stop joins
        client.loop_stop()  # (the other way round waits out the 30 s keepalive)
    return name


def publish_archived(result: Result, cfg: Any) -> str | None:
    """Publish an archived result when the config names a broker; a note (never an error)
    when it could not be: the run is archived and kept."""
    plant = getattr(cfg, "plant", None)
    if plant is None or not plant.mqtt_url:
        return None
    try:
        return f"published on {publish(result, plant.mqtt_url)}"
    except ArchiveError as exc:
        return f"not published over MQTT: {exc}"
