"""The failure benchmark, `silbridge bench --suite failures`: F1..F12, one fault class each
in the phase where it hurts most, flown by the nav suite's scripted MAVLink client against
our FC, ArduCopter and PX4 on the same JSBSim physics, seeds and fault times, and scored
from the bridge's ground truth (docs/howto/failure-bench.md).

failures.toml       F1..F12: phase, end, and the [[failure]] entries (physics.toml under them)
plans.py            the plans read and checked; each run's scenario file
translate.py        how each fault reaches each autopilot (ArduCopter's SIM_* table)
failsafe_params.py  the failsafe settings made equal across the three
watch.py            the client's timeline, its GCS silence, ArduCopter's SIM_* switches
script.py           the client's flight: take off, phase, watch through the fault
runs.py             one run per autopilot, on nav's runners
scoring.py          detection, action, outcome, deviations, landing distance (pure)
campaign.py         every run, scored; table.py the table; report.py the results page
command.py          `bench --suite failures`: options checked, campaign, outputs
merge.py            one table and page from a campaign flown in parts
"""
