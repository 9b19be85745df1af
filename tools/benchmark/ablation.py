"""The ablation study's variants, read from the one feature declaration.

The stabilisation features and the FC switch behind each are declared once, in
``fc_sil/params.py`` (``FEATURES``: name -> enable parameter; ``ABLATION_FEATURES``:
the paper's ablation list). The CLI's ``--feature-off`` choices, this module's
variants, ``FlightCore.set_feature`` and docs/params.md all take those names.

Ablation (paper 2.1): each feature switched off alone, and all off, on the same
seeds as the full controller.
"""

from silbridge.fc_sil.params import ABLATION_FEATURES, FEATURES


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
    """(label, features off) for the full controller, each ablated feature alone, all off."""
    out = [("full", ())]
    out += [(f"no_{f}", (f,)) for f in ABLATION_FEATURES]
    out.append(("all_off", tuple(ABLATION_FEATURES)))
    return out
