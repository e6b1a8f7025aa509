"""The thesis's quality pictures (§6.4) in one PNG: error map, residuals, normal probability plot.

matplotlib runs headless (Agg) and is imported only here, so commands that do not plot
stay fast.
"""

import io

import numpy as np

SCATTER_POINTS = 30_000   # residual panels subsample to this many points: fast, same picture
DPI = 110
COLOUR_PERCENTILE = 99.5


def error_png(error, predicted, xs, ys, stats, units=None):
    """The bytes of a PNG of the three quality panels of B - A.

    ``error`` and ``predicted`` are (rows, cols) grids (NaN = invalid) of B - A and of B;
    ``xs``/``ys`` are the column/row coordinates in model units; ``stats`` holds the
    summary numbers (rmse, max, r2, count) shown in the title.
    """
    figure = error_figure(error, predicted, xs, ys, stats, units)
    try:
        buffer = io.BytesIO()
        figure.savefig(buffer, format="png", dpi=DPI)
        return buffer.getvalue()
    finally:
        headless_pyplot().close(figure)


def error_figure(error, predicted, xs, ys, stats, units=None):
    """The matplotlib figure behind ``error_png``: three axes plus the error map's colour bar."""
    pyplot = headless_pyplot()
    error, predicted = np.asarray(error, dtype=float), np.asarray(predicted, dtype=float)
    unit = f" ({units})" if units else ""
    figure, (surface, scatter, probability) = pyplot.subplots(1, 3, figsize=(16, 5), layout="constrained")
    draw_error_map(figure, surface, error, np.asarray(xs), np.asarray(ys), unit)
    residual, fitted = sampled_residuals(error, predicted)
    draw_residuals(scatter, residual, fitted, unit)
    draw_probability(probability, residual, unit)
    figure.suptitle(summary_title(stats, unit))
    return figure


def headless_pyplot():
    """matplotlib.pyplot on the Agg backend: no display needed, nothing pops up."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as pyplot

    return pyplot


def draw_error_map(figure, axes, error, xs, ys, unit):
    """Error surface B - A as a colour map symmetric about 0, axes and colour bar in model units.

    The colour range is the 99.5th percentile of |B - A|, so a few spikes on steep walls
    do not wash out the error pattern over the rest of the surface.
    """
    finite = np.abs(error[np.isfinite(error)])
    bound = float(np.percentile(finite, COLOUR_PERCENTILE)) if finite.size else 0.0
    bound = bound if bound > 0 else 1.0
    image = axes.pcolormesh(xs, ys, np.ma.masked_invalid(error), cmap="RdBu_r", vmin=-bound, vmax=bound,
                            shading="nearest")
    axes.set_aspect("equal")
    axes.set(title="Error surface B - A", xlabel=f"x{unit}", ylabel=f"y{unit}")
    figure.colorbar(image, ax=axes, label=f"B - A{unit}", extend="both")


def sampled_residuals(error, predicted):
    """(residual, predicted) over nodes valid in both, an even subsample of at most SCATTER_POINTS."""
    both = np.isfinite(error) & np.isfinite(predicted)
    residual, fitted = error[both], predicted[both]
    if residual.size > SCATTER_POINTS:
        keep = np.random.default_rng(0).choice(residual.size, SCATTER_POINTS, replace=False)
        residual, fitted = residual[keep], fitted[keep]
    return residual, fitted


def draw_residuals(axes, residual, fitted, unit):
    """Residuals against predicted heights: structure here means the error depends on the shape."""
    axes.scatter(fitted, residual, s=2, alpha=0.4, linewidths=0)
    axes.axhline(0.0, color="black", linewidth=0.8)
    axes.set(title="Residuals vs predicted", xlabel=f"predicted z{unit}", ylabel=f"residual{unit}")


def draw_probability(axes, residual, unit):
    """Normal probability plot of the residuals: a straight line means Gaussian error."""
    from scipy import stats

    if residual.size >= 2:
        stats.probplot(residual, dist="norm", plot=axes)
    axes.set(title="Normal probability plot", xlabel="theoretical quantiles", ylabel=f"ordered residuals{unit}")


def summary_title(stats, unit):
    """One line of the summary numbers that are present."""
    parts = [f"{label} {stats[key]:.4g}{unit if key in ('rmse', 'max') else ''}"
             for key, label in (("rmse", "RMSE"), ("max", "max |B - A|"), ("r2", "R²")) if key in stats]
    if "count" in stats:
        parts.append(f"n = {stats['count']}")
    return "   ".join(parts)
