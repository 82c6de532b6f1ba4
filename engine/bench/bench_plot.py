#!/usr/bin/env python3
"""Plots a `vkray bench --json` report: for each scene, relative depth error (p99) and normal error
(p99, degrees) against time per frame, log-log, one colour per variant. A point is the median, its
horizontal bar the spread from the fastest to the slowest frame; rows on the Pareto front (time,
hit/miss flips, depth p99, normal p99) are ringed in black and joined by a dashed line; rows with
hit/miss flips are listed, with their count, in the depth panel's corner.

vkray runs this itself for `vkray bench --plot OUT.png`; by hand:
    python3 engine/bench/bench_plot.py BENCH.json OUT.png
Needs Debian's python3-matplotlib.
"""
import json
import math
import sys
import textwrap

import matplotlib

matplotlib.use("Agg")  # files only, no display needed
import matplotlib.pyplot as plt  # noqa: E402

# Each scene's two panels, one above the other: (JSON field, axis label).
ERRORS = (("depth_rel_p99", "relative depth error, p99"), ("normal_deg_p99", "normal error, p99 (degrees)"))
PANEL_INCHES = (5.2, 3.6)
TITLE_POINTS = 9
LEGEND_POINTS = 8


def variants_of(scenes):
    names = []
    for scene in scenes:
        for row in scene["rows"]:
            if row["variant"] not in names:
                names.append(row["variant"])
    return names


def draw_panel(axis, scene, field, label, colour, flips_listed):
    # Exact rows (error 0) sit on a floor a decade below the smallest error, marked as such.
    errors = [row[field] for row in scene["rows"] if row[field] > 0]
    floor = min(errors) / 10 if errors else 1e-9
    for row in scene["rows"]:
        error = max(row[field], floor)
        median = row["gpu_median_ms"]
        spread = [[median - row.get("gpu_min_ms", median)], [row.get("gpu_max_ms", median) - median]]
        axis.errorbar(median, error, xerr=spread, color=colour[row["variant"]], linewidth=1, zorder=2)
        axis.scatter(median, error, color=colour[row["variant"]], s=60, zorder=3, marker="o" if row["on_gpu"] else "s",
                     edgecolors="black" if row["pareto"] else "none", linewidths=1.5)
    front = sorted((row for row in scene["rows"] if row["pareto"]), key=lambda row: row["gpu_median_ms"])
    axis.plot([row["gpu_median_ms"] for row in front], [max(row[field], floor) for row in front], color="black",
              linestyle="--", linewidth=0.8, zorder=1)
    if len(errors) < len(scene["rows"]):
        axis.axhline(floor, color="grey", linewidth=0.5, linestyle=":")
    if flips_listed:
        # One block of text, not a label at each point: rows with the same error and time would
        # print their labels over each other.
        flips = [f'{row["variant"]}: {row["hit_mismatches"]} flips' for row in scene["rows"] if row["hit_mismatches"]]
        if flips:
            axis.text(0.02, 0.97, "\n".join(flips), transform=axis.transAxes, fontsize=7, va="top", ha="left",
                      bbox={"facecolor": "white", "alpha": 0.8, "edgecolor": "grey", "linewidth": 0.5}, zorder=4)
    axis.set_xscale("log")
    axis.set_yscale("log")
    axis.set_xlabel("time per frame (ms): median, bar from fastest to slowest", fontsize=8)
    axis.set_ylabel(label, fontsize=8)
    axis.grid(True, which="both", linewidth=0.3, alpha=0.5)


def bench_figure(report):
    """The figure of a report (a dict as `vkray bench --json` writes it)."""
    scenes = [scene for scene in report["scenes"] if scene["rows"]]
    if not scenes:
        raise ValueError("no rows to plot")
    variants = variants_of(scenes)
    palette = plt.get_cmap("tab20")
    colour = {name: palette(k % 20) for k, name in enumerate(variants)}

    columns = min(3, len(scenes))
    rows = math.ceil(len(scenes) / columns) * len(ERRORS)
    width = PANEL_INCHES[0] * columns
    # As many legend columns as entries of the longest name fit across (a marker and a gap, then
    # about 0.6 em a character).
    entry_points = 30 + 0.6 * LEGEND_POINTS * max(len(name) for name in variants)
    legend_columns = max(1, min(len(variants), int(width * 72 * 0.95 // entry_points)))
    legend_rows = math.ceil(len(variants) / legend_columns)
    # The title wraps to the figure's width (at about 0.55 em a character); the legend gets its own
    # band below the panels, so neither is clipped nor covers an axis label.
    title = (f'vkray {report["vkray_version"]} ({report["git_commit"][:10]}) on {report["device"]["name"]}, '
             f'{report["device"]["driver"]}; circles: GPU, squares: CPU (Embree); ringed: Pareto front; '
             f'dotted: error 0')
    title = textwrap.fill(title, width=int(width * 72 / (0.55 * TITLE_POINTS)))
    title_inches = (title.count("\n") + 1) * TITLE_POINTS * 1.4 / 72 + 0.15
    legend_inches = legend_rows * LEGEND_POINTS * 2.0 / 72 + 0.15
    height = PANEL_INCHES[1] * rows + title_inches + legend_inches
    figure, axes = plt.subplots(rows, columns, figsize=(width, height), squeeze=False)
    for k, scene in enumerate(scenes):
        band, column = divmod(k, columns)
        for e, (field, label) in enumerate(ERRORS):
            axis = axes[band * len(ERRORS) + e][column]
            draw_panel(axis, scene, field, label, colour, flips_listed=e == 0)
            if e == 0:
                axis.set_title(f'{scene["name"]} ({scene["width"]}x{scene["height"]})', fontsize=10)
    for k in range(len(scenes), math.ceil(len(scenes) / columns) * columns):
        band, column = divmod(k, columns)
        for e in range(len(ERRORS)):
            axes[band * len(ERRORS) + e][column].set_visible(False)

    handles = [plt.Line2D([], [], marker="o", linestyle="", color=colour[name], label=name) for name in variants]
    figure.legend(handles=handles, loc="lower center", ncol=legend_columns,
                  fontsize=LEGEND_POINTS, frameon=False)
    figure.suptitle(title, fontsize=TITLE_POINTS)
    figure.tight_layout(rect=(0, legend_inches / height, 1, 1 - title_inches / height))
    return figure


def main():
    if len(sys.argv) != 3:
        sys.exit("usage: bench_plot.py BENCH.json OUT.png")
    with open(sys.argv[1]) as file:
        report = json.load(file)
    try:
        figure = bench_figure(report)
    except ValueError as error:
        sys.exit(f"{sys.argv[1]}: {error}")
    figure.savefig(sys.argv[2], dpi=100)


if __name__ == "__main__":
    main()
