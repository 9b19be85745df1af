"""MAVLink HIL transport: the sensor and actuator links between the bridge and an FC (ours or a foreign autopilot) over UDP, TCP or a serial line."""
