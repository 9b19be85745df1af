"""Foreign autopilots on our physics: ArduCopter SITL over its JSON interface, PX4 SITL over
MAVLink HIL.

One subpackage per autopilot (`ardupilot/`, `px4/`: its process, driver, setpoints, flights)
and `common/` for what they share; the physics end of each link is bridge/autopilots/.
"""
