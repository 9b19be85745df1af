"""One lithium-polymer cell: open-circuit voltage and internal resistance.

Open-circuit voltage against state of charge (SoC, 0..1) is the fit of M. Chen and G. A.
Rincon-Mora, "Accurate electrical battery model capable of predicting runtime and I-V
performance", IEEE Trans. Energy Conversion 21(2), 2006, eq. (8), measured on a
lithium-ion polymer cell (TCL PL-383562):
    V_oc = -1.031 exp(-35 SoC) + 3.685 + 0.2156 SoC - 0.1178 SoC^2 + 0.3201 SoC^3   [V]
It is not linear: flat in the middle, the knee below ~15 % that every pilot knows, 4.10 V
full (that cell's charge voltage; hobby packs charged to 4.20 V sit ~0.1 V higher at the
top, the shape below 90 % is the same) and 2.65 V empty.

Internal resistance: the scenario gives it at full charge and 25 degC. Its rise at low
charge follows the same paper's series-resistance fit, R_s = 0.1562 exp(-24.37 SoC) +
0.07446 ohm, taken as a ratio to its full-charge value (x1.0 above ~30 %, x1.6 at 5 %,
x3.1 empty). Its rise in the cold is Arrhenius, R(T) = R(T_ref) exp(Ea / R_gas (1/T -
1/T_ref)), the law PVsyst's battery model applies to Li-ion after Lundgren (2016), "usual
values [of Ea] are 30 to 40 kJ/mol" (pvsyst.com help, Internal resistance): 35 kJ/mol by
default: 3.6 times the 25 degC resistance at 0 degC, half of it at 40 degC.
"""

from __future__ import annotations

import math

T_REF_K = 298.15        # the temperature the scenario's resistance is given at (25 degC)
R_GAS = 8.314           # J/(mol K)
_C_K = 273.15


def ocv_v(soc: float) -> float:
    """Open-circuit voltage of one cell [V] at state of charge soc (clamped to 0..1)."""
    s = min(1.0, max(0.0, soc))
    return -1.031 * math.exp(-35.0 * s) + 3.685 + s * (0.2156 + s * (-0.1178 + s * 0.3201))


_R_FULL = 0.1562 * math.exp(-24.37) + 0.07446


def r_soc_factor(soc: float) -> float:
    """Internal resistance at soc over the resistance at full charge (Chen and Rincon-Mora)."""
    s = min(1.0, max(0.0, soc))
    return (0.1562 * math.exp(-24.37 * s) + 0.07446) / _R_FULL


def r_temp_factor(temp_c: float, activation_j_mol: float) -> float:
    """Internal resistance at temp_c over the resistance at 25 degC (Arrhenius)."""
    t_k = max(200.0, temp_c + _C_K)      # the law has no meaning near 0 K; packs never go there
    return math.exp(activation_j_mol / R_GAS * (1.0 / t_k - 1.0 / T_REF_K))
