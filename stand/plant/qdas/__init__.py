"""The plant's Q-DAS wing: the archive's runs and the stand's evaluations as AQDEF
``.dfq`` files a quality system reads (:mod:`stand.plant.qdas.export`)."""

from stand.plant.qdas.export import export_qdas

__all__ = ["export_qdas"]
