"""silbridge.bridge: the simulator side of the loop.

JSBSim physics of our quad model (fdm.py, ../jsbsim_models), sensor models
(imu.py, lowrate.py, noise.py), disturbances and scripted setpoints
(disturbances.py, setpoints.py), the scenario format (scenario.py,
scenario_schema.py, scenarios/*.toml), and `Simulator` (simulator.py), which
turns one physics step into shm records (step_buffer.py). Around it: the
bridge's loop (bridge_loop.py, one step at a time), its driver (bridge_driver.py,
start-up checks, then lockstep or real time) and pacing (pacing.py).
"""
