"""The soak's figures (PNG, matplotlib's Agg backend): RSS, open files, log rate, late steps."""

from __future__ import annotations

from pathlib import Path


def write_figures(result: dict, out_dir: Path) -> list[str]:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    samples, minutes = result["samples"], result["minutes"]
    if not samples:
        return []
    t = [s["t_s"] / 60 for s in samples]
    fig, ax = plt.subplots(4, 1, figsize=(8, 10), sharex=True)
    for name in samples[0]["procs"]:
        ax[0].plot(t, [s["procs"].get(name, {}).get("rss_kb", float("nan")) / 1024
                       for s in samples], label=name)
        ax[1].plot(t, [s["procs"].get(name, {}).get("fds", float("nan")) for s in samples],
                   label=name)
    ax[0].set_ylabel("RSS [MB]")
    ax[1].set_ylabel("open fds")
    ax[2].plot(t, [s["log_mb_per_min"] for s in samples])
    ax[2].set_ylabel("log [MB/min]")
    ax[3].plot([m["t_s"] / 60 for m in minutes], [m["late_steps_per_min"] for m in minutes], "o-")
    ax[3].set_ylabel("late steps / min")
    ax[3].set_xlabel("minutes")
    for a in ax[:2]:
        a.legend()
    for a in ax:
        a.grid(True, alpha=0.3)
    fig.suptitle(f"silbridge soak, {result['total_s'] / 60:.0f} min: "
                 f"{'PASS' if result['ok'] else 'FAIL'}")
    fig.tight_layout()
    path = Path(out_dir) / "soak.png"
    fig.savefig(path, dpi=80)
    plt.close(fig)
    return [str(path)]
