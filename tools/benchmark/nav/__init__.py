"""The navigation benchmark, `silbridge bench --suite nav`: N1..N4 flown by one scripted
MAVLink client against our FC, ArduCopter and PX4 on the same JSBSim physics and seeds, and
scored from the bridge's ground truth (docs/howto/nav-bench.md).

plans.py       what N1..N4 fly (points, legs, missions) and on which physics (nav_*.toml)
geo.py         local NE metres <-> latitude/longitude, as the bridge's ground truth
link.py        the UDP and TCP byte links
client.py      the MAVLink client (one codec per link, paced on the vehicle's clock)
ways.py        how each autopilot is asked (modes, take-off, goto, offboard, missions)
scripts.py     the client's flight of each N
spline.py      the reference path of a mission (straight legs, ArduCopter's spline legs)
scoring.py     metrics of a trajectory against its plan (pure functions)
run_ours.py, run_ardupilot.py, run_px4.py (+ in_process.py)   one run per controller
campaign.py    every run of the suite, scored from its log
table.py       the table (printed, JSON); report.py the report page
command.py     `bench --suite nav`: options checked, campaign, outputs
"""
