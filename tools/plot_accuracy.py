#!/usr/bin/python3
"""Turns `vkray bench accuracy`'s CSV into plots (error against time per knob, Pareto front marked)
and the generated part of docs/accuracy.md.

Each point carries the spread of its interleaved timed runs (min, median, max): the plots draw it as
error bars, and the tables say which differences are within noise (overlapping min–max ranges).
Where RUN_DIR holds instructions.csv (tools/accuracy-report --count-instructions), each point's
executed JIT instructions stand beside its time: a cost without noise.

usage: tools/plot_accuracy.py RUN_DIR DOC_MD IMAGE_DIR
  RUN_DIR   the --out directory of `vkray bench accuracy` (accuracy.csv, run.txt, heat maps,
            optionally instructions.csv)
  DOC_MD    the Markdown file to (re)write; text between <!-- reading --> and <!-- /reading --> is kept
  IMAGE_DIR where plots and the heat maps the document shows are written
"""
import csv
import math
import os
import shutil
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

KNOB_STYLE = {
    "baseline": ("black", "*"),
    "depth": ("tab:blue", "o"),
    "bailout": ("tab:orange", "s"),
    "spp": ("tab:green", "^"),
    "adaptive": ("tab:olive", "v"),
    "numerics": ("tab:red", "D"),
    "precision": ("tab:purple", "P"),
    "fresnel": ("tab:brown", "X"),
    "texture_filter": ("tab:olive", "P"),
    "combined": ("tab:gray", "h"),
    "noise_threshold": ("tab:cyan", "<"),
    "time_limit": ("tab:pink", ">"),
}
ANNOTATED = ("spp", "adaptive", "depth", "bailout", "combined", "noise_threshold", "time_limit")
# Knobs whose points form a series, in the order they are swept: neighbours are compared for noise.
SERIES = ("depth", "bailout", "spp", "adaptive", "noise_threshold", "time_limit", "numerics", "texture_filter",
          "fresnel")

COMMAND = "tools/accuracy-report"


def read_rows(path):
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    for r in rows:
        for k in ("trace_ms", "trace_ms_min", "trace_ms_max", "rmse", "rmse_min", "rmse_max", "max_abs", "share_off",
                  "rmse_1spp", "share_off_1spp", "spp_mean", "noise_threshold", "time_limit"):
            r[k] = float(r[k])
        r["psnr_db"] = math.inf if r["psnr_db"] == "inf" else float(r["psnr_db"])
        for k in ("rays", "eye_rays", "pixels_off", "spp", "max_depth", "runs"):
            r[k] = int(r[k])
        r["jit_instructions"] = None
    return rows


def join_instructions(rows, path):
    """Adds jit_instructions (and the size they were counted at) from instructions.csv, by scene, knob, value."""
    if not os.path.exists(path):
        return None
    with open(path, newline="") as f:
        counts = {(c["scene"], c["knob"], c["value"]): c for c in csv.DictReader(f)}
    size = None
    for r in rows:
        c = counts.get((r["scene"], r["knob"], r["value"]))
        if c:
            r["jit_instructions"] = int(c["jit_instructions"])
            size = f"{c['width']}×{c['height']}"
    return size


def overlaps(a, b):
    """Whether two points' min–max time ranges overlap: their difference is within the noise."""
    return a["trace_ms_min"] <= b["trace_ms_max"] and b["trace_ms_min"] <= a["trace_ms_max"]


def within_noise(rows):
    """Neighbours in each knob's series (and each point against the baseline) whose time ranges overlap."""
    base = next((r for r in rows if r["knob"] == "baseline"), None)
    pairs = []
    for knob in SERIES:
        series = [r for r in rows if r["knob"] == knob]
        for a, b in zip(series, series[1:]):
            if overlaps(a, b):
                pairs.append(f"{knob} {a['value']} ↔ {b['value']}")
    same = [f"{r['knob']} {r['value']}" for r in rows
            if base is not None and r is not base and r["knob"] not in ("reference", "baseline") and overlaps(r, base)]
    return pairs, same


def pareto(points):
    """Points (time, error) not dominated by any other: no other is both faster and more accurate."""
    front = []
    best = math.inf
    for t, e, label in sorted(points):
        if e < best:
            front.append((t, e, label))
            best = e
    return front


def annotation(r):
    if r["knob"] == "noise_threshold":
        return f"E {r['value']}"
    if r["knob"] == "time_limit":
        return f"S {r['value']} s"
    return r["value"]


def spread(ax, r, err, color):
    """Error bars: the time's min–max over the timed runs; for time-limited points also the error's."""
    xerr = [[r["trace_ms"] - r["trace_ms_min"]], [r["trace_ms_max"] - r["trace_ms"]]]
    yerr = None
    if r["rmse_max"] > r["rmse_min"]:
        yerr = [[err - max(r["rmse_min"], 1e-6)], [max(r["rmse_max"], 1e-6) - err]]
    ax.errorbar(r["trace_ms"], err, xerr=xerr, yerr=yerr, fmt="none", ecolor=color, elinewidth=0.9, capsize=2,
                alpha=0.8, zorder=2)


def plot_scene(name, rows, path):
    fig, ax = plt.subplots(figsize=(7.5, 4.8), dpi=110)
    pts = []
    for r in rows:
        if r["knob"] == "reference":
            continue
        color, marker = KNOB_STYLE.get(r["knob"], ("gray", "."))
        err = max(r["rmse"], 1e-6)
        spread(ax, r, err, color)
        ax.scatter(r["trace_ms"], err, c=color, marker=marker, s=36, zorder=3,
                   label=r["knob"] if r["knob"] not in [p[2] for p in pts] else None)
        pts.append((r["trace_ms"], err, r["knob"]))
        if r["knob"] in ANNOTATED:
            ax.annotate(annotation(r), (r["trace_ms"], err), fontsize=6, xytext=(3, 3), textcoords="offset points")
    front = pareto(pts)
    ax.plot([p[0] for p in front], [p[1] for p in front], "k--", lw=1, zorder=2, label="Pareto front")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("GPU trace time (ms; median, bars min–max of the interleaved runs)")
    ax.set_ylabel("RMSE against the reference (linear RGB)")
    ax.set_title(f"{name}: error against time")
    handles, labels = ax.get_legend_handles_labels()
    seen = {}
    for h, l in zip(handles, labels):
        if l and l not in seen:
            seen[l] = h
    ax.legend(seen.values(), seen.keys(), fontsize=7, loc="upper right")
    ax.grid(True, which="both", alpha=0.25)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)
    return front


def table(rows, base):
    counted = any(r["jit_instructions"] is not None for r in rows)
    head = "| knob | value | time ms | min–max ms | × baseline |"
    align = "|---|---|---:|---:|---:|"
    if counted:
        head += " JIT instr. (M) | × baseline |"
        align += "---:|---:|"
    head += (" rays | spp mean | RMSE | PSNR dB | max abs | pixels off (>1/255) | RMSE vs 1-spp ref | "
             "off vs 1-spp ref |")
    align += "---:|---:|---:|---:|---:|---:|---:|---:|"
    out = [head, align]
    for r in rows:
        psnr = "∞" if math.isinf(r["psnr_db"]) else f"{r['psnr_db']:.1f}"
        ratio = r["trace_ms"] / base["trace_ms"] if base["trace_ms"] > 0 else 0
        one_sample = r["spp"] == 1 and r["noise_threshold"] == 0 and r["time_limit"] == 0
        iso = f"{r['rmse_1spp']:.5f} | {100 * r['share_off_1spp']:.2f} %" if one_sample else "— | —"
        if r["runs"] == 0:  # not timed: one counted render
            times = f"≈{r['trace_ms']:.1f} | (1 counted render) | ≈{ratio:.1f}"
        else:
            noise = " ≈" if r is not base and r["knob"] != "reference" and overlaps(r, base) else ""
            times = f"{r['trace_ms']:.2f} | {r['trace_ms_min']:.2f}–{r['trace_ms_max']:.2f} | {ratio:.2f}{noise}"
        cells = f"| {r['knob']} | {r['value']} | {times} |"
        if counted:
            n, b = r["jit_instructions"], base["jit_instructions"]
            cells += (f" {n / 1e6:.3g} | {n / b:.2f} |" if n is not None and b else " — | — |")
        rmse = f"{r['rmse']:.5f}"
        if r["rmse_max"] > r["rmse_min"]:
            rmse += f" ({r['rmse_min']:.5f}–{r['rmse_max']:.5f})"
        out.append(cells + f" {r['rays']} | {r['spp_mean']:.3g} | {rmse} | {psnr} | {r['max_abs']:.4f} | "
                   f"{100 * r['share_off']:.2f} % | {iso} |")
    return "\n".join(out)


def main():
    run_dir, doc, image_dir = sys.argv[1], sys.argv[2], sys.argv[3]
    rows = read_rows(os.path.join(run_dir, "accuracy.csv"))
    counted_at = join_instructions(rows, os.path.join(run_dir, "instructions.csv"))
    os.makedirs(image_dir, exist_ok=True)
    meta = open(os.path.join(run_dir, "run.txt")).read().strip() if os.path.exists(os.path.join(run_dir, "run.txt")) else ""
    scenes = []
    for r in rows:
        if r["scene"] not in scenes:
            scenes.append(r["scene"])

    rel = os.path.relpath(image_dir, os.path.dirname(os.path.abspath(doc)))
    body = ["<!-- generated by tools/accuracy-report from `vkray bench accuracy`; do not edit below -->", "",
            "## The run", "", "```", meta, "```", "",
            "Time is the median GPU trace time (timestamp queries) of the timed runs, which are interleaved (run "
            "r of every point of a scene before run r+1 of any); *min–max* is their range, and the error bars of "
            "the plots draw it. `× baseline` divides by the scene's own settings at 1 spp; **≈** marks a point "
            "whose range overlaps the baseline's: its difference in time is within the noise. " +
            (f"*JIT instr.* is the number of instructions the code lavapipe compiled executed for one render at "
             f"{counted_at} (callgrind, `tools/accuracy-report --count-instructions`): the same on every run, so "
             f"it ranks points whose times overlap. " if counted_at else
             "Executed-instruction counts (a cost without noise) are not in this run: "
             "`tools/accuracy-report --count-instructions` adds them. ") +
            "*spp mean* is the samples per pixel a noise threshold or time limit took (their error is the "
            "median run's, with its min–max for a time limit, whose samples vary run by run). RMSE, PSNR (peak 1) and max abs are in linear RGB against the "
            "reference; *pixels off* is the share of pixels with a channel more than 1/255 away after sRGB "
            "encoding. At 1 spp every image shares the aliasing of the reference's many samples, so the last two "
            "columns compare 1-spp points with the reference's own 1-spp image: that is the error of the knob "
            "alone.", ""]
    combined = []
    for name in scenes:
        srows = [r for r in rows if r["scene"] == name]
        base = next((r for r in srows if r["knob"] == "baseline"), srows[0])
        plot = os.path.join(image_dir, f"accuracy-{name}.png")
        front = plot_scene(name, srows, plot)
        combined.append((name, srows))
        pairs, same = within_noise(srows)
        size = f"{base['width']}×{base['height']}, {base['runs']} interleaved runs per point"
        body += [f"## {name}", "", f"![error against time, {name}]({rel}/accuracy-{name}.png)", "",
                 f"{size}. Pareto front (fastest point for each level of error, by median time): " +
                 ", ".join(f"{p[2]} ({p[0]:.1f} ms, RMSE {p[1]:.4f})" for p in front) + ".", "",
                 "Within noise (overlapping min–max times): between neighbours, " +
                 (", ".join(pairs) if pairs else "none") + "; against the baseline, " +
                 (", ".join(same) if same else "none") + ".", "",
                 table(srows, base), ""]
        maps = sorted(f for f in os.listdir(run_dir) if f.startswith(name + "-error-") and f.endswith(".png"))
        if maps:
            body += ["Where the error is (|error| per pixel, dark blue 0 → yellow → red ≥ 0.05; 1-spp points "
                     "against the 1-spp reference):", "", "| " + " | ".join(m[len(name) + 7:-4] for m in maps) + " |",
                     "|" + "---|" * len(maps)]
            cells = []
            for m in maps:
                shutil.copy(os.path.join(run_dir, m), os.path.join(image_dir, m))
                cells.append(f"![]({rel}/{m})")
            body += ["| " + " | ".join(cells) + " |", ""]

    # The README's plot: every scene side by side.
    fig, axes = plt.subplots(1, len(combined), figsize=(5.2 * len(combined), 4.2), dpi=100, squeeze=False)
    for ax, (name, srows) in zip(axes[0], combined):
        pts = []
        for r in srows:
            if r["knob"] == "reference":
                continue
            color, marker = KNOB_STYLE.get(r["knob"], ("gray", "."))
            spread(ax, r, max(r["rmse"], 1e-6), color)
            ax.scatter(r["trace_ms"], max(r["rmse"], 1e-6), c=color, marker=marker, s=28, label=r["knob"], zorder=3)
            pts.append((r["trace_ms"], max(r["rmse"], 1e-6), r["knob"]))
        front = pareto(pts)
        ax.plot([p[0] for p in front], [p[1] for p in front], "k--", lw=1, zorder=2)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_title(name)
        ax.set_xlabel("GPU time (ms)")
        ax.grid(True, which="both", alpha=0.25)
    axes[0][0].set_ylabel("RMSE vs reference")
    handles, labels = axes[0][0].get_legend_handles_labels()
    seen = {}
    for h, l in zip(handles, labels):
        seen.setdefault(l, h)
    fig.legend(seen.values(), seen.keys(), loc="lower center", ncol=len(seen), fontsize=8)
    fig.tight_layout(rect=(0, 0.08, 1, 1))
    fig.savefig(os.path.join(image_dir, "accuracy.png"))
    plt.close(fig)

    reading = "<!-- reading -->\n(Write the reading of the results here.)\n<!-- /reading -->"
    if os.path.exists(doc):
        text = open(doc).read()
        a, b = text.find("<!-- reading -->"), text.find("<!-- /reading -->")
        if a >= 0 and b > a:
            reading = text[a:b + len("<!-- /reading -->")]
    header = ["# What accuracy costs in time", "",
              "Regenerate everything below the reading with `tools/accuracy-report --count-instructions` on an "
              "otherwise idle machine (it runs `build/vkray bench accuracy --out build/accuracy`, then the same "
              "points once each under callgrind for their instruction counts, then this script; without "
              "`--count-instructions` it skips the counts).", "", reading, ""]
    with open(doc, "w") as f:
        f.write("\n".join(header + body) + "\n")
    print(f"wrote {doc} and plots in {image_dir}")


if __name__ == "__main__":
    main()
