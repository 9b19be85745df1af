"""Faults on purpose (issue 28): the engine (engine.py: FaultEngine, ActiveFault) and the
appliers of the bridge's own units, each beside what it changes: sensors.py (gyro, accel,
baro, mag in the C sensor stage), gnss.py (the GNSS model), motors.py (thrust scale, ESC
desync, damaged prop); failure_checks.py holds the scenario rules that span tables.
The catalog of units, types and parameters is shm/fault_catalog.py.
Nothing is imported here: scenario.py loads failure_checks without the simulator's parts."""
