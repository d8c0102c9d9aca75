# Charts of `spotshell bench` (embedded into the spotshell binary at build time; run by it as
# `python3 - DIR`). Reads DIR/results.json, writes DIR/pareto.png, DIR/stability.png and, when
# the suite measured scaling, DIR/scaling.png. Needs matplotlib (Debian: python3-matplotlib).
import json
import math
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.ticker import LogLocator, ScalarFormatter  # noqa: E402


def plain_log_axis(axis):
    """Log scale with plain numbers (12, 50, 200) instead of 1.2x10^1."""
    fmt = ScalarFormatter()
    fmt.set_scientific(False)
    axis.set_major_formatter(fmt)
    axis.set_minor_formatter(matplotlib.ticker.NullFormatter())
    axis.set_major_locator(LogLocator(base=10, subs=(1.0, 2.0, 5.0)))

out = sys.argv[1]
doc = json.load(open(out + "/results.json"))
rows = [r for r in doc["rows"] if r.get("status") in ("ok", "degraded") and "flip" in r]
scaling = [r for r in doc["rows"] if r["scenario"].startswith("scaling") and r.get("status") == "ok"]
stability = [r for r in doc["rows"] if not r["scenario"].startswith("scaling")]

METHOD_STYLE = {
    "instanced": ("s", "tab:gray"),
    "oit": ("o", "tab:blue"),
    "hybrid": ("D", "tab:orange"),
    "sorted": ("^", "tab:green"),
    "raymarch": ("v", "tab:red"),
    "baked": ("P", "tab:purple"),
}


def style(method):
    return METHOD_STYLE.get(method, ("x", "black"))


# ---- pareto.png: per scene, milliseconds (log) against FLIP, the Pareto front drawn -----------
scenes = []
for r in rows:
    if r["scene"] not in scenes:
        scenes.append(r["scene"])
cols = min(3, max(1, len(scenes)))
lines = max(1, math.ceil(len(scenes) / cols))
fig, axes = plt.subplots(lines, cols, figsize=(6.0 * cols, 4.6 * lines), squeeze=False)
for i, scene in enumerate(scenes):
    ax = axes[i // cols][i % cols]
    pts = [r for r in rows if r["scene"] == scene]
    for r in pts:
        marker, color = style(r["method"])
        ax.scatter(r["ms_median"], r["flip"], marker=marker, color=color, s=46, zorder=3,
                   edgecolors="black", linewidths=0.5)
        ax.annotate(r["method"] + "\n" + r["setting"], (r["ms_median"], r["flip"]), fontsize=6.5,
                    xytext=(4, 3), textcoords="offset points", color="#333333")
    # Pareto front: no other point is both faster and more accurate.
    front = sorted(pts, key=lambda r: (r["ms_median"], r["flip"]))
    kept, best = [], float("inf")
    for r in front:
        if r["flip"] < best:
            kept.append(r)
            best = r["flip"]
    ax.step([r["ms_median"] for r in kept], [r["flip"] for r in kept], where="post",
            color="black", linewidth=1.0, alpha=0.6, zorder=2, label="Pareto front")
    ax.set_xscale("log")
    plain_log_axis(ax.xaxis)
    ax.set_xlabel("GPU milliseconds per frame (median of warm frames, log)")
    ax.set_ylabel("FLIP against the reference (lower is better)")
    ax.set_title(scene, fontsize=11)
    ax.grid(True, which="both", alpha=0.3)
for j in range(len(scenes), lines * cols):
    axes[j // cols][j % cols].axis("off")
handles = [plt.Line2D([], [], marker=m, color=c, linestyle="", markersize=7, label=k)
           for k, (m, c) in METHOD_STYLE.items() if any(r["method"] == k for r in rows)]
handles.append(plt.Line2D([], [], color="black", alpha=0.6, label="Pareto front"))
fig.suptitle("spotshell: speed against accuracy (%s suite, %dx%d, %s)"
             % (doc["suite"], doc["width"], doc["height"], doc["device"]), y=0.995, fontsize=12)
fig.legend(handles=handles, loc="upper center", ncol=len(handles), frameon=False,
           bbox_to_anchor=(0.5, 0.965))
fig.tight_layout(rect=(0, 0, 1, 0.92))
fig.savefig(out + "/pareto.png", dpi=110)
plt.close(fig)

# ---- stability.png: scenarios x methods, the best setting of each, coloured by verdict --------
def column(r):
    # The ray-march without a pixel filter and the bake without mips (level 0 only) are columns
    # of their own (as in stability.md).
    if r.get("rays_per_pixel") == 1:
        return r["method"] + " (1 ray/pixel)"
    if r["method"] == "baked" and r.get("levels") == 1:
        return r["method"] + " (no mips)"
    return r["method"]


scenarios, methods = [], []
for r in stability:
    if r["scenario"] not in scenarios:
        scenarios.append(r["scenario"])
    if column(r) not in methods:
        methods.append(column(r))


def best(scenario, method):
    cands = [r for r in stability if r["scenario"] == scenario and column(r) == method]
    good = [r for r in cands if r["status"] not in ("failed", "refused")]
    if good:
        return min(good, key=lambda r: r["flip"])
    return cands[0] if cands else None


VERDICT = {"ok": "#a6dba0", "degraded": "#fdd49e", "failed": "#f4a6a6", "refused": "#d9d9d9"}
fig, ax = plt.subplots(figsize=(2.3 * len(methods) + 3.2, 0.8 * len(scenarios) + 1.6))
for y, scenario in enumerate(scenarios):
    for x, method in enumerate(methods):
        r = best(scenario, method)
        color = VERDICT.get(r["status"], "white") if r else "white"
        ax.add_patch(plt.Rectangle((x, y), 1, 1, color=color, ec="white", lw=2))
        if r is None:
            text = "-"
        elif r["status"] in ("failed", "refused"):
            text = r["status"]
        else:
            text = "FLIP %.3f\nflicker %+.4f\n%s" % (r["flip"], r["flicker"], r["setting"])
        ax.text(x + 0.5, y + 0.5, text, ha="center", va="center", fontsize=8)
ax.set_xlim(0, len(methods))
ax.set_ylim(len(scenarios), 0)
ax.set_xticks([x + 0.5 for x in range(len(methods))])
ax.set_xticklabels([m.replace(" (", "\n(") for m in methods])
ax.xaxis.tick_top()
ax.set_yticks([y + 0.5 for y in range(len(scenarios))])
ax.set_yticklabels(scenarios)
ax.tick_params(length=0)
for s in ax.spines.values():
    s.set_visible(False)
handles = [plt.Rectangle((0, 0), 1, 1, color=c, label=k) for k, c in VERDICT.items()]
ax.legend(handles=handles, loc="upper center", bbox_to_anchor=(0.5, -0.02), ncol=len(handles),
          frameon=False)
ax.set_title("Which method fails where (best setting per method; %s suite)" % doc["suite"],
             pad=28, fontsize=11)
fig.tight_layout()
fig.savefig(out + "/stability.png", dpi=110)
plt.close(fig)

# ---- scaling.png: ms and memory against visible kernels, ms against resolution ---------------
if scaling:
    fig, axes = plt.subplots(1, 3, figsize=(16, 4.6))
    kern = [r for r in scaling if r["scenario"] == "scaling-kernels"]
    for method in sorted({r["method"] for r in kern}):
        pts = sorted([r for r in kern if r["method"] == method], key=lambda r: r["kernels_drawn"])
        marker, color = style(method)
        axes[0].plot([r["kernels_drawn"] for r in pts], [r["ms_median"] for r in pts],
                     marker=marker, color=color, label=method)
        axes[1].plot([r["kernels_drawn"] for r in pts], [r["gpu_memory_bytes"] / 2**20 for r in pts],
                     marker=marker, color=color, label=method + " GPU")
        axes[1].plot([r["kernels_drawn"] for r in pts], [r["host_memory_bytes"] / 2**20 for r in pts],
                     marker=marker, color=color, linestyle="--", alpha=0.6, label=method + " host")
    for ax, ylabel in ((axes[0], "GPU ms per frame"), (axes[1], "memory, MiB")):
        ax.set_xscale("log")
        ax.set_yscale("log")
        plain_log_axis(ax.yaxis)
        ax.set_xlabel("visible kernels drawn (log)")
        ax.set_ylabel(ylabel)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    axes[0].set_title("time against kernels (uniform preset on a sphere, 256x256)")
    axes[1].set_title("memory against kernels")
    res = sorted([r for r in scaling if r["scenario"] == "scaling-resolution"],
                 key=lambda r: r["width"] * r["height"])
    axes[2].plot([r["width"] * r["height"] for r in res], [r["ms_median"] for r in res],
                 marker="D", color=style("hybrid")[1], label="hybrid, fur-bunny")
    for r in res:
        axes[2].annotate(r["setting"], (r["width"] * r["height"], r["ms_median"]), fontsize=7,
                         xytext=(4, -8), textcoords="offset points")
    axes[2].set_xscale("log")
    axes[2].set_yscale("log")
    plain_log_axis(axes[2].yaxis)
    axes[2].set_xlabel("pixels (log)")
    axes[2].set_ylabel("GPU ms per frame")
    axes[2].set_title("time against resolution")
    axes[2].grid(True, which="both", alpha=0.3)
    axes[2].legend(fontsize=8)
    fig.suptitle("spotshell scaling (%s)" % doc["device"], fontsize=12)
    fig.tight_layout()
    fig.savefig(out + "/scaling.png", dpi=110)
    plt.close(fig)
