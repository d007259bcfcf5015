"""The plant's systems, a wing each where they are many modules: Q-DAS files for the
quality engineer's statistics (:mod:`stand.plant.qdas`), an OPC UA result server for the
line (:mod:`stand.plant.opcua`), results published over MQTT (:mod:`stand.plant.mqtt`), and
the bind rule and token every server of the stand keeps to (:mod:`stand.plant.safety`).
They read the archive and format Results; they never measure.
"""

from stand.plant.mqtt import publish_archived
from stand.plant.opcua import Access, ResultServer
from stand.plant.qdas import export_qdas
from stand.plant.safety import TokenGate, check_bind, is_local, read_token

__all__ = [
    "Access",
    "ResultServer",
    "TokenGate",
    "check_bind",
    "export_qdas",
    "is_local",
    "publish_archived",
    "read_token",
]
