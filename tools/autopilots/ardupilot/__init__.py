"""ArduCopter SITL on our physics: its process, MAVLink driver, setpoints, bench and bridge
flights, and speed (the JSON physics end is bridge/autopilots/ardupilot/)."""
