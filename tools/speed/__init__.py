"""`silbridge speed`: the lockstep's speed beside its references, from one interleaved run.

cases.py says what one run of each case is (bare JSBSim, our flights, ArduCopter's own
physics), rounds.py runs them interleaved, figures.py turns the runs into medians, spreads,
ratios and the issue's targets. tools/cli/cmd_speed.py only parses and prints.
"""
