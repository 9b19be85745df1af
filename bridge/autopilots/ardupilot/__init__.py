"""ArduPilot SITL's JSON physics interface, served from our Simulator (SITL itself is run by
tools/autopilots/ardupilot/)."""
