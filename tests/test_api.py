"""The Python API (silbridge/__init__.py): what `import silbridge` gives a script.

Each function must answer what the command line answers: `fly` the same flight and the
metrics `silbridge analyze` computes from its log, `bench` the Table 1 of `silbridge bench
--json`, `load_scenario` the flight's scenario with overrides. Importing the package must
stay free (every subprocess of a run imports it), and nothing below it may import it back.
"""

from __future__ import annotations

import ast
import dataclasses
import json
import math
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

import silbridge

ROOT = Path(__file__).resolve().parents[1]
PARTS = ("bridge", "fc_sil", "shm", "mavlink", "tools", "jsbsim_models")


def test_import_is_free_of_the_runtime():
    """`import silbridge` loads no subpackage and no numpy: the names come on first use."""
    code = ("import sys, json, silbridge; "
            "print(json.dumps(sorted(m for m in sys.modules "
            "if m.split('.')[0] in ('silbridge', 'numpy', 'jsbsim', 'pymavlink'))))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, cwd=ROOT.parent)
    assert json.loads(out.stdout) == ["silbridge"]


def test_version_is_the_distributions():
    from importlib.metadata import version
    declared = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["version"]
    assert silbridge.__version__ == version("silbridge") == declared


def test_the_public_names_resolve_and_unknown_ones_do_not():
    for name in silbridge.__all__:
        assert getattr(silbridge, name) is not None, name
        assert name in dir(silbridge)
    with pytest.raises(AttributeError):
        silbridge.no_such_thing      # noqa: B018
    from silbridge import tools      # a subpackage is still a subpackage
    assert tools.__name__ == "silbridge.tools"


def test_fly_returns_the_summary_and_the_metrics_of_its_log(tmp_path):
    log = tmp_path / "run.mcap"
    flight = silbridge.fly(scenario="S1", duration_s=12.0, processes=1, log_path=str(log))
    assert isinstance(flight, silbridge.Flight)
    assert flight.sim_s == pytest.approx(12.0) and flight.scenario == "S1"
    assert flight.crashed is False and flight.log_path == str(log) and log.is_file()
    assert flight.summary["trace_hash"] == flight.trace_hash
    # The metrics are the log's, as `silbridge analyze` computes them.
    from silbridge.tools.benchmark.metrics import compute_metrics
    again = compute_metrics(silbridge.read_log(log))
    assert flight.metrics["att_rms_deg"] == again["att_rms_deg"]
    assert flight.metrics["pwm_pp_us"] == again["pwm_pp_us"]
    assert math.isfinite(flight.metrics["att_rms_deg"]) and flight.metrics["window_note"]


def test_fly_without_a_log_flies_the_same_and_leaves_no_log():
    opts = silbridge.FlightOptions(scenario="S1", duration_s=12.0, processes=1)
    plain = silbridge.fly(opts)
    assert plain.log_path is None and "log" not in plain.summary
    assert plain.metrics["att_rms_deg"] > 0
    again = silbridge.fly(opts, metrics=False)
    assert again.trace_hash == plain.trace_hash and again.metrics == {}
    # A field given by name overrides the options' and reaches the FC.
    tuned = silbridge.fly(opts, params={"ATC_RAT_RLL_P": 0.2})
    assert tuned.trace_hash != plain.trace_hash
    with pytest.raises(TypeError):
        silbridge.fly(opts, no_such_option=1)


def test_fly_windows_choose_the_metric_window():
    flight = silbridge.fly(scenario="S1", duration_s=12.0, processes=1,
                           windows=silbridge.Windows(analysis=(4.0, 12.0), yaw=(8.0, 12.0)))
    assert (flight.metrics["analysis_start_s"], flight.metrics["analysis_end_s"]) == (4.0, 12.0)


def test_bench_returns_the_commands_table1(tmp_path):
    out = tmp_path / "bench"
    windows = ["--warmup", "0", "1", "--transient", "1", "2", "--analysis", "2", "6",
               "--yaw-window", "4", "6"]
    result = silbridge.bench(["S1"], runs=1, duration_s=6.0, jobs=1, out_dir=out,
                             report=False, flags=windows)
    assert result.exit_code == 0 and result.out_dir == out and result.report is None
    assert result.table == json.loads((out / "table1.json").read_text())
    assert result.table["runs"] == 1 and "| S1" in result.markdown
    # Run 0 is seed 1 flown in one process: the same flight as fly() with those windows.
    flight = silbridge.fly(scenario="S1", duration_s=6.0, processes=1, seed=1,
                           windows=silbridge.Windows(warmup=(0, 1), transient=(1, 2),
                                                     analysis=(2, 6), yaw=(4, 6)))
    row = result.table["scenarios"]["S1"]
    assert row["att_rms_deg"]["mean"] == pytest.approx(flight.metrics["att_rms_deg"])
    assert row["pwm_pp_us"]["mean"] == pytest.approx(flight.metrics["pwm_pp_us"])


def test_bench_refuses_what_the_command_refuses(tmp_path):
    with pytest.raises(Exception) as info:
        silbridge.bench(["S1"], runs=0, out_dir=tmp_path)
    assert getattr(info.value, "user_facing", False)
    assert not (tmp_path / "table1.json").exists()
    with pytest.raises(Exception) as info:       # not SystemExit, as argparse would
        silbridge.bench(["S1"], out_dir=tmp_path, flags=["--no-such-flag"])
    assert getattr(info.value, "user_facing", False) and "--no-such-flag" in str(info.value)


def test_load_scenario_applies_seed_and_overrides():
    sc = silbridge.load_scenario("S1", seed=7, duration_s=60.0, **{"imu.rate_hz": 8000})
    assert isinstance(sc, silbridge.Scenario)
    assert (sc.name, sc.seed, sc.duration_s, sc.imu_hz) == ("S1", 7, 60.0, 8000)
    assert silbridge.load_scenario("S1").duration_s != 60.0     # the file is untouched
    with pytest.raises(Exception) as info:
        silbridge.load_scenario("S1", **{"imu.rate_hz": -5})
    assert getattr(info.value, "user_facing", False) and "rate_hz" in str(info.value)


def test_read_log_gives_the_channels(tmp_path):
    log = tmp_path / "run.mcap"
    silbridge.fly(scenario="S1", duration_s=3.0, processes=1, log_path=str(log), metrics=False)
    run = silbridge.read_log(log)
    assert isinstance(run, silbridge.RunLog)
    assert len(run.channels["/imu"]) > 0 and run.end is not None
    assert run.duration_s() == pytest.approx(3.0, abs=0.01)


def test_flight_fields_are_typed():
    hints = {f.name: f.type for f in dataclasses.fields(silbridge.Flight)}
    assert hints["sim_s"] == "float" and hints["log_path"] == "str | None"
    assert silbridge.fly.__doc__ and silbridge.bench.__doc__ and silbridge.load_scenario.__doc__


def test_the_command_refuses_a_platform_other_than_linux(monkeypatch, capsys):
    from silbridge.__main__ import main
    monkeypatch.setattr(sys, "platform", "darwin")
    assert main(["fly", "--duration", "1"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "Linux only" in err[0] and "darwin" in err[0]


def test_python_dash_m_silbridge_is_the_command():
    out = subprocess.run([sys.executable, "-m", "silbridge", "fly", "--help"],
                         capture_output=True, text=True, cwd=ROOT.parent)
    assert out.returncode == 0 and "--duration" in out.stdout


def test_the_console_script_is_the_platform_checked_main():
    scripts = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["scripts"]
    assert scripts["silbridge"] == "silbridge.__main__:main"


def _imports_the_api(path: Path) -> list[str]:
    """`silbridge` top-level names (not subpackages) a file imports."""
    found = []
    for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
        if isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            if node.module == "silbridge":
                found += [a.name for a in node.names if a.name not in PARTS]
            elif node.module.startswith("silbridge._"):
                found.append(node.module)
        elif isinstance(node, ast.Import):
            found += [a.name for a in node.names
                      if a.name == "silbridge" or a.name.startswith("silbridge._")]
    return found


def test_nothing_below_the_api_imports_it(tmp_path):
    bad = [f"{p.relative_to(ROOT)}: {', '.join(names)}"
           for part in PARTS for p in sorted((ROOT / part).rglob("*.py"))
           if (names := _imports_the_api(p))]
    assert not bad, "the API is the top layer; these import it:\n" + "\n".join(bad)
    probe = tmp_path / "x.py"
    probe.write_text("from silbridge import fly\nimport silbridge._flight\n"
                     "from silbridge import tools\n")
    assert _imports_the_api(probe) == ["fly", "silbridge._flight"]
