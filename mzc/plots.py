"""The quality pictures of a comparison in one PNG, for a person choosing a setting: the error
map over the surface's hillshade, the histogram of the whole-surface distance, and the
thesis's residual and normal probability plots (§6.4), every axis in the surface's units.

matplotlib runs headless (Agg) and is imported only here, so commands that do not plot
stay fast.
"""

import io

import numpy as np

SCATTER_POINTS = 30_000   # residual panels subsample to this many points: fast, same picture
DPI = 110
COLOUR_PERCENTILE = 99.5  # the colour and residual ranges: a few spikes on steep walls do not flatten the rest
HISTOGRAM_BINS = 60


def error_png(error, predicted, xs, ys, stats, units=None, distances=None):
    """The bytes of a PNG of the four quality panels of B - A.

    ``error`` and ``predicted`` are (rows, cols) grids (NaN = invalid) of B - A and of B;
    ``xs``/``ys`` are the column/row coordinates in model units; ``stats`` holds the
    summary numbers (rmse, max, r2, count) shown in the title; ``distances`` the whole-surface
    distances sampled each way (``mzc.measure.Comparison.distances``), or None.
    """
    figure = error_figure(error, predicted, xs, ys, stats, units, distances)
    try:
        buffer = io.BytesIO()
        figure.savefig(buffer, format="png", dpi=DPI)
        return buffer.getvalue()
    finally:
        headless_pyplot().close(figure)


def error_figure(error, predicted, xs, ys, stats, units=None, distances=None):
    """The matplotlib figure behind ``error_png``: four axes plus the error map's colour bar."""
    pyplot = headless_pyplot()
    error, predicted = np.asarray(error, dtype=float), np.asarray(predicted, dtype=float)
    unit = f" ({units})" if units else ""
    figure, axes = pyplot.subplots(2, 2, figsize=(14, 10), layout="constrained")
    (surface, histogram), (scatter, probability) = axes
    draw_error_map(figure, surface, error, predicted - error, np.asarray(xs), np.asarray(ys), unit)
    draw_distances(histogram, distances, error, unit)
    residual, fitted = sampled_residuals(error, predicted)
    draw_residuals(scatter, residual, fitted, unit)
    draw_probability(probability, residual, unit)
    figure.suptitle(summary_title(stats, unit, distances))
    return figure


def headless_pyplot():
    """matplotlib.pyplot on the Agg backend: no display needed, nothing pops up."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as pyplot

    return pyplot


def draw_error_map(figure, axes, error, reference, xs, ys, unit):
    """Error surface B - A as a colour map symmetric about 0 over the hillshade of A (the
    shape the errors sit on: a ridge, a wall, an eye socket), axes and colour bar in model units.

    The colour range is the COLOUR_PERCENTILE of |B - A|, so a few spikes on steep walls
    do not wash out the error pattern over the rest of the surface.
    """
    axes.pcolormesh(xs, ys, np.ma.masked_invalid(hillshade(reference, xs, ys)), cmap="gray", vmin=0, vmax=1,
                    shading="nearest")
    bound = robust_bound(error)
    image = axes.pcolormesh(xs, ys, np.ma.masked_invalid(error), cmap="RdBu_r", vmin=-bound, vmax=bound,
                            shading="nearest", alpha=0.6)
    axes.set_aspect("equal")
    axes.set(title="Error B - A over A's hillshade", xlabel=f"x{unit}", ylabel=f"y{unit}")
    figure.colorbar(image, ax=axes, label=f"B - A{unit}", extend="both")


def hillshade(heights, xs, ys):
    """The hillshade (0 dark .. 1 lit, light from the north-west at 45 degrees) of a grid of
    heights at columns ``xs`` and rows ``ys``; NaN where the heights are."""
    from matplotlib.colors import LightSource

    valid = np.isfinite(heights)
    if valid.sum() < 2:
        return np.full(heights.shape, np.nan)
    filled = np.where(valid, heights, np.mean(heights[valid]))
    spacing = [abs(float(np.diff(axis[:2])[0])) if len(axis) > 1 else 1.0 for axis in (xs, ys)]
    shade = LightSource(azdeg=315, altdeg=45).hillshade(filled, dx=spacing[0] or 1.0, dy=spacing[1] or 1.0)
    return np.where(valid, shade, np.nan)


def robust_bound(values):
    """The COLOUR_PERCENTILE of |values| over the finite ones (1 when there are none or it is 0)."""
    finite = np.abs(values[np.isfinite(values)])
    bound = float(np.percentile(finite, COLOUR_PERCENTILE)) if finite.size else 0.0
    return bound if bound > 0 else 1.0


def draw_distances(axes, distances, error, unit):
    """The histogram of the whole-surface distance, both directions' samples together, with its
    RMS and largest value marked; without one measured, that of |B - A| along the node lines."""
    if distances is not None:
        values, title = np.concatenate(distances), "Whole-surface distance (both directions)"
    else:
        values, title = np.abs(error[np.isfinite(error)]), "|B - A| along the node lines"
    if values.size:
        top = float(np.percentile(values, 99.9)) or 1.0
        axes.hist(np.minimum(values, top), bins=HISTOGRAM_BINS, range=(0, top), color="tab:blue")
        rms = float(np.sqrt(np.mean(values ** 2)))
        axes.axvline(rms, color="black", linewidth=1.2, label=f"RMS {rms:.4g}{unit}")
        axes.axvline(top, color="tab:red", linewidth=1.0, linestyle="--",
                     label=f"99.9th percentile {top:.4g}{unit} (largest {float(values.max()):.4g})")
        axes.legend(loc="upper right")
        axes.set_yscale("log")
    axes.set(title=title, xlabel=f"distance{unit}", ylabel="samples")


def sampled_residuals(error, predicted):
    """(residual, predicted) over nodes valid in both, an even subsample of at most SCATTER_POINTS."""
    both = np.isfinite(error) & np.isfinite(predicted)
    residual, fitted = error[both], predicted[both]
    if residual.size > SCATTER_POINTS:
        keep = np.random.default_rng(0).choice(residual.size, SCATTER_POINTS, replace=False)
        residual, fitted = residual[keep], fitted[keep]
    return residual, fitted


def draw_residuals(axes, residual, fitted, unit):
    """Residuals against predicted heights: structure here means the error depends on the shape.
    The residual axis spans the COLOUR_PERCENTILE of |residual|, the title counting those beyond."""
    axes.scatter(fitted, residual, s=2, alpha=0.4, linewidths=0)
    axes.axhline(0.0, color="black", linewidth=0.8)
    bound = robust_bound(residual)
    beyond = int((np.abs(residual) > bound).sum())
    axes.set_ylim(-1.05 * bound, 1.05 * bound)
    note = f" ({beyond} of {residual.size} beyond the axis)" if beyond else ""
    axes.set(title=f"Residuals vs predicted{note}", xlabel=f"predicted z{unit}", ylabel=f"residual{unit}")


def draw_probability(axes, residual, unit):
    """Normal probability plot of the residuals: a straight line means Gaussian error."""
    from scipy import stats

    if residual.size >= 2:
        stats.probplot(residual, dist="norm", plot=axes)
        bound = robust_bound(residual)
        axes.set_ylim(-1.05 * bound, 1.05 * bound)   # as the residual panel: the tails' spikes off the axis
    axes.set(title="Normal probability plot", xlabel="theoretical quantiles", ylabel=f"ordered residuals{unit}")


def summary_title(stats, unit, distances=None):
    """One line of the summary numbers that are present: the whole-surface distance first,
    then the statistics along the node lines."""
    parts = []
    if distances is not None and sum(len(side) for side in distances):
        values = np.concatenate(distances)
        parts.append(f"whole surface: RMS {float(np.sqrt(np.mean(values ** 2))):.4g}{unit}, "
                     f"Hausdorff {float(values.max()):.4g}{unit};  along node lines:")
    parts += [f"{label} {stats[key]:.4g}{unit if key in ('rmse', 'max') else ''}"
              for key, label in (("rmse", "RMSE"), ("max", "max |B - A|"), ("r2", "R²")) if key in stats]
    if "count" in stats:
        parts.append(f"n = {stats['count']}")
    return "   ".join(parts)
