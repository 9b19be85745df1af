"""PX4 SITL's MAVLink simulator link, served from our Simulator (PX4 itself is run by
tools/autopilots/px4/)."""
