# Charts of `spotshell bench` (embedded into the spotshell binary at build time; run by it as
# `python3 - DIR`). Reads DIR/results.json, writes DIR/pareto.png, DIR/stability.png and, when
# the suite measured scaling, DIR/scaling.png. Needs matplotlib (Debian: python3-matplotlib).
#
# Every chart keeps its text inside the figure and apart: titles are wrapped to the figure's
# width, legends wrap into rows, and the Pareto charts number their points (a key beside each
# panel names them) instead of writing a label at each point. Before a chart is saved,
# `layout_problems` measures every text's box as drawn: one outside the figure, or two point
# labels that overlap, fails the script (tests/bench/charts_test.py holds it on crowded data).
import json
import math
import sys
import textwrap

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


def wrap(text, fig, fontsize):
    """Text wrapped to the figure's width (about 0.55 em a character)."""
    chars = max(20, int(fig.get_figwidth() * 72.0 / (0.55 * fontsize)))
    return "\n".join(textwrap.wrap(text, chars))


def layout_problems(fig, labels=()):
    """What does not fit: every visible text (titles, axis labels, ticks, legends, annotations)
    whose drawn box leaves the figure, and every pair of `labels` (point labels) that overlap.
    Measured on the renderer after drawing; an empty list is a chart that reads."""
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    box = fig.bbox
    problems = []
    # Tick labels of ticks outside an axis's view are never drawn: not measured.
    hidden = set()
    for ax in fig.axes:
        for axis in (ax.xaxis, ax.yaxis):
            lo, hi = sorted(axis.get_view_interval())
            for tick in axis.get_major_ticks() + axis.get_minor_ticks():
                loc = tick.get_loc()
                if loc is None or not (lo - 1e-9 * abs(hi - lo) <= loc <= hi + 1e-9 * abs(hi - lo)):
                    hidden.update((id(tick.label1), id(tick.label2)))
    whole = fig.get_tightbbox(renderer)
    if whole is not None:
        w = whole.transformed(fig.dpi_scale_trans)
        if w.x0 < box.x0 - 0.5 or w.y0 < box.y0 - 0.5 or w.x1 > box.x1 + 0.5 or \
                w.y1 > box.y1 + 0.5:
            problems.append("the drawn artists' tight box (%.0f..%.0f x %.0f..%.0f) is larger "
                            "than the figure (%.0f x %.0f)" % (w.x0, w.x1, w.y0, w.y1,
                                                              box.width, box.height))
    for t in fig.findobj(matplotlib.text.Text):
        if not t.get_visible() or not t.get_text().strip() or id(t) in hidden:
            continue
        e = t.get_window_extent(renderer)
        if e.x0 < box.x0 - 0.5 or e.y0 < box.y0 - 0.5 or e.x1 > box.x1 + 0.5 or \
                e.y1 > box.y1 + 0.5:
            problems.append("text %r reaches outside the figure (%.0f..%.0f x %.0f..%.0f in "
                            "%.0f x %.0f)" % (t.get_text()[:40], e.x0, e.x1, e.y0, e.y1,
                                              box.width, box.height))
    extents = [(t, t.get_window_extent(renderer)) for t in labels]
    for i in range(len(extents)):
        for j in range(i + 1, len(extents)):
            a, b = extents[i][1], extents[j][1]
            if a.x0 < b.x1 and b.x0 < a.x1 and a.y0 < b.y1 and b.y0 < a.y1:
                problems.append("labels %r and %r overlap" % (extents[i][0].get_text(),
                                                              extents[j][0].get_text()))
    return problems


def save(fig, path, labels=()):
    problems = layout_problems(fig, labels)
    if problems:
        raise SystemExit("plot_bench: %s does not fit: %s" % (path, "; ".join(problems)))
    fig.savefig(path, dpi=110)
    plt.close(fig)


def place_labels(ax, points, texts, fontsize=7):
    """Number labels beside their points, each at the first of 8 offsets around the point (tried
    outwards) where it overlaps no label already placed and no point's marker, and stays in the
    axes. Boxes are computed from each label's measured size, so nothing is drawn per trial.
    Returns the text artists."""
    fig = ax.figure
    renderer = fig.canvas.get_renderer()
    scale = fig.dpi / 72.0  # pixels a point
    marker = 5.0  # pixels: a marker's half size
    screen = [ax.transData.transform(p) for p in points]
    frame = ax.bbox
    placed, artists = [], []
    offsets = [(4, 3), (4, -12), (-4, 3), (-4, -12), (6, -4.5), (-6, -4.5), (-3, 6), (-3, -15)]
    for (x, y), (px, py), text in zip(points, screen, texts):
        probe = ax.text(0, 0, text, fontsize=fontsize)
        e = probe.get_window_extent(renderer)
        probe.remove()
        w, h = e.width, e.height
        choice = None
        for radius in (1.0, 1.6, 2.3, 3.2, 4.5):
            for dx, dy in offsets:
                # Left-hand offsets put the label's right edge there.
                x0 = px + dx * radius * scale - (w if dx < 0 else 0.0)
                y0 = py + dy * radius * scale
                box = (x0, y0, x0 + w, y0 + h)
                inside = frame.x0 <= box[0] and box[2] <= frame.x1 and frame.y0 <= box[1] and \
                    box[3] <= frame.y1
                clear = all(not (box[0] < q[2] and q[0] < box[2] and box[1] < q[3] and
                                 q[1] < box[3]) for q in placed)
                off_points = all(not (box[0] - marker < sx < box[2] + marker and
                                      box[1] - marker < sy < box[3] + marker)
                                 for sx, sy in screen)
                if inside and clear and off_points:
                    choice = box
                    break
            if choice:
                break
        if choice is None:  # nowhere free: beside the point (the key still names it)
            choice = (px + 4 * scale, py + 3 * scale, px + 4 * scale + w, py + 3 * scale + h)
        placed.append(choice)
        t = ax.annotate(text, (x, y), xytext=((choice[0] - px) / scale, (choice[1] - py) / scale),
                        textcoords="offset points", fontsize=fontsize, color="#222222",
                        ha="left", va="bottom")
        artists.append(t)
    return artists


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
# Each point carries a number; the key beside its panel names the method and the setting.
def pareto(doc, rows, path):
    scenes = []
    for r in rows:
        if r["scene"] not in scenes:
            scenes.append(r["scene"])
    cols = min(2, max(1, len(scenes)))
    lines = max(1, math.ceil(len(scenes) / cols))
    # Each panel: the plot and its key to the right (11 inches a panel: room for the key).
    fig, axes = plt.subplots(lines, cols, figsize=(10.0 * cols, 5.6 * lines + 1.2),
                             squeeze=False)
    placements, keys = [], []
    for i, scene in enumerate(scenes):
        ax = axes[i // cols][i % cols]
        pts = sorted([r for r in rows if r["scene"] == scene],
                     key=lambda r: (r["method"], r["ms_median"]))
        for r in pts:
            marker, color = style(r["method"])
            ax.scatter(r["ms_median"], r["flip"], marker=marker, color=color, s=46, zorder=3,
                       edgecolors="black", linewidths=0.5)
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
        xs = [r["ms_median"] for r in pts]
        ys = [r["flip"] for r in pts]
        if xs:  # margins, so that the numbers of the outermost points stay inside the axes
            ax.set_xlim(min(xs) / 1.35, max(xs) * 1.35)
            span = max(ys) - min(ys) or max(abs(max(ys)), 1e-3)
            ax.set_ylim(min(ys) - 0.12 * span, max(ys) + 0.12 * span)
        ax.set_xlabel("GPU milliseconds per frame (median of warm frames, log)")
        ax.set_ylabel("FLIP against the reference (lower is better)")
        ax.set_title(scene, fontsize=11)
        ax.grid(True, which="both", alpha=0.3)
        # The key: number, method and setting, in columns to the right of the panel.
        names = ["%d %s %s%s" % (k + 1, r["method"], r["setting"],
                                 " *" if r in kept else "") for k, r in enumerate(pts)]
        # One monospace block (columns of 40 entries padded side by side), so that it moves
        # and scales as one text when the layout shrinks the panel.
        rows_per_column = 40
        columns = [names[c:c + rows_per_column] for c in range(0, len(names), rows_per_column)]
        widths = [max(len(n) for n in col) for col in columns]
        text = []
        for k in range(len(columns[0]) if columns else 0):
            text.append("   ".join(col[k].ljust(w) if k < len(col) else " " * w
                                    for col, w in zip(columns, widths)).rstrip())
        keys.append(ax.text(1.03, 1.0, "\n".join(text), transform=ax.transAxes, fontsize=6.5,
                            va="top", ha="left", family="monospace"))
        placements.append((ax, pts))
    for j in range(len(scenes), lines * cols):
        axes[j // cols][j % cols].axis("off")
    handles = [plt.Line2D([], [], marker=m, color=c, linestyle="", markersize=7, label=k)
               for k, (m, c) in METHOD_STYLE.items() if any(r["method"] == k for r in rows)]
    handles.append(plt.Line2D([], [], color="black", alpha=0.6, label="Pareto front (* in the key)"))
    title = "spotshell: speed against accuracy (%s suite, %dx%d, %s)" % (
        doc["suite"], doc["width"], doc["height"], doc["device"])
    fig.suptitle(wrap(title, fig, 12), fontsize=12)
    fig.legend(handles=handles, loc="lower center", ncol=min(len(handles), 4), frameon=False)
    # The layout first (the keys count in it), then the numbers, placed where they are drawn.
    fig.tight_layout(rect=(0, 0.06, 1, 0.93))
    labels = list(keys)
    for ax, pts in placements:
        labels += place_labels(ax, [(r["ms_median"], r["flip"]) for r in pts],
                               [str(k + 1) for k in range(len(pts))])
    save(fig, path, labels)


# ---- stability.png: scenarios x methods, the best setting of each, coloured by verdict --------
def column(r):
    # The ray-march without a pixel filter and the bake without mips (level 0 only) are columns
    # of their own (as in stability.md).
    if r.get("rays_per_pixel") == 1:
        return r["method"] + " (1 ray/pixel)"
    if r["method"] == "baked" and r.get("levels") == 1:
        return r["method"] + " (no mips)"
    return r["method"]


def best(stability, scenario, method):
    cands = [r for r in stability if r["scenario"] == scenario and column(r) == method]
    good = [r for r in cands if r["status"] not in ("failed", "refused")]
    if good:
        return min(good, key=lambda r: r["flip"])
    return cands[0] if cands else None


VERDICT = {"ok": "#a6dba0", "degraded": "#fdd49e", "failed": "#f4a6a6", "refused": "#d9d9d9"}


def stability_chart(doc, stability, path):
    scenarios, methods = [], []
    for r in stability:
        if r["scenario"] not in scenarios:
            scenarios.append(r["scenario"])
        if column(r) not in methods:
            methods.append(column(r))
    fig, ax = plt.subplots(figsize=(2.3 * len(methods) + 3.2, 0.8 * len(scenarios) + 1.6))
    for y, scenario in enumerate(scenarios):
        for x, method in enumerate(methods):
            r = best(stability, scenario, method)
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
    ax.set_title(wrap("Which method fails where (best setting per method; %s suite)" % doc["suite"],
                      fig, 11), pad=28, fontsize=11)
    fig.tight_layout()
    save(fig, path)


# ---- scaling.png: ms and memory against visible kernels, ms against resolution ---------------
def scaling_chart(doc, scaling, path):
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
    fig.suptitle(wrap("spotshell scaling (%s)" % doc["device"], fig, 12), fontsize=12)
    fig.tight_layout()
    save(fig, path)


def main(out):
    doc = json.load(open(out + "/results.json"))
    rows = [r for r in doc["rows"] if r.get("status") in ("ok", "degraded") and "flip" in r]
    scaling = [r for r in doc["rows"]
               if r["scenario"].startswith("scaling") and r.get("status") == "ok"]
    stability = [r for r in doc["rows"] if not r["scenario"].startswith("scaling")]
    pareto(doc, rows, out + "/pareto.png")
    stability_chart(doc, stability, out + "/stability.png")
    if scaling:
        scaling_chart(doc, scaling, out + "/scaling.png")


if __name__ == "__main__":
    main(sys.argv[1])
