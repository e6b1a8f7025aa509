"""mzc.plots: the quality panels of a comparison in one PNG."""

import numpy as np
import pytest

from mzc.errors import MzcError
from mzc.plots import SCATTER_POINTS, error_figure, error_png
from mzc.streams import write_output

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def example(rows=60, cols=80):
    """(error, predicted, xs, ys, stats) of a small comparison with a hole."""
    rng = np.random.default_rng(0)
    ys, xs = np.arange(rows) * 0.75, 10 + np.arange(cols) * 0.25
    predicted = np.sin(xs[None, :]) + ys[:, None] / 10
    error = rng.normal(scale=0.1, size=(rows, cols))
    error[20:30, 30:40] = np.nan
    stats = {"rmse": 0.1, "max": 0.4, "r2": 0.99, "count": int(np.isfinite(error).sum())}
    return error, predicted, xs, ys, stats


def error_plot(path, *panels):
    """The PNG written to ``path`` as mzc diff --plot writes it (mzc.streams)."""
    write_output(path, error_png(*panels))


def test_png_is_written_and_sensible(tmp_path):
    path = tmp_path / "quality.png"
    error_plot(path, *example())
    data = path.read_bytes()
    assert data.startswith(PNG_SIGNATURE)
    width, height = int.from_bytes(data[16:20], "big"), int.from_bytes(data[20:24], "big")
    assert 1000 <= width <= 3000 and 300 <= height <= 1500
    assert 20_000 < len(data) < 2_000_000
    assert [p.name for p in tmp_path.iterdir()] == ["quality.png"]   # no temporary left


def test_figure_has_four_panels_a_colour_bar_and_the_summary_in_units():
    import matplotlib.pyplot as pyplot

    error, predicted, xs, ys, stats = example()
    distances = (np.abs(np.random.default_rng(1).normal(scale=0.05, size=1000)), np.full(500, 0.02))
    figure = error_figure(error, predicted, xs, ys, stats, units="mm", distances=distances)
    try:
        panels = [axes for axes in figure.axes if axes.get_label() != "<colorbar>"]
        assert len(panels) == 4 and len(figure.axes) == 5
        surface, histogram, scatter, probability = panels
        assert surface.get_xlim() == pytest.approx((xs[0] - 0.125, xs[-1] + 0.125))
        assert surface.get_ylim() == pytest.approx((ys[0] - 0.375, ys[-1] + 0.375))
        assert len(surface.collections) == 2   # the hillshade, and the error over it
        assert "mm" in surface.get_xlabel() and "mm" in figure.axes[-1].get_ylabel()
        assert sum(patch.get_height() for patch in histogram.patches) == 1500   # every sample, both ways
        assert "Whole-surface" in histogram.get_title() and "mm" in histogram.get_xlabel()
        assert len(scatter.collections[0].get_offsets()) == stats["count"]
        assert len(probability.lines[0].get_xdata()) == stats["count"]
        title = figure.get_suptitle()
        rms = np.sqrt(np.mean(np.concatenate(distances) ** 2))
        assert title.startswith(f"whole surface: RMS {rms:.4g} (mm)")
        assert "RMSE 0.1" in title and "R² 0.99" in title and f"n = {stats['count']}" in title
    finally:
        pyplot.close(figure)


def test_a_few_spikes_do_not_set_the_residual_axes():
    import matplotlib.pyplot as pyplot

    error, predicted, xs, ys, stats = example()
    error[0, :5] = 40.0   # a wall's spikes, as on a steep side of a face
    figure = error_figure(error, predicted, xs, ys, stats)
    try:
        surface, histogram, scatter, probability = [a for a in figure.axes if a.get_label() != "<colorbar>"]
        assert scatter.get_ylim()[1] < 1 and probability.get_ylim()[1] < 1
        assert "beyond the axis" in scatter.get_title() and "node lines" in histogram.get_title()   # no distances
    finally:
        pyplot.close(figure)


def test_scatter_is_subsampled_on_large_grids():
    import matplotlib.pyplot as pyplot

    error, predicted, xs, ys, stats = example(rows=300, cols=400)
    figure = error_figure(error, predicted, xs, ys, stats)
    try:
        scatter = [a for a in figure.axes if a.get_label() != "<colorbar>"][2]
        assert len(scatter.collections[0].get_offsets()) == SCATTER_POINTS
    finally:
        pyplot.close(figure)


def test_failing_write_leaves_no_file(tmp_path):
    with pytest.raises(MzcError):
        error_plot(tmp_path / "missing" / "quality.png", *example())
    assert not (tmp_path / "missing").exists()


def test_failing_render_leaves_no_file(tmp_path, monkeypatch):
    import matplotlib.figure

    def broken(*args, **kwargs):
        raise OSError("disk full")

    monkeypatch.setattr(matplotlib.figure.Figure, "savefig", broken)
    path = tmp_path / "quality.png"
    with pytest.raises(OSError):
        error_plot(path, *example())
    assert list(tmp_path.iterdir()) == []
