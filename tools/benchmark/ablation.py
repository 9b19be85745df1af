"""The ablation study's variants, read from the one feature declaration.

The stabilisation features and the FC switch behind each are declared once, in
``fc_sil/params.py`` (``FEATURES``: name -> enable parameter; ``ABLATION_FEATURES``:
the paper's ablation list). The CLI's ``--feature-off`` choices, this module's
variants, ``FlightCore.set_feature`` and docs/params.md all take those names; the
overrides that switch named features off (``feature_params``) live there too, as the
flight assembly (tools/loop/flight.py) applies them to every flight.

Ablation (paper 2.1): each feature switched off alone, and all off, on the same
seeds as the full controller. Every variant sets every paper switch explicitly, so
``full`` is the paper's controller (all on) whatever the defaults say: the study
still shows what each feature pays after the ablation itself has switched some of
them off by default. ``defaults`` flies the declared defaults, so the same table
shows where they stand against the paper's controller.

The harmonic notch (issue 27) is ablated when the campaign flies one (INS_HNTCH_ENABLE 1
among its parameters, e.g. `--params` from `silbridge tune notch`): `full` keeps it as set,
and three variants change only the notch: off; off with the gyro low-pass lowered until it
alone attenuates the notch's centre as deeply as the notch did (a plain low-pass in its
place); and the same notch driven by the in-flight FFT (MODE 4) instead of its own mode.
"""

from silbridge.fc_sil.params import ABLATION_FEATURES, BY_NAME, FEATURES, feature_params

# The in-flight FFT as a tuner sets it for a notch (tests/fc_sil/test_fft_flight.py): a
# 256-point window (3.9 Hz bins at 1 kHz; the default 32 has 31 Hz bins and sits ~6 % off a
# rotor line) and FFT_MINHZ 50, which keeps a hover line near 80 Hz off the search's edge.
NOTCH_FFT = {"INS_HNTCH_MODE": 4, "FFT_ENABLE": 1, "FFT_WINDOW_SIZE": 256, "FFT_MINHZ": 50}


def variant_switches(features_off) -> dict:
    """Every paper switch set explicitly: the named features off, the others on."""
    off = feature_params(features_off)
    return {FEATURES[f]: off.get(FEATURES[f], 1) for f in ABLATION_FEATURES}


def variants(params=()) -> list[tuple[str, dict]]:
    """(label, FC parameters) for the full paper controller, each ablated feature off
    alone, all off, and the declared defaults (no switch set). params: the campaign's
    own overrides ({name: value} or pairs); a variant's switches win over them."""
    base = dict(params)
    out = [("full", {**base, **variant_switches(())})]
    out += [(f"no_{f}", {**base, **variant_switches((f,))}) for f in ABLATION_FEATURES]
    out.append(("all_off", {**base, **variant_switches(ABLATION_FEATURES)}))
    out.append(("defaults", base))
    if base.get("INS_HNTCH_ENABLE", BY_NAME["INS_HNTCH_ENABLE"].default) == 1:
        full = out[0][1]
        out += [(label, {**full, **change}) for label, change in notch_changes(full)]
    return out


def lowpass_for(freq_hz: float, att_db: float) -> int:
    """The gyro low-pass cutoff (INS_GYRO_FILTER, whole Hz, at least 1) at which that
    2nd-order Butterworth alone attenuates freq_hz by att_db: |H(f)|^2 = 1 / (1 + (f/fc)^4),
    so fc = f / (10^(att/10) - 1)^(1/4); the notch's 40 dB at 81 Hz gives 8 Hz."""
    return max(1, int(round(freq_hz / (10.0 ** (att_db / 10.0) - 1.0) ** 0.25)))


def notch_changes(params: dict) -> list[tuple[str, dict]]:
    """(label, the parameters that differ from params) of the notch's variants."""
    def value(name):
        return float(params.get(name, BY_NAME[name].default))
    lowpass = lowpass_for(value("INS_HNTCH_FREQ"), value("INS_HNTCH_ATT"))
    return [("notch_off", {"INS_HNTCH_ENABLE": 0}),
            ("notch_lowpass", {"INS_HNTCH_ENABLE": 0, "INS_GYRO_FILTER": lowpass}),
            ("notch_fft", dict(NOTCH_FFT))]
