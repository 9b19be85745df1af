"""The GCS server: what QGroundControl, MAVProxy and MAVSDK talk to (heartbeat, parameters, commands, missions, fence, rally, telemetry streams, MAVFTP)."""
