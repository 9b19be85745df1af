"""Every flight-controller parameter, read from the one declaration file.

fc_sil/core/fc_params.def is the single declaration (see its header for the
format and why it is an X-macro): the C compiler builds the core's struct and
table from it, and this module parses the same lines for Python: names,
permanent indices, types, defaults, ranges, units and one-line texts, for the
C-core parameters (FC_PARAM) and for the host-side ones the Python runtime
keeps (FC_HOST: navigation, identity, failsafes). MAVLink PARAM_*, the `.parm`
files and docs/params.md all read `PARAMS` from here.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path

from .errors import ParamError

DEF_PATH = Path(__file__).resolve().parent / "core" / "fc_params.def"
NAME_MAX = 16

# MAVLink MAV_PARAM_TYPE of each declared type (integers travel C-cast as floats).
MAV_PARAM_TYPE = {"INT8": 2, "INT16": 4, "INT32": 6, "FLOAT": 9}
_INT_RANGE = {"INT8": (-128, 127), "INT16": (-32768, 32767), "INT32": (-2**31, 2**31 - 1)}

# Feature switches of the ablation study: short name -> enable parameter.
FEATURES = {
    "d_filter": "SB_DFILT_EN",        # D-term PT2x2 filter (paper 3.6)
    "d_clamp": "SB_DCLAMP_EN",        # D-term +-12 us clamp (paper 3.6)
    "trim": "SB_TRIM_EN",             # hover-trim learning (paper 3.7)
    "trim_ramp": "SB_TRIM_RAMP_EN",   # hover-trim 0.8 s ramp-in (paper 3.7)
    "trust_ema": "SB_TRUST_EMA_EN",   # accelerometer-trust EMA (Listing 3)
    "blend": "SB_BLEND_EN",           # continuous EST/GT blending (paper 3.7, 2.4)
    "yaw_antiwindup": "SB_YAW_AW_EN", # yaw rate-PI anti-windup (paper 3.6)
    "slew": "SB_SLEW_EN",             # per-motor slew limit (paper 3.8)
    "gyro_bias": "SB_BIAS_EN",        # online gyro-bias estimation (Listing 3)
    "shaping": "SB_SHAPE_EN",         # attitude input shaping + rate feed-forward (ArduCopter)
}
# The paper's ablation list (paper 2.1): each switched off alone, then all.
ABLATION_FEATURES = ("d_filter", "d_clamp", "trim_ramp", "trust_ema", "blend",
                     "yaw_antiwindup", "slew")


@dataclass(frozen=True)
class ParamDef:
    """One declared parameter."""

    index: int          # permanent slot
    name: str           # at most 16 characters
    type: str           # FLOAT, INT8, INT16, INT32
    default: float
    min: float
    max: float
    unit: str
    text: str
    host: bool          # True: lives in the Python runtime, not in the C core
    field: str | None   # C struct field (C-core parameters only)

    @property
    def mav_type(self) -> int:
        return MAV_PARAM_TYPE[self.type]

    @property
    def is_int(self) -> bool:
        return self.type != "FLOAT"

    def validate(self, value) -> float:
        """The value as stored, or ParamError (NaN/inf, out of range, not integral)."""
        try:
            v = float(value)
        except (TypeError, ValueError):
            raise ParamError(f"{self.name}: {value!r} is not a number; "
                             f"give a value in [{_fmt(self.min)}, {_fmt(self.max)}]") from None
        if not math.isfinite(v):
            raise ParamError(f"{self.name}: {value!r} is not finite; "
                             f"give a value in [{_fmt(self.min)}, {_fmt(self.max)}]")
        if v < self.min or v > self.max:
            raise ParamError(f"{self.name}: {_fmt(v)} is outside [{_fmt(self.min)}, "
                             f"{_fmt(self.max)}] {self.unit}".rstrip() + "; value kept")
        if self.is_int and v != math.trunc(v):
            raise ParamError(f"{self.name} is an integer ({self.type}); {_fmt(v)} is not")
        if self.type == "FLOAT":
            # What the C core stores: float32.
            v = float(_to_f32(v))
        return v


def _fmt(v: float) -> str:
    return f"{v:g}"


def _to_f32(v: float) -> float:
    import struct
    return struct.unpack("<f", struct.pack("<f", v))[0]


_LINE = re.compile(r"^\s*FC_(PARAM|HOST)\s*\((.*)\)\s*$")
_ARG = re.compile(r'\s*("(?:[^"\\]|\\.)*"|[^,]+?)\s*(?:,|$)')


def _split_args(text: str) -> list[str]:
    args, pos = [], 0
    while pos < len(text):
        m = _ARG.match(text, pos)
        if not m or m.end() == pos:
            raise ValueError(f"cannot parse parameter arguments: {text!r}")
        args.append(m.group(1))
        pos = m.end()
    return args


def _unquote(s: str) -> str:
    if len(s) >= 2 and s[0] == s[-1] == '"':
        return s[1:-1].replace('\\"', '"').replace("\\\\", "\\")
    raise ValueError(f"expected a quoted string, got {s!r}")


def load_definitions(path: Path | str = DEF_PATH) -> tuple[ParamDef, ...]:
    """Parse fc_params.def; checks names, indices and defaults as it goes."""
    defs: list[ParamDef] = []
    for lineno, line in enumerate(Path(path).read_text().splitlines(), 1):
        m = _LINE.match(line)
        if not m:
            continue
        kind, args = m.group(1), _split_args(m.group(2))
        try:
            if kind == "PARAM":
                idx, name, typ, field, d, lo, hi, unit, text = args
            else:
                idx, name, typ, d, lo, hi, unit, text = args
                field = None
        except ValueError:
            raise ValueError(f"{path}:{lineno}: wrong number of fields") from None
        p = ParamDef(index=int(idx), name=name, type=typ, default=float(d), min=float(lo),
                     max=float(hi), unit=_unquote(unit), text=_unquote(text),
                     host=(kind == "HOST"), field=field)
        if len(p.name) > NAME_MAX:
            raise ValueError(f"{path}:{lineno}: {p.name} is longer than {NAME_MAX} characters")
        if p.type not in MAV_PARAM_TYPE:
            raise ValueError(f"{path}:{lineno}: unknown type {p.type}")
        if not (p.min <= p.default <= p.max):
            raise ValueError(f"{path}:{lineno}: default of {p.name} outside its range")
        defs.append(p)
    names = [p.name for p in defs]
    indices = [p.index for p in defs]
    if len(set(names)) != len(names) or len(set(indices)) != len(indices):
        raise ValueError(f"{path}: duplicate parameter name or index")
    return tuple(sorted(defs, key=lambda p: p.index))


PARAMS: tuple[ParamDef, ...] = load_definitions()
BY_NAME: dict[str, ParamDef] = {p.name: p for p in PARAMS}
BY_INDEX: dict[int, ParamDef] = {p.index: p for p in PARAMS}


def lookup(name: str) -> ParamDef:
    """The definition of a parameter by name, or ParamError naming close matches."""
    try:
        return BY_NAME[name.upper()]
    except KeyError:
        import difflib
        close = difflib.get_close_matches(name.upper(), BY_NAME, n=3)
        hint = f"; did you mean {', '.join(close)}?" if close else \
            "; `silbridge params` lists them"
        raise ParamError(f"unknown parameter {name!r}{hint}") from None


def feature_param(feature: str) -> str:
    """Enable-parameter name of an ablation feature (also accepts the parameter name)."""
    if feature in FEATURES:
        return FEATURES[feature]
    if feature.upper() in FEATURES.values():
        return feature.upper()
    raise ParamError(f"unknown feature {feature!r}; known: {', '.join(FEATURES)}")


def feature_params(features_off) -> dict[str, int]:
    """Parameter overrides that switch the named features off (`--feature-off`, the ablation's
    variants): short names only, as the CLI offers them."""
    out = {}
    for f in features_off:
        if f not in FEATURES:
            raise ParamError(f"unknown feature {f!r}; choose from {', '.join(FEATURES)}")
        out[FEATURES[f]] = 0
    return out


def defaults() -> dict[str, float]:
    """name -> default for every declared parameter, in index order."""
    return {p.name: p.default for p in PARAMS}
