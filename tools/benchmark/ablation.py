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
"""

from silbridge.fc_sil.params import ABLATION_FEATURES, FEATURES, feature_params


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
    return out
