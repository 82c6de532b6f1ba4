#!/usr/bin/env python3
"""Plots a `vkray bench --json` report: relative depth error (p99) against median time per frame,
log-log, one panel per scene, one colour per variant; rows on the Pareto front (time, hit/miss
flips, depth p99, normal p99) are ringed in black and joined by a dashed line.

vkray runs this itself for `vkray bench --plot OUT.png`; by hand:
    python3 engine/bench/bench_plot.py BENCH.json OUT.png
Needs Debian's python3-matplotlib.
"""
import json
import math
import sys

import matplotlib

matplotlib.use("Agg")  # files only, no display needed
import matplotlib.pyplot as plt  # noqa: E402


def main():
    if len(sys.argv) != 3:
        sys.exit("usage: bench_plot.py BENCH.json OUT.png")
    with open(sys.argv[1]) as file:
        report = json.load(file)
    scenes = [scene for scene in report["scenes"] if scene["rows"]]
    if not scenes:
        sys.exit(f"{sys.argv[1]}: no rows to plot")

    variants = []
    for scene in scenes:
        for row in scene["rows"]:
            if row["variant"] not in variants:
                variants.append(row["variant"])
    palette = plt.get_cmap("tab20")
    colour = {name: palette(k % 20) for k, name in enumerate(variants)}

    columns = min(3, len(scenes))
    rows = math.ceil(len(scenes) / columns)
    figure, axes = plt.subplots(rows, columns, figsize=(5.2 * columns, 4.2 * rows), squeeze=False)
    for axis, scene in zip(axes.flat, scenes):
        # Exact rows (error 0) sit on a floor a decade below the smallest error, marked as such.
        errors = [row["depth_rel_p99"] for row in scene["rows"] if row["depth_rel_p99"] > 0]
        floor = min(errors) / 10 if errors else 1e-9
        for row in scene["rows"]:
            error = max(row["depth_rel_p99"], floor)
            axis.scatter(row["gpu_median_ms"], error, color=colour[row["variant"]], s=60, zorder=3,
                         marker="o" if row["on_gpu"] else "s",
                         edgecolors="black" if row["pareto"] else "none", linewidths=1.5)
            if row["hit_mismatches"] > 0:
                axis.annotate(f'{row["hit_mismatches"]} flips', (row["gpu_median_ms"], error), fontsize=7,
                              xytext=(4, 4), textcoords="offset points")
        front = sorted((row for row in scene["rows"] if row["pareto"]), key=lambda row: row["gpu_median_ms"])
        axis.plot([row["gpu_median_ms"] for row in front], [max(row["depth_rel_p99"], floor) for row in front],
                  color="black", linestyle="--", linewidth=0.8, zorder=2)
        if len(errors) < len(scene["rows"]):
            axis.axhline(floor, color="grey", linewidth=0.5, linestyle=":")
        axis.set_xscale("log")
        axis.set_yscale("log")
        axis.set_title(f'{scene["name"]} ({scene["width"]}x{scene["height"]})', fontsize=10)
        axis.set_xlabel("median time per frame (ms)")
        axis.set_ylabel("relative depth error, p99")
        axis.grid(True, which="both", linewidth=0.3, alpha=0.5)
    for axis in axes.flat[len(scenes):]:
        axis.set_visible(False)

    handles = [plt.Line2D([], [], marker="o", linestyle="", color=colour[name], label=name) for name in variants]
    figure.legend(handles=handles, loc="lower center", ncol=min(6, len(variants)), fontsize=8, frameon=False)
    device = report["device"]
    figure.suptitle(f'vkray {report["vkray_version"]} ({report["git_commit"][:10]}) on {device["name"]}, '
                    f'{device["driver"]}; circles: GPU, squares: CPU (Embree); ringed: Pareto front; '
                    f'dotted: error 0', fontsize=9)
    figure.tight_layout(rect=(0, 0.06, 1, 0.96))
    figure.savefig(sys.argv[2], dpi=100)


if __name__ == "__main__":
    main()
