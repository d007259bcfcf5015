"""The plant's OPC UA wing: the stand's result server for the line's MES (OPC 40001-1
machinery, OPC 40001-3 job management, the result transfer add-in), its address space,
methods, events and who may connect (:mod:`stand.plant.opcua.server` and the modules it
builds on)."""

from stand.plant.opcua.server import Access, ResultServer

__all__ = ["Access", "ResultServer"]
