"""silbridge.mavlink: MAVLink links and the ArduCopter-compatible GCS server.

Entry points others use:
  GcsServer(vehicle, params, endpoints, sysid=1, compid=1, param_file=None)  -- gcs/server.py
  VehicleSnapshot, VehicleCommands, ParamStore, MissionItem                  -- gcs/vehicle_api.py
  parse_endpoint, add_gcs_arguments, endpoints_from_args                     -- endpoints.py
  load_parm, save_parm, apply_parm, save_store                               -- gcs/params_file.py
  load_wpl, save_wpl                                                         -- gcs/wpl.py
Modules are imported lazily by their users; importing this package costs nothing.
"""
