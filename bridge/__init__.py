"""silbridge.bridge: the simulator side of the loop.

JSBSim physics of our quad model (fdm.py, ../jsbsim_models), sensor models
(imu.py, lowrate.py, noise.py), disturbances and scripted setpoints
(disturbances.py, setpoints.py), the scenario format (scenario.py,
scenario_schema.py, scenarios/*.toml), and `Simulator` (simulator.py), which
turns one physics step into shm records (step_buffer.py). The run loop, pacing
and lockstep around it live in runner*/pacing*/lockstep* modules.
"""
