"""Load, validate and resolve a scenario file (TOML) into a `Scenario`.

``load_scenario("S1")`` reads the built-in bridge/scenarios/S1.toml;
``load_scenario(path, seed=7, overrides={"imu.rate_hz": 8000})`` reads any
file, replaces its seed, and sets dotted keys before validation. Validation
refuses unknown keys, wrong types, out-of-range values (a negative rate) and
missing required fields, with a `ScenarioError` naming the key and the file.

Randomness: every value written as ``{uniform = [lo, hi]}`` or
``{choice = [...]}`` is drawn here, once, from a generator keyed by the seed
and the key's path (`draw_rng`). Keying by path means that adding a
disturbance or changing a block size never shifts another draw; the drawn
values are kept in ``Scenario.draws`` and in ``to_dict()`` for the run log.
The schema (keys, units, defaults and their sources) is scenario_schema.py.
"""

from __future__ import annotations

import copy
import math
import re
import sys
import tomllib
import zlib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from silbridge.bridge import scenario_schema as S
from silbridge.bridge import imu_raw, vibration_checks
from silbridge.bridge.faults import failure_checks
from silbridge.bridge.errors import ScenarioError
from silbridge.magfield import field_at
from silbridge.shm import fault_catalog
from silbridge.shm.records import NS_PER_S

SCENARIO_DIR = Path(__file__).resolve().parent / "scenarios"
_AXES = {"x": (1.0, 0.0, 0.0), "y": (0.0, 1.0, 0.0), "z": (0.0, 0.0, 1.0)}


def builtin_names() -> list[str]:
    return sorted(p.stem for p in SCENARIO_DIR.glob("*.toml"))


def draw_rng(seed: int, key: str) -> np.random.Generator:
    """The generator for one named stream of a run: seed plus a CRC of the name."""
    return np.random.default_rng(np.random.SeedSequence(int(seed), spawn_key=(zlib.crc32(key.encode()),)))


# The sections the Scenario dataclass names as fields; any other one goes to Scenario.extra.
_FIXED_SECTIONS = ("physics", "home", "windows", "imu", "baro", "mag", "gnss")


class Section:
    """Resolved values of one table, as attributes (read-only by convention)."""

    def __init__(self, values: dict):
        self.__dict__.update(values)

    def to_dict(self) -> dict:
        return {k: (list(v) if isinstance(v, tuple) else v) for k, v in self.__dict__.items()}

    def __repr__(self):
        return f"Section({self.__dict__!r})"


@dataclass
class Scenario:
    """A validated scenario with every random value drawn. Times in s, angles as written."""

    name: str
    description: str
    seed: int
    duration_s: float
    takeoff_alt_m: float
    setpoint_rate_hz: float
    physics: Section
    home: Section
    windows: Section
    imu: Section
    baro: Section
    mag: Section
    gnss: Section
    disturbances: list[Section]
    setpoints: list[Section]
    source: str
    draws: dict = field(default_factory=dict)
    fc_params: list[Section] = field(default_factory=list)   # [[fc_param]]: FC parameter sets
    failures: list[Section] = field(default_factory=list)    # [[failure]]: faults on purpose
    # Sections declared in scenario_schema.SECTIONS beyond the fields above (issue 26's
    # [vehicle], [vibration], ...): read as attributes, sc.vehicle, like the others.
    extra: dict = field(default_factory=dict)

    def __getattr__(self, name):
        extra = self.__dict__.get("extra")
        if extra is not None and name in extra:
            return extra[name]
        raise AttributeError(f"Scenario has no section or field {name!r}")

    @property
    def imu_hz(self) -> int:
        return self.imu.rate_hz

    @property
    def physics_hz(self) -> int:
        return self.physics.rate_hz

    @property
    def baro_hz(self) -> float:
        return self.baro.rate_hz

    @property
    def mag_hz(self) -> float:
        return self.mag.rate_hz

    @property
    def gnss_hz(self) -> float:
        return self.gnss.rate_hz

    def to_dict(self) -> dict:
        """Everything that defines the run, JSON-serialisable, for logs."""
        return {
            "name": self.name, "description": self.description, "seed": self.seed,
            "duration_s": self.duration_s, "takeoff_alt_m": self.takeoff_alt_m,
            "setpoint_rate_hz": self.setpoint_rate_hz,
            "physics": self.physics.to_dict(), "home": self.home.to_dict(),
            "windows": self.windows.to_dict(), "imu": self.imu.to_dict(),
            "baro": self.baro.to_dict(), "mag": self.mag.to_dict(), "gnss": self.gnss.to_dict(),
            "disturbances": [d.to_dict() for d in self.disturbances],
            "setpoints": [s.to_dict() for s in self.setpoints],
            "fc_params": [p.to_dict() for p in self.fc_params],
            "failures": [f.to_dict() for f in self.failures],
            "source": self.source, "draws": dict(self.draws),
            **{name: sec.to_dict() for name, sec in self.extra.items()},
        }


# --- public entry point ------------------------------------------------------------------

def load_scenario(name_or_path, seed: int | None = None, overrides: dict | None = None,
                  check_fc_param=None) -> Scenario:
    """check_fc_param(name, value): raises ValueError (with a message for the user) for a
    [[fc_param]] the FC would refuse; the caller that knows the FC gives it."""
    path = _find(name_or_path)
    data = path.read_bytes()
    try:
        raw = tomllib.loads(data.decode("utf-8"))
    except UnicodeDecodeError as exc:    # TOML is UTF-8 by definition
        line = data[:exc.start].count(b"\n") + 1
        raise ScenarioError(f"{path.name}: byte 0x{data[exc.start]:02x} at line {line} is not "
                            f"UTF-8 text; save the file as UTF-8") from None
    except tomllib.TOMLDecodeError as exc:
        # tomllib says "(at line L, column C)", or "(at end of document)": that is the last line
        why = str(exc).replace("(at end of document)",
                               f"(at line {max(1, len(data.splitlines()))}, end of file)")
        raise ScenarioError(f"{path.name}: not valid TOML ({why}); fix the syntax") from None
    except ValueError:   # tomllib lets Python's int() limit through: a number of 4301+ digits
        long_number = re.search(r"\d{%d,}" % (sys.get_int_max_str_digits() + 1), data.decode())
        line = data.decode()[:long_number.start()].count("\n") + 1 if long_number else 1
        raise ScenarioError(f"{path.name}: line {line}: a number with too many digits; "
                            f"write a smaller one") from None
    return scenario_from_dict(raw, source=str(path), seed=seed, overrides=overrides,
                              check_fc_param=check_fc_param)


def scenario_from_dict(raw: dict, source: str = "<dict>", seed: int | None = None,
                       overrides: dict | None = None, check_fc_param=None) -> Scenario:
    raw = copy.deepcopy(raw)
    where = Path(source).name
    for key, value in (overrides or {}).items():
        _set_dotted(raw, key, value, where)
    if seed is not None:
        raw["seed"] = seed
    return _Resolver(raw, where, source, check_fc_param).scenario()


def _find(name_or_path) -> Path:
    p = Path(name_or_path)
    if p.suffix != ".toml" and (SCENARIO_DIR / f"{p.name}.toml").is_file() and not p.is_file():
        return SCENARIO_DIR / f"{p.name}.toml"
    if p.is_file():
        return p
    raise ScenarioError(
        f"no scenario {str(name_or_path)!r}: give a file path or one of the built-ins "
        f"{', '.join(builtin_names())}")


def _set_dotted(raw: dict, dotted: str, value, where: str) -> None:
    """Set 'imu.rate_hz' or 'disturbance[0].amplitude_g' in the raw table."""
    node = raw
    parts = dotted.split(".")
    for i, part in enumerate(parts):
        last = i == len(parts) - 1
        name, index = part, None
        if part.endswith("]") and "[" in part:
            name, idx = part[:-1].split("[", 1)
            index = int(idx)
        if index is None:
            if last:
                node[name] = value
                return
            node = node.setdefault(name, {})
        else:
            seq = node.get(name)
            if not isinstance(seq, list) or index >= len(seq):
                raise ScenarioError(f"{where}: override {dotted!r}: there is no {name}[{index}]")
            if last:
                seq[index] = value
                return
            node = seq[index]
        if not isinstance(node, dict):
            raise ScenarioError(f"{where}: override {dotted!r}: {part} is not a table")


# --- validation and draws ----------------------------------------------------------------

class _Resolver:
    def __init__(self, raw: dict, where: str, source: str, check_fc_param=None):
        self.raw = raw
        self.check_fc_param = check_fc_param
        self.where = where
        self.source = source
        self.seed = None
        self.draws: dict = {}

    def fail(self, key: str, problem: str):
        raise ScenarioError(f"{self.where}: {key}: {problem}")

    def scenario(self) -> Scenario:
        raw = self.raw
        allowed = set(S.TOP) | set(S.SECTIONS) | {"disturbance", "setpoint", "fc_param", "failure"}
        for key in raw:
            if key not in allowed:
                self.fail(key, f"unknown key; valid top-level keys are {', '.join(sorted(allowed))}")
        seed_val = raw.get("seed", S.REQUIRED)
        if seed_val is S.REQUIRED:
            self.fail("seed", "missing required field; add e.g. 'seed = 1'")
        self.seed = self.value("seed", seed_val, S.TOP["seed"])
        top = self.table("", raw, S.TOP, skip={"disturbance", "setpoint", "fc_param", "failure",
                                                 *S.SECTIONS})
        self.duration_s = top["duration_s"]
        sections = {}
        for sec, schema in S.SECTIONS.items():
            tbl = raw.get(sec, {})
            if not isinstance(tbl, dict):
                self.fail(sec, "must be a table, e.g. [" + sec + "]")
            sections[sec] = Section(self.table(sec + ".", tbl, schema))
        mag, home = sections["mag"], sections["home"]
        if mag.field_ned_gauss is None:      # undeclared: the Earth's field at this home
            mag.field_ned_gauss = field_at(home.lat_deg, home.lon_deg).ned_gauss
        dists = [Section(self.entry(f"disturbance[{i}]", e, S.DISTURBANCE_COMMON, S.DISTURBANCE_TYPES))
                 for i, e in enumerate(self.array("disturbance"))]
        sps = [Section(self.entry(f"setpoint[{i}]", e, S.SETPOINT_COMMON, S.SETPOINT_TYPES))
               for i, e in enumerate(self.array("setpoint"))]
        sc = Scenario(name=top["name"], description=top["description"], seed=top["seed"],
                      duration_s=top["duration_s"], takeoff_alt_m=top["takeoff_alt_m"],
                      setpoint_rate_hz=top["setpoint_rate_hz"], physics=sections["physics"],
                      home=sections["home"], windows=sections["windows"], imu=sections["imu"],
                      baro=sections["baro"], mag=sections["mag"], gnss=sections["gnss"],
                      disturbances=dists, setpoints=sps, source=self.source, draws=self.draws,
                      fc_params=[Section(self.table(f"fc_param[{i}].", e, S.FC_PARAM))
                                 for i, e in enumerate(self.array("fc_param"))],
                      failures=[Section(self.failure_entry(f"failure[{i}]", e))
                                for i, e in enumerate(self.array("failure"))],
                      extra={k: v for k, v in sections.items() if k not in _FIXED_SECTIONS})
        self.check_consistency(sc)
        return sc

    def array(self, key: str) -> list:
        val = self.raw.get(key, [])
        if not isinstance(val, list) or not all(isinstance(e, dict) for e in val):
            self.fail(key, f"must be an array of tables written [[{key}]]")
        return val

    def table(self, prefix: str, tbl: dict, schema: dict, skip=()) -> dict:
        for key in tbl:
            if prefix + key in S.MOVED:
                self.fail(prefix + key, f"moved to {S.MOVED[prefix + key]}: write it under "
                                        f"[{S.MOVED[prefix + key].split('.')[0]}]")
            if key not in schema and key not in skip:
                self.fail(prefix + key, f"unknown key; valid keys{' in [' + prefix[:-1] + ']' if prefix else ''} "
                                        f"are {', '.join(schema)}")
        out = {}
        for key, spec in schema.items():
            if key in tbl:
                out[key] = self.value(prefix + key, tbl[key], spec)
            elif spec.default is S.REQUIRED:
                self.fail(prefix + key, f"missing required field ({spec.kind}"
                                        f"{', ' + spec.unit if spec.unit else ''}); add it")
            else:
                out[key] = spec.default
        return out

    def entry(self, prefix: str, tbl: dict, common: dict, types: dict) -> dict:
        kind = tbl.get("type")
        if kind is None:
            self.fail(prefix + ".type", f"missing required field; one of {', '.join(types)}")
        if not isinstance(kind, str) or kind not in types:
            self.fail(prefix + ".type", f"unknown type {kind!r}; one of {', '.join(types)}")
        schema = {**common, **types[kind]}
        if kind == "tilt":
            return self.tilt_entry(prefix, tbl, schema)
        return self.table(prefix + ".", tbl, schema)

    def failure_entry(self, prefix: str, tbl: dict) -> dict:
        """A [[failure]]: the unit, then its type, then the common keys and the type's
        parameters (scenario_schema.FAILURE_TYPES, built from shm/fault_catalog.py)."""
        units = S.FAILURE_TYPES
        unit = tbl.get("unit")
        if unit is None:
            self.fail(prefix + ".unit", f"missing required field; one of {', '.join(units)}")
        if not isinstance(unit, str) or unit not in units:
            self.fail(prefix + ".unit", f"unknown unit {unit!r}; one of {', '.join(units)}")
        types = units[unit]
        kind = tbl.get("type")
        if kind is None:
            self.fail(prefix + ".type", f"missing required field; {unit} types: {', '.join(types)}")
        if not isinstance(kind, str) or kind not in types:
            self.fail(prefix + ".type", f"unknown {unit} type {kind!r}; one of {', '.join(types)}")
        schema = {**S.FAILURE_COMMON, **types[kind]}
        for key in tbl:
            if key not in schema:
                params = ", ".join(types[kind]) or "none"
                common = ", ".join(S.FAILURE_COMMON)
                self.fail(f"{prefix}.{key}", f"unknown key for {unit}.{kind}; common keys are "
                                             f"{common}, its parameters {params}")
        out = self.table(prefix + ".", tbl, schema)
        allowed = fault_catalog.unit_named(unit).instances
        if out["instance"] not in allowed:
            self.fail(prefix + ".instance", f"{unit} has no instance {out['instance']}; one of "
                                            f"{', '.join(map(str, allowed))} "
                                            f"({fault_catalog.unit_named(unit).instance_text})")
        return out

    def tilt_entry(self, prefix: str, tbl: dict, schema: dict) -> dict:
        """Tilt commands repeat; each repetition draws its own amplitude and hold."""
        plain = {k: v for k, v in tbl.items() if k not in ("amplitude_deg", "hold_s", "ramp_s")}
        plain_schema = {k: v for k, v in schema.items() if k not in ("amplitude_deg", "hold_s", "ramp_s")}
        for key in tbl:
            if key not in schema:
                self.fail(f"{prefix}.{key}", f"unknown key; valid keys are {', '.join(schema)}")
        out = self.table(prefix + ".", plain, plain_schema)
        reps = out["repeat"]
        if reps > 1 and out["period_s"] <= 0:
            self.fail(prefix + ".period_s", "must be > 0 when repeat > 1")
        # Checked before the per-repetition draws below, which would otherwise be made (and
        # held) for every one of a mistyped count of 10**12.
        last_start_s = out["start_s"] + (reps - 1) * out["period_s"]
        if reps > 1 and not last_start_s < self.duration_s:
            self.fail(prefix + ".repeat", f"repetition {reps} would start at {last_start_s:g} s, "
                                          f"not before the end of the run "
                                          f"({self.duration_s:g} s); lower repeat or period_s")
        for key in ("amplitude_deg", "hold_s", "ramp_s"):
            spec = schema[key]
            if key not in tbl and spec.default is S.REQUIRED:
                self.fail(f"{prefix}.{key}", "missing required field; add it")
            raw = tbl.get(key, spec.default)
            out[key] = [self.value(f"{prefix}.{key}" + (f"#{r}" if r else ""), raw, spec)
                        for r in range(reps)]
        return out

    def value(self, key: str, raw, spec: S.Field):
        if isinstance(raw, dict):
            if not spec.drawable:
                self.fail(key, "cannot be drawn at random here; give a fixed value")
            raw = self.draw(key, raw)
        kind = spec.kind
        if kind in ("vec3", "vec4"):
            n = int(kind[-1])
            if not isinstance(raw, list) or len(raw) != n:
                self.fail(key, f"must be a list of {n} numbers")
            vals = []
            for i, item in enumerate(raw):
                if isinstance(item, dict):
                    if not spec.drawable:
                        self.fail(f"{key}[{i}]", "cannot be drawn at random here")
                    item = self.draw(f"{key}[{i}]", item)
                vals.append(self.number(f"{key}[{i}]", item, "float", spec))
            return tuple(vals)
        if kind == "axis":
            if isinstance(raw, str):
                if raw not in _AXES:
                    self.fail(key, f"unknown axis {raw!r}; use x, y, z or [ax, ay, az]")
                return _AXES[raw]
            if not isinstance(raw, list) or len(raw) != 3:
                self.fail(key, "must be x, y, z or a list of 3 numbers")
            vec = [self.number(f"{key}[{i}]", v, "float", S.Field("float")) for i, v in enumerate(raw)]
            norm = math.sqrt(sum(c * c for c in vec))
            if norm == 0:
                self.fail(key, "direction must not be zero")
            return tuple(c / norm for c in vec)
        if kind == "str":
            if not isinstance(raw, str):
                self.fail(key, f"must be a string, got {raw!r}")
            if spec.choices and raw not in spec.choices:
                self.fail(key, f"{raw!r} is not one of {', '.join(spec.choices)}")
            return raw
        if kind == "bool":
            if not isinstance(raw, bool):
                self.fail(key, f"must be true or false, got {raw!r}")
            return raw
        if raw is None and spec.default is None:
            return None
        return self.number(key, raw, kind, spec)

    def number(self, key: str, raw, kind: str, spec: S.Field):
        if isinstance(raw, bool) or not isinstance(raw, (int, float)):
            self.fail(key, f"must be a number, got {raw!r}")
        if kind == "int":
            if isinstance(raw, float) and not raw.is_integer():
                self.fail(key, f"must be an integer, got {raw!r}")
            raw = int(raw)
        else:
            raw = float(raw)
            if not math.isfinite(raw):
                self.fail(key, f"must be finite, got {raw!r}")
        if spec.above is not None and not raw > spec.above:
            self.fail(key, f"must be > {spec.above:g}, got {raw:g}")
        if spec.min is not None and raw < spec.min:
            self.fail(key, f"must be >= {spec.min:g}, got {raw:g}")
        if spec.max is not None and raw > spec.max:
            self.fail(key, f"must be <= {spec.max:g}, got {raw:g}")
        return raw

    def draw(self, key: str, spec: dict):
        if len(spec) != 1 or next(iter(spec)) not in ("uniform", "choice"):
            self.fail(key, "a random value is {uniform = [lo, hi]} or {choice = [a, b, ...]}")
        how, args = next(iter(spec.items()))
        if not isinstance(args, list) or not args or not all(
                isinstance(a, (int, float)) and not isinstance(a, bool) for a in args):
            self.fail(key, f"{how} needs a list of numbers")
        rng = draw_rng(self.seed, key)
        if how == "uniform":
            if len(args) != 2 or not args[0] <= args[1]:
                self.fail(key, "uniform needs [lo, hi] with lo <= hi")
            val = float(rng.uniform(args[0], args[1]))
        else:
            val = args[int(rng.integers(len(args)))]
        self.draws[key] = val
        return val

    def check_consistency(self, sc: Scenario) -> None:
        if NS_PER_S % sc.physics.rate_hz:
            self.fail("physics.rate_hz", f"{sc.physics.rate_hz} Hz gives a step that is not a whole "
                                         "number of nanoseconds; use e.g. 500, 1000, 2000, 4000")
        if sc.windows.transient_end_s < sc.windows.warmup_s:
            self.fail("windows.transient_end_s", "must not be before windows.warmup_s")
        for i, d in enumerate(sc.disturbances):
            if d.start_s >= sc.duration_s:
                self.fail(f"disturbance[{i}].start_s", f"{d.start_s:g} s is not before the end "
                                                        f"of the run ({sc.duration_s:g} s)")
            if d.stop_s is not None and d.stop_s <= d.start_s:
                self.fail(f"disturbance[{i}].stop_s", "must be after start_s")
            if d.type == "motor_bias" and any(s < 0 for s in d.thrust_scale):
                self.fail(f"disturbance[{i}].thrust_scale", "scales must be >= 0")
        for i, sp in enumerate(sc.setpoints):
            if sp.start_s >= sc.duration_s:
                self.fail(f"setpoint[{i}].start_s", f"{sp.start_s:g} s is not before the end "
                                                     f"of the run ({sc.duration_s:g} s)")
        vibration_checks.check(sc, self.fail)   # [vibration], [mount], [imu_chip]
        failure_checks.check(sc, self.fail)     # [[failure]] against the rest of the run
        imu_raw.check(sc, self.fail)            # imu_chip.log_raw
        for i, fp in enumerate(sc.fc_params):
            if fp.at_s >= sc.duration_s:
                self.fail(f"fc_param[{i}].at_s", f"{fp.at_s:g} s is not before the end "
                                                  f"of the run ({sc.duration_s:g} s)")
            if self.check_fc_param is not None:
                try:
                    self.check_fc_param(fp.name, fp.value)
                except ValueError as exc:
                    self.fail(f"fc_param[{i}]", str(exc))
