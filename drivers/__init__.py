"""The edge towards the hardware: CAN buses (python-can), the sensor-node protocol, logs
and run files.  The numerical core (:mod:`stand.core`) never imports this package.
"""
