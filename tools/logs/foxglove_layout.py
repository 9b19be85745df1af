"""The Foxglove layout of the repository (docs/foxglove_layout.json), built from the channels.

Plots of attitude against its command and the FC's target, body rates
against the rate targets, the motors, the IMU's vibration (largest gyro peak
and band RMS over time), and a 3D view following the vehicle,
all on the viewable channels of tools/logs/viz_log.py. The layout is Foxglove's
exported-layout JSON (configById, layout, globalVariables, userNodes,
playbackConfig), which "Import from file..." in the Layouts menu opens.
Series are plotted against the message log time, which is sim time.

    python -m silbridge.tools.logs.foxglove_layout > docs/foxglove_layout.json
tests/tools/test_viz_log.py checks that the committed file is this output
and that every series names a field of a channel a log holds.
"""

from __future__ import annotations

import json

from silbridge.tools.logs.viz_log import PLOTS, SCENE_CHANNEL

_COLORS = ["#e6194b", "#3cb44b", "#4363d8", "#f58231", "#911eb4", "#42d4f4"]


def _series(path: str, label: str, i: int) -> dict:
    return {"value": path, "enabled": True, "timestampMethod": "receiveTime",
            "label": label, "color": _COLORS[i % len(_COLORS)]}


def _plot(title: str, series: list[tuple[str, str]], ylabel: str) -> dict:
    return {"paths": [_series(p, lab, i) for i, (p, lab) in enumerate(series)],
            "showXAxisLabels": True, "showYAxisLabels": True, "showLegend": True,
            "legendDisplay": "floating", "showPlotValuesInLegend": True, "isSynced": True,
            "xAxisVal": "timestamp", "sidebarDimension": 240,
            "foxglovePanelTitle": f"{title} [{ylabel}]"}


def _attitude_plot(axis: str) -> dict:
    return _plot(f"{axis.capitalize()}: true, commanded, FC target, FC estimate", [
        (f"/viz/attitude.{axis}_deg", "true"),
        (f"/viz/command.{axis}_deg", "commanded (setpoint)"),
        (f"/viz/fc.target_{axis}_deg", "FC target"),
        (f"/viz/fc.{axis}_deg", "FC estimate")], "deg")


def layout() -> dict:
    plots = {
        "Plot!roll": _attitude_plot("roll"),
        "Plot!pitch": _attitude_plot("pitch"),
        "Plot!yaw": _attitude_plot("yaw"),
        "Plot!rates": _plot("Body rates: true and FC rate targets", [
            ("/viz/attitude.p_deg_s", "p true"), ("/viz/fc.target_p_deg_s", "p target"),
            ("/viz/attitude.q_deg_s", "q true"), ("/viz/fc.target_q_deg_s", "q target"),
            ("/viz/attitude.r_deg_s", "r true"), ("/viz/fc.target_r_deg_s", "r target")],
            "deg/s"),
        "Plot!motors": _plot("Motors (PWM the FC published)", [
            (f"/viz/motors.m{i}_us", f"motor {i}") for i in range(1, 5)], "us"),
        # The IMU's spectrum, 10 times a second (tools/logs/viz_spectrum.py).
        "Plot!vibration_hz": _plot("Vibration: largest gyro peak per axis", [
            (f"/viz/vibration.gyro_{ax}_peak_hz", f"gyro {ax}") for ax in "xyz"], "Hz"),
        "Plot!vibration_rms": _plot("Vibration: gyro and accel band RMS", [
            *((f"/viz/vibration.gyro_{ax}_rms_rad_s", f"gyro {ax} [rad/s]") for ax in "xyz"),
            *((f"/viz/vibration.accel_{ax}_rms_m_s2", f"accel {ax} [m/s^2]") for ax in "xyz")],
            "rad/s, m/s^2"),
    }
    three_d = {
        "cameraState": {"distance": 4.0, "perspective": True, "phi": 60.0, "thetaOffset": 45.0,
                        "targetOffset": [0, 0, 0], "target": [0, 0, 0],
                        "targetOrientation": [0, 0, 0, 1], "fovy": 45, "near": 0.05,
                        "far": 5000},
        "followMode": "follow-position", "followTf": "base_link",
        "scene": {}, "transforms": {"frame:base_link_fc": {"visible": True}},
        "topics": {SCENE_CHANNEL: {"visible": True}, "/viz/pose": {"visible": False}},
        "layers": {"grid": {"visible": True, "layerId": "foxglove.Grid", "frameId": "world",
                            "size": 40, "divisions": 40, "lineWidth": 1,
                            "color": "#248eff66", "position": [0, 0, 0],
                            "rotation": [0, 0, 0]}},
        "publish": {"type": "point", "poseTopic": "/move_base_simple/goal",
                    "pointTopic": "/clicked_point", "poseEstimateTopic": "/initialpose",
                    "poseEstimateXDeviation": 0.5, "poseEstimateYDeviation": 0.5,
                    "poseEstimateThetaDeviation": 0.26179939},
        "imageMode": {},
        "foxglovePanelTitle": "Vehicle (solid: true; green: FC target; arrows: forces)",
    }
    return {
        "configById": {**plots, "3D!vehicle": three_d},
        "globalVariables": {}, "userNodes": {}, "playbackConfig": {"speed": 1},
        "layout": {
            "direction": "row", "splitPercentage": 55,
            "first": {"direction": "column", "splitPercentage": 60,
                      "first": {"direction": "column", "splitPercentage": 33,
                                "first": "Plot!roll",
                                "second": {"direction": "column", "first": "Plot!pitch",
                                           "second": "Plot!yaw"}},
                      "second": {"direction": "column", "first": "Plot!rates",
                                 "second": "Plot!motors"}},
            "second": {"direction": "column", "splitPercentage": 60, "first": "3D!vehicle",
                       "second": {"direction": "column", "first": "Plot!vibration_hz",
                                  "second": "Plot!vibration_rms"}}},
    }


def layout_paths(lay: dict) -> list[str]:
    """Every plotted message path of a layout (for the test against the channels)."""
    return [p["value"] for cfg in lay["configById"].values() for p in cfg.get("paths", [])]


def layout_topics(lay: dict) -> list[str]:
    """Every topic a layout names: plotted ones and the 3D panel's."""
    topics = {p.split(".", 1)[0] for p in layout_paths(lay)}
    for cfg in lay["configById"].values():
        topics |= set(cfg.get("topics", {}))
    return sorted(topics)


def plot_fields() -> dict[str, list[str]]:
    """topic -> fields of the plot channels."""
    return {topic: [f for f, _ in fields] for topic, (_n, _s, fields) in PLOTS.items()}


def main() -> int:
    print(json.dumps(layout(), indent=2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
