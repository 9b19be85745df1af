"""Foreign autopilots on our physics: ArduCopter SITL over its JSON interface, PX4 SITL over MAVLink HIL."""
