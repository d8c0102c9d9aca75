#!/usr/bin/env python3
"""Print README's per-scene summary tables from a bench run's results.json.

    python3 scripts/bench_table.py docs/bench/results.json

Table 1, per scene: the most accurate row; the fastest splatting row within 1 dB of the best
splatting PSNR; the cheapest ray-march whose FLIP is at least as low, and the splatter's speed-up
over it. Table 2, per scene and splat method at its default setting: the splat pass's time
against its roofline (the rasterizer's own cost for the same quads) and the fragment efficiency
(fragments shaded / pixels where a kernel's alpha reaches 1/255). Table 3, when the run has baked
rows, per scene: each baked setting's time (GPU and wall) and error against hybrid's default
setting, the bake's seconds and file size (refused rows with their reason). Table 4, when the
run checked the --quality table (splat/quality.h): each quality's choice, its mean PSNR and the
geometric mean of its wall milliseconds over the run's scenes, and the verdict.
"""
import json
import sys

SPLATTERS = ("instanced", "oit", "hybrid", "sorted")
DEFAULTS = {"instanced": "default", "oit": "ewa mb analytic", "hybrid": "ewa mb analytic",
            "sorted": "ewa analytic"}


def ms(row):
    """GPU milliseconds and, in parentheses, wall milliseconds: lavapipe's timestamps miss work in
    frames that draw nothing (docs/design.md section 8), so compare those by wall time."""
    wall = row.get("wall_ms_median")
    return f"{row['ms_median']:.1f} ({wall:.1f})" if wall else f"{row['ms_median']:.1f}"


def label(row):
    return f"{row['method']} {row['setting']}".replace(" default", "")


def main(path):
    doc = json.load(open(path))
    rows = [r for r in doc["rows"] if r.get("status") in ("ok", "degraded", "fails") and "psnr" in r]
    scenes = []
    for r in rows:
        if r["scene"] not in scenes:
            scenes.append(r["scene"])

    size = f"{doc['width']}x{doc['height']}" if "width" in doc else f"{doc.get('size')}"
    print(f"Suite {doc['suite']}, {size}, references at "
          f"{doc['reference_spp']} spp, {doc['device']}.\n")
    print("| scene (scenario) | best PSNR (method) | fastest splatter within 1 dB of the best splatter "
          "| ray-march at matched error | speed-up |")
    print("| --- | --- | --- | --- | --- |")
    for s in scenes:
        sr = [r for r in rows if r["scene"] == s]
        best = max(sr, key=lambda r: r["psnr"])
        splat = [r for r in sr if r["method"] in SPLATTERS]
        march = [r for r in sr if r["method"] == "raymarch"]
        cells = [f"{s} ({sr[0]['scenario']})", f"{best['psnr']:.2f} ({label(best)})"]
        if splat:
            top = max(r["psnr"] for r in splat)
            fast = min((r for r in splat if r["psnr"] >= top - 1.0), key=lambda r: r["ms_median"])
            cells.append(f"{label(fast)}: {fast['psnr']:.2f} dB, FLIP {fast['flip']:.3f}, "
                         f"{fast['ms_median']:.1f} ms")
            matched = [r for r in march if r["flip"] <= fast["flip"]]
            if matched:
                m = min(matched, key=lambda r: r["ms_median"])
                cells += [f"{m['setting']}, {m['ms_median']:.1f} ms",
                          f"{m['ms_median'] / fast['ms_median']:.1f}x"]
            elif march:
                cells += [f"never (best FLIP {min(r['flip'] for r in march):.3f})", "-"]
            else:
                cells += ["-", "-"]
        else:
            cells += ["-", "-", "-"]
        print("| " + " | ".join(cells) + " |")

    print("\nSplat pass / roofline, and fragment efficiency, at each method's default setting:\n")
    print("| scene | " + " | ".join(f"{m} ms (x roofline)" for m in SPLATTERS) + " | fragment efficiency |")
    print("| --- " * (len(SPLATTERS) + 2) + "|")
    for s in scenes:
        cells = [s]
        eff = "-"
        for m in SPLATTERS:
            r = next((r for r in rows if r["scene"] == s and r["method"] == m
                      and r["setting"] == DEFAULTS[m]), None)
            if r is None or not r.get("roofline_splat_ms"):
                cells.append("-")
                continue
            cells.append(f"{r['ms_median']:.1f} ({r['splat_ms_median'] / r['roofline_splat_ms']:.2f})")
            if r.get("fragment_efficiency"):
                eff = f"{r['fragment_efficiency']:.2f}"
        cells.append(eff)
        print("| " + " | ".join(cells) + " |")

    baked = [r for r in doc["rows"] if r["method"] == "baked"]
    if baked:
        print("\nbaked (resolution: level 0's voxels along the mesh's longest side; levels: mip "
              "levels; peels: depth-peeling passes) against hybrid's default setting:\n")
        print("| scene | setting | ms (wall) | PSNR | FLIP | hybrid ms (wall) / PSNR / FLIP | bake s "
              "| bake MiB | status |")
        print("| --- " * 9 + "|")
        refused = {}  # scene -> reason, when every baked row of the scene was refused alike
        for scene in dict.fromkeys(r["scene"] for r in baked):
            mine = [r for r in baked if r["scene"] == scene]
            reasons = {r.get("reason", "") for r in mine}
            if all(r["status"] == "refused" for r in mine) and len(reasons) == 1:
                refused[scene] = reasons.pop()
        for r in baked:
            if r["scene"] in refused:
                if r is next(x for x in baked if x["scene"] == r["scene"]):
                    print(f"| {r['scene']} | every setting | - | - | - | - | - | - | refused: "
                          f"{refused[r['scene']]} |")
                continue
            h = next((x for x in rows if x["scene"] == r["scene"] and x["method"] == "hybrid"
                      and x["setting"] == DEFAULTS["hybrid"]), None)
            hyb = f"{ms(h)} / {h['psnr']:.2f} / {h['flip']:.3f}" if h else "-"
            size = f"{r['bake_bytes'] / 2**20:.1f}" if r.get("bake_bytes") else "-"
            secs = f"{r['bake_seconds']:.2f}" if "bake_seconds" in r else "-"
            if "psnr" in r and r["status"] in ("ok", "degraded"):
                cells = [ms(r), f"{r['psnr']:.2f}", f"{r['flip']:.3f}"]
                status = r["status"]
            else:
                cells = ["-", "-", "-"]
                status = f"{r['status']}: {r.get('reason', '')}"
            print("| " + " | ".join([r["scene"], r["setting"]] + cells + [hyb, secs, size, status])
                  + " |")
    quality = doc.get("quality")
    if quality and quality.get("choices"):
        print(f"\n--quality over {', '.join(quality['scenes'])} (noise: "
              f"{quality['psnr_noise_db']} dB, {quality['time_noise_factor']}x time)\n")
        print("| quality | method (setting) | mean PSNR (dB) | wall ms (geometric mean) | verdict |")
        print("| --- | --- | --- | --- | --- |")
        for c in quality["choices"]:
            setting = f" ({c['setting']})" if "setting" in c else ""
            psnr = f"{c['psnr']:.2f}" if "psnr" in c else "-"
            wall = f"{c['wall_ms']:.1f}" if "wall_ms" in c else "-"
            verdict = c["status"]
            if "beaten_by" in c:
                b = c["beaten_by"]
                verdict += (f": {b['method']} ({b['setting']}) {b['psnr']:.2f} dB in "
                            f"{b['wall_ms']:.1f} ms")
            print(f"| {c['quality']} | {c['method']}{setting} | {psnr} | {wall} | {verdict} |")


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit("usage: bench_table.py RESULTS.json")
    main(sys.argv[1])
