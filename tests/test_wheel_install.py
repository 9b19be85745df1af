"""The light install, as a user gets it: a wheel, a clean virtual environment, a flight.

The working tree (tracked and new files, as git lists them) is copied out, built into a
wheel with `pip wheel --no-deps` (this environment's setuptools and numpy: no build
dependency beyond the test set-up's), and installed into a fresh venv with its declared
dependencies only, from PyPI or pip's cache. From a folder outside the repository that
venv then flies, benches with its report and serves MAVLink, while the heavy extras (Ray,
MAVProxy, MAVSDK, optuna) are absent from it, and `tune` and `--executor ray` are refused
with the extra to install.

pyproject.toml lists the packages by hand (the repository's folders map into the
`silbridge` package); the first test, fast, checks that list against the tree.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PYPROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text())
HEAVY = ("ray", "MAVProxy", "mavsdk", "optuna")     # import names of the extras' packages
INSTALL_TIMEOUT_S = 1800                            # a cold pip cache downloads ~100 MB


def _package_dirs() -> dict[str, Path]:
    """Every Python package of the tree as its installed name -> folder."""
    setuptools = PYPROJECT["tool"]["setuptools"]
    out = {}
    for name, folder in setuptools["package-dir"].items():
        for init in sorted((ROOT / folder).rglob("__init__.py")):
            rel = init.parent.relative_to(ROOT / folder)
            if "__pycache__" not in rel.parts:
                out[".".join((name, *rel.parts))] = init.parent
    return out


def test_every_package_folder_is_in_the_wheel():
    listed = set(PYPROJECT["tool"]["setuptools"]["packages"])
    missing = sorted(set(_package_dirs()) - listed)
    assert not missing, f"add to pyproject.toml [tool.setuptools] packages: {missing}"
    assert "silbridge.tools.cli" in _package_dirs()      # the scan sees the tree


def test_a_missing_extra_is_named_with_its_install_line():
    from silbridge.tools.optional_deps import MissingExtraError, require
    require(["json"], "tune", "x")                      # present: nothing to say
    with pytest.raises(MissingExtraError) as info:
        require(["json", "no_such_module_c22"], "ray", "--executor ray")
    assert info.value.user_facing
    assert str(info.value) == ("--executor ray needs no_such_module_c22, from the 'ray' extra: "
                               "in the silbridge source folder run: pip install '.[ray]'")
    extras = PYPROJECT["project"]["optional-dependencies"]
    assert {"tune", "ray", "clients", "docs", "test"} <= set(extras)


def _run(cmd, *, cwd, timeout, env=None) -> subprocess.CompletedProcess:
    return subprocess.run(cmd, cwd=cwd, env=env, capture_output=True, text=True,
                          timeout=timeout)


def _copy_tree(dest: Path) -> None:
    """The working tree as git sees it (tracked plus untracked, ignored files left out)."""
    if shutil.which("git") is None or not (ROOT / ".git").exists():
        pytest.skip("not a git checkout: the wheel is built from the files git lists")
    listed = subprocess.run(["git", "ls-files", "-z", "--cached", "--others",
                             "--exclude-standard"], cwd=ROOT, capture_output=True,
                            check=True).stdout.decode().split("\0")
    for rel in filter(None, listed):
        src = ROOT / rel
        if src.is_file():            # a file deleted in the tree but still in the index
            (dest / rel).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(src, dest / rel)


@pytest.fixture(scope="module")
def light_venv(tmp_path_factory):
    """(bin folder, environment, an empty folder outside the repository)."""
    base = tmp_path_factory.mktemp("wheel")
    src, dist, venv, work = base / "src", base / "dist", base / "venv", base / "work"
    work.mkdir()
    _copy_tree(src)
    built = _run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation",
                  "-q", "-w", str(dist), str(src)], cwd=base, timeout=900)
    assert built.returncode == 0, built.stderr[-3000:]
    wheel, = dist.glob("silbridge-*.whl")
    made = _run([sys.executable, "-m", "venv", str(venv)], cwd=base, timeout=300)
    assert made.returncode == 0, made.stderr
    env = {k: v for k, v in os.environ.items()
           if k not in ("PYTHONPATH", "VIRTUAL_ENV", "PYTHONHOME")}
    env["PATH"] = f"{venv / 'bin'}{os.pathsep}{env.get('PATH', '')}"
    installed = _run([str(venv / "bin" / "python"), "-m", "pip", "install", "-q",
                      "--disable-pip-version-check", str(wheel)],
                     cwd=work, timeout=INSTALL_TIMEOUT_S, env=env)
    assert installed.returncode == 0, installed.stderr[-3000:]
    return venv / "bin", env, work


def _json(proc: subprocess.CompletedProcess) -> dict:
    assert proc.returncode == 0, proc.stderr[-3000:]
    return json.loads(proc.stdout.strip().splitlines()[-1])


@pytest.mark.slow
def test_the_wheel_flies_from_a_clean_venv(light_venv):
    bin_dir, env, work = light_venv
    summary = _json(_run([str(bin_dir / "silbridge"), "fly", "--duration", "5", "--json"],
                         cwd=work, timeout=300, env=env))
    assert summary["scenario"] == "S1" and summary["sim_s"] == pytest.approx(5.0)
    assert summary["crashed"] is False and summary["rates_hz"]["pwm"] > 0
    # The same flight from the source tree: the wheel carries the same code, bit for bit.
    here = _json(_run([sys.executable, "-m", "silbridge.tools", "fly", "--duration", "5",
                       "--json"], cwd=ROOT, timeout=300))
    assert summary["trace_hash"] == here["trace_hash"]


@pytest.mark.slow
def test_the_light_install_leaves_the_extras_out(light_venv):
    bin_dir, env, work = light_venv
    probe = ("import importlib.util, json; "
             f"print(json.dumps([m for m in {list(HEAVY)!r} if importlib.util.find_spec(m)]))")
    found = _json(_run([str(bin_dir / "python"), "-c", probe], cwd=work, timeout=60, env=env))
    assert found == []
    version = _run([str(bin_dir / "python"), "-c",
                    "import silbridge; print(silbridge.__version__)"],
                   cwd=work, timeout=60, env=env)
    assert version.returncode == 0, version.stderr
    assert version.stdout.strip() == PYPROJECT["project"]["version"]
    meta = ("import importlib.metadata as m, json; d = m.distribution('silbridge'); "
            "print(json.dumps([d.metadata['License-Expression'], "
            "[f.name for f in d.files if f.name == 'LICENSE']]))")
    licence, files = _json(_run([str(bin_dir / "python"), "-c", meta], cwd=work, timeout=60,
                                env=env))
    assert licence == "MIT" and files == ["LICENSE"]     # the licence text travels with it


@pytest.mark.slow
def test_the_light_install_benches_with_its_report(light_venv):
    bin_dir, env, work = light_venv
    out = work / "bench-out"
    table = _json(_run([str(bin_dir / "silbridge"), "bench", "--scenarios", "S1", "--runs",
                        "1", "--duration", "6", "--jobs", "1", "--warmup", "0", "1",
                        "--transient", "1", "2", "--analysis", "2", "6", "--yaw-window",
                        "4", "6", "--out", str(out), "--json"],
                       cwd=work, timeout=600, env=env))
    assert "S1" in table["scenarios"]
    assert (out / "report" / "index.html").is_file()
    assert list((out / "report").glob("*.png")), "the report has no plots"


@pytest.mark.slow
def test_the_light_install_serves_mavlink(light_venv):
    bin_dir, env, work = light_venv
    summary = _json(_run([str(bin_dir / "silbridge"), "fly", "--speed", "10", "--duration",
                          "2", "--mavlink", "--no-default-gcs", "--json"],
                         cwd=work, timeout=300, env=env))
    assert summary["mavlink"]["server"]["tx_msgs"] > 0      # the GCS server ran and sent


@pytest.mark.slow
@pytest.mark.parametrize("cmd, extra", [
    (["tune", "sysid", "--axis", "roll"], "tune"),
    (["bench", "--executor", "ray", "--scenarios", "S1", "--runs", "1", "--duration", "1"],
     "ray"),
])
def test_the_light_install_names_the_missing_extra(light_venv, cmd, extra):
    bin_dir, env, work = light_venv
    proc = _run([str(bin_dir / "silbridge"), *cmd, "--out", str(work / f"out-{extra}")],
                cwd=work, timeout=120, env=env)
    assert proc.returncode == 2, proc.stderr[-2000:]
    assert f"'{extra}' extra" in proc.stderr and f"pip install '.[{extra}]'" in proc.stderr
    assert "Traceback" not in proc.stderr
