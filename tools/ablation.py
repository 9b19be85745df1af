"""The stabilisation features of the paper and the FC switch behind each.

Ablation (paper 2.1, DESIGN "Ablation"): each feature switched off alone, and
all off, on the same seeds as the full controller.
"""

# feature name -> the FC parameter that enables it (1 = on)
FEATURES = {
    "dfilter": "SB_DFILT_EN",       # D-term PT2x2 filter (off: ArduCopter's PT1)
    "dclamp": "SB_DCLAMP_EN",       # D output clamp +-12 us
    "trim_ramp": "SB_TRIM_RAMP_EN",  # hover-trim 0.8 s ramp-in (off: applied as a step)
    "trust_ema": "SB_TRUST_EMA_EN",  # accel-trust EMA in the Mahony filter
    "blend": "SB_BLEND_EN",         # continuous EST/GT blending (off: discrete switch)
    "yaw_aw": "SB_YAW_AW_EN",       # yaw rate-PI anti-windup
    "slew": "SB_SLEW_EN",           # per-motor slew-rate limit
}


class UnknownFeature(ValueError):
    user_facing = True


def feature_params(features_off) -> dict:
    """Parameter overrides that switch the named features off."""
    out = {}
    for f in features_off:
        if f not in FEATURES:
            raise UnknownFeature(f"unknown feature {f!r}; choose from {', '.join(FEATURES)}")
        out[FEATURES[f]] = 0
    return out


def variants() -> list[tuple[str, tuple]]:
    """(label, features off) for the full controller, each feature alone, all off."""
    out = [("full", ())]
    out += [(f"no_{f}", (f,)) for f in FEATURES]
    out.append(("all_off", tuple(FEATURES)))
    return out
