"""PX4 SITL on our physics: its process, offboard driver, rest-height check, setpoints, bench
and bridge flights, and speed (the simulator-link end is bridge/autopilots/px4/)."""
