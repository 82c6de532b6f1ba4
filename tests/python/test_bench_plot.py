"""The bench's plot (engine/bench/bench_plot.py) laid out whole: every text inside the figure, the
legend clear of every panel and its axis labels, the flip counts apart from each other, and a
depth and a normal panel for each scene. Drawn from reports made up to be hard to lay out: one
scene with a long device name and rows that share a point, and seven scenes."""
import importlib.util
import pathlib

import matplotlib
import pytest

matplotlib.use("Agg")

SCRIPT = pathlib.Path(__file__).parents[2] / "engine" / "bench" / "bench_plot.py"
spec = importlib.util.spec_from_file_location("bench_plot", SCRIPT)
bench_plot = importlib.util.module_from_spec(spec)
spec.loader.exec_module(bench_plot)


def row(variant, ms, flips=0, depth=1e-7, normal=1e-5, on_gpu=True, pareto=False):
    return {"variant": variant, "on_gpu": on_gpu, "gpu_median_ms": ms, "gpu_min_ms": 0.8 * ms, "gpu_max_ms": 1.5 * ms,
            "hit_mismatches": flips, "depth_rel_p99": depth, "normal_deg_p99": normal, "pareto": pareto}


def report(scenes):
    return {"vkray_version": "0.1.0", "git_commit": "0123456789abcdef",
            "device": {"name": "llvmpipe (LLVM 15.0.6, 256 bits) with a name as long as a real GPU's",
                       "driver": "llvmpipe Mesa 25.0.7-2~bpo12+1 (LLVM 15.0.6)"},
            "scenes": scenes}


def scene(name, rows):
    return {"name": name, "width": 1920, "height": 1080, "rows": rows}


def stiff_rows():
    # Three rows with one flip each at the same time and error (what printed "1 flips1 flips"), an
    # exact row, Embree, and enough variants for a legend of several lines.
    rows = [row("default", 10, pareto=True), row("naive", 10, flips=1, depth=1e-6), row("naive-sphere", 10, flips=1,
            depth=1e-6), row("moller-trumbore", 10, flips=1, depth=1e-6), row("float64", 40, depth=0, normal=0,
            pareto=True), row("embree-8", 12, on_gpu=False)]
    rows += [row(f"variant-{k}", 11 + k) for k in range(8)]
    return rows


def boxes_overlap(a, b):
    return a.x0 < b.x1 and b.x0 < a.x1 and a.y0 < b.y1 and b.y0 < a.y1


@pytest.mark.parametrize("scenes", [[scene("far-sphere-1e-04", stiff_rows())],
                                    [scene(f"scene-{k}", stiff_rows()) for k in range(7)]], ids=["one", "seven"])
def test_the_plot_is_laid_out_whole(scenes):
    figure = bench_plot.bench_figure(report(scenes))
    figure.canvas.draw()
    renderer = figure.canvas.get_renderer()
    page = figure.bbox
    panels = [axis for axis in figure.axes if axis.get_visible()]
    assert len(panels) == 2 * len(scenes)
    assert sum(axis.get_ylabel().startswith("relative depth") for axis in panels) == len(scenes)
    assert sum(axis.get_ylabel().startswith("normal error") for axis in panels) == len(scenes)

    texts = [figure._suptitle] + [text for legend in figure.legends for text in legend.get_texts()]
    for axis in panels:
        texts += [axis.title, axis.xaxis.label, axis.yaxis.label] + list(axis.texts)
    for text in texts:
        box = text.get_window_extent(renderer)
        assert page.x0 - 0.5 <= box.x0 and box.x1 <= page.x1 + 0.5, f"{text.get_text()!r} clipped left or right"
        assert page.y0 - 0.5 <= box.y0 and box.y1 <= page.y1 + 0.5, f"{text.get_text()!r} clipped at top or bottom"

    legend = figure.legends[0].get_window_extent(renderer)
    for axis in panels:
        assert not boxes_overlap(legend, axis.get_tightbbox(renderer)), "the legend covers a panel or its labels"
    title = figure._suptitle.get_window_extent(renderer)
    for axis in panels:
        assert not boxes_overlap(title, axis.get_tightbbox(renderer)), "the title covers a panel"

    for axis in panels:
        flips = [text for text in axis.texts if "flips" in text.get_text()]
        if axis.get_ylabel().startswith("relative depth"):
            assert len(flips) == 1 and flips[0].get_text().count("1 flips") == 3
        else:
            assert not flips
