"""``gpu_check``'s figure: lane-steps per second against lanes (whole lives, each phase) and a generation's seconds,
per kernel, from the check's results."""

from __future__ import annotations

import json
import os

from imrl_jax.commands.gpu_harness import KERNELS
from imrl_jax.commands.gpu_steps import PHASE_KERNELS


def figure(results: dict, path: str, cpu_bench: str | None = None) -> bool:
    """Lane-steps per second against lanes (whole lives, each phase) and a generation's seconds, per kernel:
    a panel for each of these steps that measured something (False, and no file, when none did)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from imrl_jax.commands import bench

    steps = {s["step"]: s for s in results["steps"]}
    done = {name: [r for r in steps.get(name, {}).get("rows", []) if r.get("status") == "ok"]
            for name in ("life", "phases", "generation")}
    sweep_done = steps.get("sweep", {}).get("status") == "ok"
    panels = [name for name in done if done[name] or (name == "generation" and sweep_done)]
    if not panels:
        return False
    fig, axes = plt.subplots(1, len(panels), figsize=(5 * len(panels), 4.4), squeeze=False)
    axes = dict(zip(panels, axes[0]))
    colours = {"xla": "tab:blue", "pallas": "tab:red"}
    if "life" in axes:
        ax = axes["life"]
        for kernel in KERNELS:
            rows = [r for r in done["life"] if r["kernel"] == kernel]
            if rows:
                ax.plot([r["lanes"] for r in rows], [r["lane_steps_per_s"] for r in rows], "o-",
                        color=colours[kernel], label=f"{kernel} on the device")
        if cpu_bench and os.path.exists(cpu_bench):
            with open(cpu_bench) as f:
                cpu = json.load(f).get("lifetimes", [])
            ax.plot([r["lanes"] for r in cpu], [r["lane_steps_per_s"] for r in cpu], "s--", color="0.4",
                    label="xla, 2-core CPU (docs/bench)")
        ax.set(xscale="log", yscale="log", xlabel="adult lanes (6 per individual)", ylabel="lane-steps per second",
               title="Whole LE-LS lives")
    if "phases" in axes:
        ax = axes["phases"]
        styles = dict(zip([p[0] for p in bench.PHASES], ("o-", "s-", "^-", "v-")))
        for kernel, retina in PHASE_KERNELS:  # the kernel observing by points: dashed, a lighter red
            label = kernel if retina in (None, "entries") else f"{kernel}, by points"
            for phase, style in styles.items():
                rows = [r for r in done["phases"] if r["kernel"] == kernel and r["phase"] == phase
                        and r.get("retina", "entries" if kernel == "pallas" else None) == retina]
                if rows:
                    ax.plot([r["lanes"] for r in rows], [r["lane_steps_per_s"] for r in rows],
                            style if retina != "points" else style[0] + "--",
                            color=colours[kernel] if retina != "points" else "tab:orange",
                            label=f"{phase} ({label})", ms=4, lw=1)
        ax.set(xscale="log", yscale="log", xlabel="lanes", ylabel="lane-steps per second", title="Each phase")
    if "generation" in axes:
        ax = axes["generation"]
        rows = done["generation"]
        labels = [f"{r['kernel']}\n{r['seeds']} seeds" for r in rows]
        values = [r["seconds"] for r in rows]
        bar_colours = [colours[r["kernel"]] for r in rows]
        if sweep_done:
            s = steps["sweep"]
            labels.append(f"sweep ({s['kernel']})\n{s['points']} points\nx {s['seeds']} seeds")
            values.append(s["seconds"])
            bar_colours.append(colours[s["kernel"]])
        ax.bar(range(len(values)), values, color=bar_colours)
        for i, v in enumerate(values):
            ax.text(i, v, f"{v:.1f} s", ha="center", va="bottom", fontsize=8)
        ax.set_xticks(range(len(values)), labels, fontsize=7)
        ax.set(ylabel="seconds (compilation apart)", title="One paper-scale generation")
    for name in ("life", "phases"):
        if name in axes:
            axes[name].legend(fontsize=7, loc="best")
    machine = results.get("machine", {})
    fig.suptitle(f"gpu_check on {machine.get('device', '?')}, jax {machine.get('versions', {}).get('jax', '?')}"
                 + (" (--dry: tiny sizes, not speeds)" if results.get("dry") else ""), fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return True
