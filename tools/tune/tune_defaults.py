"""The defaults of `silbridge tune`'s options, declared once.

The configurations that use them (tune_sysid.SweepConfig, tune_step.StepConfig,
tune_auto.AutoConfig, tune_anchor.run_autotune) take their defaults from here, and the
command line shows these same values in --help. This module imports nothing, so
building the parser needs neither scipy nor optuna (the `tune` extra).
"""

# The sweep (SweepConfig): ArduCopter's SID_* defaults for frequencies and fade-out; a
# shorter record and fade-in (SIL has no pilot to settle and no battery to spare);
# magnitudes small enough that no motor saturates or hits the slew limit at the top
# frequency.
SWEEP_F_START_HZ = 0.5
SWEEP_F_STOP_HZ = 40.0
SWEEP_T_FADE_IN_S = 5.0
SWEEP_T_REC_S = 40.0
SWEEP_MAGNITUDE_RATE_DPS = 15.0      # SID_MAGNITUDE for rate targets [deg/s]
SWEEP_MAGNITUDE_MIXER = 0.05         # SID_MAGNITUDE for mixer inputs (0-1)

# Step and doublet responses (StepConfig).
STEP_AMPLITUDE_DEG = 10.0
STEP_HOLD_S = 1.5
STEP_REPEAT = 2

# The gain search (AutoConfig).
AUTO_TRIALS = 60
AUTO_RUNS = 3                        # seeds per scenario in the before/after Table 1
AUTO_BATCH = 2                       # trials evaluated together (keeps every worker busy)
PM_MIN_DEG = 45.0                    # phase margin floor
GM_MIN_DB = 6.0                      # gain margin floor

# ArduCopter's AUTOTUNE (tune anchor): its own default aggressiveness.
AUTOTUNE_AGGR = 0.1
