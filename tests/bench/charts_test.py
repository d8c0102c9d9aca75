"""The benchmark's charts keep their text inside the figure and their labels apart (issue 41).

    /usr/bin/python3 tests/bench/charts_test.py SOURCE_DIR TMP_DIR

Draws scripts/plot_bench.py's charts from the lit bench's results (docs/bench-lit/results.json:
one scene, a long title, 29 points crowded at the Pareto front, the chart the issue found cut
off) and from a made-up suite crowded further (two scenes, 40 points each, half of them on top
of each other), then checks each saved PNG as a user sees it: no text touches its edges (its
outermost 3 pixels all white), and plot_bench's own measure (every text's drawn box inside the
figure, no two point labels overlapping) finds nothing. The measure itself is checked to see a
title pushed off the figure and two labels on one spot.
"""
import copy
import importlib.util
import json
import os
import random
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.image  # noqa: E402
import matplotlib.pyplot as plt  # noqa: E402

source, tmp = sys.argv[1], sys.argv[2]
spec = importlib.util.spec_from_file_location("plot_bench", os.path.join(source, "scripts/plot_bench.py"))
plot_bench = importlib.util.module_from_spec(spec)
spec.loader.exec_module(plot_bench)
failures = []


def check_png(path):
    image = matplotlib.image.imread(path)
    rgb = image[:, :, :3]
    edge = 3
    border = [rgb[:edge], rgb[-edge:], rgb[:, :edge], rgb[:, -edge:]]
    dark = sum(int((b < 0.99).any(axis=-1).sum()) for b in border)
    if dark:
        failures.append("%s: %d pixels of its outer %d-pixel border are not background (text "
                        "cut at the edge)" % (path, dark, edge))
    print("%s: %dx%d, border clear: %s" % (path, image.shape[1], image.shape[0], dark == 0))


def draw(name, doc):
    out = os.path.join(tmp, name)
    os.makedirs(out, exist_ok=True)
    with open(os.path.join(out, "results.json"), "w") as f:
        json.dump(doc, f)
    try:
        plot_bench.main(out)
    except SystemExit as e:
        failures.append("%s: %s" % (name, e))
        return
    for chart in ("pareto.png", "stability.png", "scaling.png"):
        if os.path.exists(os.path.join(out, chart)):
            check_png(os.path.join(out, chart))


lit = json.load(open(os.path.join(source, "docs/bench-lit/results.json")))
draw("charts-lit", lit)

# A crowded suite: two scenes, each point repeated with a tiny offset, a very long device name.
random.seed(7)
crowded = copy.deepcopy(lit)
crowded["device"] = "a GPU with a very long name indeed (driver 1.2.3.4, LLVM 15.0.6, 256 bits)"
rows = []
for scene in ("fur-bunny", "a-scene-with-a-long-name-too"):
    for r in lit["rows"]:
        for k in range(2):
            q = dict(r)
            q["scene"] = scene
            if "ms_median" in q:
                q["ms_median"] *= 1.0 + 0.002 * k
            if "flip" in q:
                q["flip"] += 0.0005 * k
            q["setting"] = q.get("setting", "") + (" copy" if k else "")
            rows.append(q)
crowded["rows"] = rows
draw("charts-crowded", crowded)

# The measure sees what it must: a title off the figure, two labels on one spot.
fig, ax = plt.subplots(figsize=(4, 3))
fig.suptitle("a title far too long for a figure four inches wide, cut at both ends", x=0.5)
if not plot_bench.layout_problems(fig):
    failures.append("layout_problems missed a title wider than the figure")
plt.close(fig)
fig, ax = plt.subplots(figsize=(4, 3))
a = ax.text(0.5, 0.5, "12")
b = ax.text(0.5, 0.5, "13")
if not plot_bench.layout_problems(fig, [a, b]):
    failures.append("layout_problems missed two labels on one spot")
plt.close(fig)

if failures:
    print("FAILED:\n  " + "\n  ".join(failures))
    sys.exit(1)
print("charts_test: passed")
