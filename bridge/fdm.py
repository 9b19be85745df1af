"""JSBSim wrapper: load the quad model quietly, place it at home, and expose the
property handles the bridge's hot path reads and writes.

Everything JSBSim-specific lives here: the silent logger, the load order
(set_dt before load_model), initial conditions that put the legs on the
ground without a bounce, the integrator switch between ground and air, and
unit conversions out of JSBSim's feet, pounds and slugs. The hot path
(`Simulator.step`) uses the handle objects directly (``node.get_double_value``,
~33 ns) instead of name lookups (~0.3-0.5 us), see JSBSIM_NOTES.md section 2.

Handle naming: attributes ``h_*`` are jsbsim property nodes.
"""

from __future__ import annotations

import math

import jsbsim

from silbridge.bridge.errors import SimulatorError
from silbridge.jsbsim_models import AIRCRAFT_DIR

FT_M = 0.3048            # m per ft
LBF_N = 4.448222         # N per lbf
PSF_PA = 47.88026        # Pa per lbf/ft^2
SLUG_KG = 14.593903      # kg per slug
G0_M_S2 = 9.80665        # standard gravity

# WGS-84 ellipsoid, for the local NED position around home.
_WGS84_A_M = 6378137.0
_WGS84_E2 = 6.69437999014e-3

# Integrator choices (JSBSIM_NOTES.md section 8): Euler rates on the ground (AB
# schemes limit-cycle on stiff contacts), AB4 rates in the air (energy drift
# 6e-9 over 10 s instead of 1.6e-3 with the defaults).
_RATE_ROT_GROUND = 1
_RATE_ROT_AIR = 5

LEG_BELOW_CG_M = 0.10    # quadx.xml: feet 0.10 m below the CG
LEG_COUNT = 4
LEG_SPRING_N_M = 2000.0  # quadx.xml spring_coeff per leg
# The mass moved to place the CG off centre: the battery of quadx.xml's mass budget.
_CG_MOVED_MASS_KG = 0.320
_LBM_PER_SLUG = 32.174049   # pounds-mass per slug (standard gravity in ft/s^2)
_IN_M = 0.0254              # m per inch
# Rotor hubs in body FRD (quadx.xml: 0.1591 m along x and y, 0.03 m above the CG).
ROTOR_HUBS_FRD_M = ((0.1591, 0.1591, -0.03), (-0.1591, -0.1591, -0.03),
                    (0.1591, -0.1591, -0.03), (-0.1591, 0.1591, -0.03))


class _QuietLogger(jsbsim.FGLogger):
    """Swallows JSBSim's banner and messages (JSBSIM_NOTES.md section 1)."""

    def set_level(self, level):
        pass

    def file_location(self, filename, line):
        pass

    def message(self, message):
        pass

    def format(self, fmt):
        pass

    def flush(self):
        pass


_LOGGER = None


def _quiet():
    # The logger is per thread in JSBSim; keep one Python object alive for it.
    global _LOGGER  # noqa: PLW0603 - process-wide by JSBSim's own design
    if _LOGGER is None:
        _LOGGER = _QuietLogger()
    jsbsim.set_logger(_LOGGER)


# The FDM sample the bridge's sensor stage reads after every step (bridge/src/sensor_stage.h,
# sb_fdm_sample): field name -> JSBSim property. The names are the C struct's fields, so the
# kernel binds each getter by name; JSBSim's own units stay in them (the stage converts).
SAMPLE_PROPERTIES = {
    "p_rad_s": "velocities/p-rad_sec", "q_rad_s": "velocities/q-rad_sec",
    "r_rad_s": "velocities/r-rad_sec",
    "fbx_lbf": "forces/fbx-total-lbs", "fby_lbf": "forces/fby-total-lbs",
    "fbz_lbf": "forces/fbz-total-lbs",
    "phi_rad": "attitude/phi-rad", "theta_rad": "attitude/theta-rad",
    "psi_rad": "attitude/psi-rad",
    "vn_ft_s": "velocities/v-north-fps", "ve_ft_s": "velocities/v-east-fps",
    "vd_ft_s": "velocities/v-down-fps",
    "lat_rad": "position/lat-geod-rad", "lon_rad": "position/long-gc-rad",
    # Height above ground is this minus the terrain's elevation (Fdm.terrain_ft), which is
    # what JSBSim's own position/h-agl-ft returns, the same double (flat terrain, the default
    # ground callback; tests/bridge/test_fdm_height.py holds the two equal). The stage
    # subtracts: h-agl-ft's getter places a contact point through the ground callback,
    # about 1,400 instructions a step, where this one reads the geodetic altitude JSBSim keeps.
    "geod_alt_ft": "position/geod-alt-ft",
    **{f"omega{i}_rad_s": f"fcs/m{i}-omega-rad_s" for i in range(1, 5)},
    "gear_contacts": "fcs/gear-contacts",
    "pressure_psf": "atmosphere/P-psf",
    "temperature_r": "atmosphere/T-R",
}


class Fdm:
    """One JSBSim instance flying the quad model, placed at a home location.

    Parameters: ``dt_s`` physics step; home latitude/longitude (deg), ground
    elevation above MSL (m) and heading (deg); ``initial_agl_m`` height of the
    feet above ground at start (0 = resting on the legs); ``random_seed`` for
    JSBSim's own generator (turbulence); ``vehicle`` the vehicle's imperfections
    (bridge/vehicle_draw.py; None or a neutral draw: the perfect quad, untouched).
    """

    def __init__(self, dt_s: float, lat_deg: float, lon_deg: float, ground_alt_m: float,
                 heading_deg: float, initial_agl_m: float = 0.0, random_seed: int = 0,
                 model: str = "quadx", vehicle=None):
        self.fdm = self._load(dt_s, model)
        self.dt_s = dt_s
        self._model = model
        self.mass_kg = self.fdm["inertia/mass-slugs"] * SLUG_KG
        # Rest height of the CG: legs compressed by m g / (n k) (no bounce at step 1).
        self.rest_agl_m = LEG_BELOW_CG_M - self.mass_kg * G0_M_S2 / (LEG_COUNT * LEG_SPRING_N_M)
        if vehicle is not None and vehicle.imperfect:
            # Before the initial conditions: JSBSim places the CG, so the legs must know it.
            self._apply_vehicle(vehicle)
        self._place(lat_deg, lon_deg, ground_alt_m, heading_deg, initial_agl_m, random_seed)
        self._air_integrator = False
        self._bind_handles()
        self._set_home(lat_deg, lon_deg, ground_alt_m)

    @staticmethod
    def _load(dt_s: float, model: str):
        """A quiet FGFDMExec with the model loaded at step dt_s."""
        _quiet()
        fdm = jsbsim.FGFDMExec(None)
        # At its default debug level JSBSim formats messages for the logger several times a step
        # (about 7000 instructions, 15-20 % of run()); the quiet logger drops them all anyway.
        fdm.set_debug_level(0)
        fdm.set_aircraft_path(str(AIRCRAFT_DIR))
        fdm.set_dt(dt_s)  # before load_model: lag filters take dt at load
        if not fdm.load_model(model):
            raise SimulatorError(
                f"JSBSim could not load model {model!r} from {AIRCRAFT_DIR}; "
                "check that the XML exists and is well formed")
        return fdm

    def _apply_vehicle(self, v) -> None:
        """The vehicle's imperfections as model parameters (see bridge/vehicle_draw.py).

        CG: the battery's mass moved by d = offset m / w (quadx.xml's point-mass pair), so
        the mass stays, the CG moves by the offset and the inertia changes as it would.
        Coefficients: fcs/mN-kt-scale and -kq-scale (motors.xml). Tilts: each rotor force's
        unit direction (JSBSim does not renormalise it; vehicle_draw gives unit vectors).
        The reaction torque keeps the body z axis: its roll/pitch part from a 0.6 deg tilt,
        kQ/kT sin(tilt) = 0.0165 m x 0.0105 = 1.7e-4 N m per N of thrust, is 1/900 of what
        a thrust change gives about the same axis (0.159 m per N) and is left out."""
        fdm = self.fdm
        w_lbs = _CG_MOVED_MASS_KG / SLUG_KG * _LBM_PER_SLUG
        scale = self.mass_kg / _CG_MOVED_MASS_KG / _IN_M
        dx, dy, dz = v.cg_offset_frd_m
        fdm["inertia/pointmass-weight-lbs[0]"] = -w_lbs
        fdm["inertia/pointmass-weight-lbs[1]"] = w_lbs
        # Structural frame: x aft, y right, z up (FRD's x and z flipped).
        fdm["inertia/pointmass-location-X-inches[1]"] = -dx * scale
        fdm["inertia/pointmass-location-Y-inches[1]"] = dy * scale
        fdm["inertia/pointmass-location-Z-inches[1]"] = -dz * scale
        # The feet are fixed to the frame: a CG dz lower sits dz nearer to them.
        self.rest_agl_m -= dz
        for i in range(4):
            fdm[f"fcs/m{i + 1}-kt-scale"] = v.kt_scale[i]
            fdm[f"fcs/m{i + 1}-kq-scale"] = v.kq_scale[i]
            for axis, c in zip("xyz", v.thrust_dir_frd[i]):
                fdm[f"external_reactions/m{i + 1}/{axis}"] = c

    def _place(self, lat_deg: float, lon_deg: float, ground_alt_m: float, heading_deg: float,
               initial_agl_m: float, random_seed: int) -> None:
        """Initial conditions: level and at rest on (or initial_agl_m above) the legs."""
        fdm = self.fdm
        fdm["simulation/randomseed"] = int(random_seed) & 0x7FFFFFFF
        fdm["ic/lat-geod-deg"] = lat_deg
        fdm["ic/long-gc-deg"] = lon_deg
        self.terrain_ft = ground_alt_m / FT_M     # JSBSim holds exactly this double
        fdm["ic/terrain-elevation-ft"] = self.terrain_ft
        fdm["ic/h-agl-ft"] = (self.rest_agl_m + initial_agl_m) / FT_M
        fdm["ic/psi-true-deg"] = heading_deg
        for name in ("ic/phi-deg", "ic/theta-deg", "ic/u-fps", "ic/v-fps", "ic/w-fps",
                     "ic/p-rad_sec", "ic/q-rad_sec", "ic/r-rad_sec"):
            fdm[name] = 0.0
        fdm["simulation/integrator/rate/rotational"] = _RATE_ROT_GROUND
        fdm["simulation/integrator/rate/translational"] = 3
        fdm["simulation/integrator/position/rotational"] = 5
        fdm["simulation/integrator/position/translational"] = 4
        if not fdm.run_ic():
            raise SimulatorError("JSBSim refused the initial conditions; check the home location")

    def _node(self, path: str):
        n = self.fdm.get_property_manager().get_node(path)
        if n is None:
            raise SimulatorError(f"model {self._model!r} lacks property {path}; "
                                 "it is not a silbridge quad model")
        return n

    def _bind_handles(self) -> None:
        """Property nodes of the inputs, the FDM sample and the disturbance forces."""
        node = self._node
        # Inputs.
        self.h_pwm = [node(f"fcs/m{i}-pwm-us") for i in range(1, 5)]
        self.h_scale = [node(f"fcs/m{i}-thrust-scale") for i in range(1, 5)]
        self.h_rate_rot = node("simulation/integrator/rate/rotational")
        # State: the sample's nodes by field name, and the ones Python reads by role.
        self.sample_nodes = {name: node(path) for name, path in SAMPLE_PROPERTIES.items()}
        h = self.sample_nodes
        self.h_p, self.h_q, self.h_r = h["p_rad_s"], h["q_rad_s"], h["r_rad_s"]
        self.h_fbx, self.h_fby, self.h_fbz = h["fbx_lbf"], h["fby_lbf"], h["fbz_lbf"]
        self.h_phi, self.h_theta, self.h_psi = h["phi_rad"], h["theta_rad"], h["psi_rad"]
        self.h_vn, self.h_ve, self.h_vd = h["vn_ft_s"], h["ve_ft_s"], h["vd_ft_s"]
        self.h_lat, self.h_lon = h["lat_rad"], h["lon_rad"]
        self.h_hagl = node("position/h-agl-ft")
        self.h_pressure, self.h_temp = h["pressure_psf"], h["temperature_r"]
        self.h_gear = h["gear_contacts"]
        self.h_omega = [h[f"omega{i}_rad_s"] for i in range(1, 5)]
        # Disturbance force handles (magnitude lbf, unit direction).
        self.h_dist_ned = [node(f"external_reactions/dist_ned/{a}") for a in
                           ("magnitude", "x", "y", "z")]
        self.h_dist_frd = [node(f"external_reactions/dist_frd/{a}") for a in
                           ("magnitude", "x", "y", "z")]

    def _set_home(self, lat_deg: float, lon_deg: float, ground_alt_m: float) -> None:
        """Home: where the CG rests on the legs below the start point (an air start is
        above home); local NED about it on the WGS-84 ellipsoid."""
        lat0 = self.h_lat.get_double_value()
        self.home_lat_rad = lat0
        self.home_lon_rad = self.h_lon.get_double_value()
        self.home_agl_m = self.rest_agl_m
        s = math.sin(lat0)
        w = math.sqrt(1.0 - _WGS84_E2 * s * s)
        self.m_per_rad_lat = _WGS84_A_M * (1.0 - _WGS84_E2) / (w * w * w)  # meridian radius
        self.m_per_rad_lon = _WGS84_A_M / w * math.cos(lat0)               # prime vertical
        self.home_lat_deg = lat_deg
        self.home_lon_deg = lon_deg
        self.ground_alt_m = ground_alt_m

    def sample_getters(self) -> dict:
        """{sample field name: bound getter} for the step kernel (bound once: ~33 ns a call)."""
        return {name: n.get_double_value for name, n in self.sample_nodes.items()}

    # --- constants of the loaded model -------------------------------------------------
    def model_constant(self, path: str) -> float:
        return self._node(path).get_double_value()

    # --- hot-path helpers (kept tiny; the simulator inlines the handle calls) ----------
    def set_air_integrator(self, airborne: bool) -> None:
        """AB4 rotational rates in the air, Euler on the ground (no contact limit cycle)."""
        if airborne != self._air_integrator:
            self.h_rate_rot.set_double_value(_RATE_ROT_AIR if airborne else _RATE_ROT_GROUND)
            self._air_integrator = airborne

    def set_dist_force(self, frame: str, magnitude_n: float, unit_dir) -> None:
        """Disturbance force at the CG: frame 'ned' or 'frd', magnitude in N."""
        handles = self.h_dist_ned if frame == "ned" else self.h_dist_frd
        handles[0].set_double_value(magnitude_n / LBF_N)
        for h, c in zip(handles[1:], unit_dir):
            h.set_double_value(float(c))

    def set_wind_ned(self, wind_ned_m_s) -> None:
        """Steady wind, NED components of the air velocity (where the air goes)."""
        for axis, v in zip(("north", "east", "down"), wind_ned_m_s):
            self.fdm[f"atmosphere/wind-{axis}-fps"] = float(v) / FT_M

    def set_turbulence(self, kind: str, wind_at_20ft_m_s: float, severity: int) -> None:
        """JSBSim turbulence: 'none', 'dryden' (MIL-F-8785C, type 3) or 'tustin' (type 4)."""
        turb_type = {"none": 0, "dryden": 3, "tustin": 4}[kind]
        self.fdm["atmosphere/turb-type"] = turb_type
        self.fdm["atmosphere/turbulence/milspec/windspeed_at_20ft_AGL-fps"] = (
            wind_at_20ft_m_s / FT_M)
        self.fdm["atmosphere/turbulence/milspec/severity"] = int(severity)

    def set_thrust_scale(self, motor_index: int, scale: float) -> None:
        self.h_scale[motor_index].set_double_value(scale)
