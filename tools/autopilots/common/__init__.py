"""What flying a foreign autopilot on our physics shares, whichever it is.

The run and its process (run.py, process.py), the MAVLink driver's base (driver.py), the
setpoint forwarder's base (setpoints.py), the run log (log_sink.py) and the wiring of a bench
flight (flight.py).
"""
