"""silbridge.jsbsim_models: our JSBSim vehicle models, as XML with the source of every figure.

``AIRCRAFT_DIR`` is the folder to pass to ``FGFDMExec.set_aircraft_path``; each
model is ``<AIRCRAFT_DIR>/<name>/<name>.xml``. ``quadx`` is the 450 mm class
quad X (ArduCopter motor order) that the bridge flies.
"""

from __future__ import annotations

from pathlib import Path

AIRCRAFT_DIR = Path(__file__).resolve().parent
DEFAULT_MODEL = "quadx"


def model_names() -> list[str]:
    """Models shipped in this package (folders holding <name>/<name>.xml)."""
    return sorted(p.name for p in AIRCRAFT_DIR.iterdir()
                  if p.is_dir() and (p / f"{p.name}.xml").is_file())
