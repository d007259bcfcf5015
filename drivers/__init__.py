"""The edge towards the hardware: CAN buses, the sensor-node protocol, recordings.

Empty until the CAN layer lands (issue "2 · CAN layer"). The numerical core
(:mod:`stand.core`) never imports this package.
"""
