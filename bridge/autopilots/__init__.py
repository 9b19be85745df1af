"""The physics' end of each foreign autopilot's simulator link, one subpackage each.

`ardupilot/`: ArduPilot SITL's JSON physics (its servo packet in, our state line out, over
UDP); `px4/`: PX4's MAVLink simulator link (HIL_SENSOR and friends out, HIL_ACTUATOR_CONTROLS
in, over TCP or a serial line). Each has the same three parts: the wire format
(`json_protocol.py`, `hil_messages.py`), the lockstep rules around a Simulator with no sockets
(`physics.py`, so tests drive them directly) and the server that owns the link (`server.py`,
sharing its result and stop rules in bridge/serve_loop.py). Starting, flying and logging the
autopilots themselves is the toolkit's part: tools/autopilots/ (the bridge never imports it).
"""
