"""``mzc diff A B``: how far surface B is from surface A."""

import json

import click

from mzc.cli.options import float32_option, plain_option, zgrid_body
from mzc.limits import MAX_SAMPLES


@click.command(help="""Compare two surfaces (meshes or mzc files, any mix).

First the whole-surface distance: the symmetric point-to-surface distance (RMS, mean,
Hausdorff, then each direction) on area-weighted samples of every triangle, in the
grid's units when a side knows them. Then the grid statistics (grid_*): both surfaces
sampled on one common grid over A's extent (A's own nodes when A is a z-grid, else
1/1000 of A's longest side; --d1/--d2 override, in metres when A is a geographic grid,
which is compared in metres about its centre, never in degrees) and compared along its node lines (in
z, or along the rays of a central grid) over the nodes valid in both: RMSE, max and mean
absolute error, R^2 = 1 - SSE/SST, the 50/95/99th percentiles of |B - A| and the node
count; they grow on steep walls, where a small move of the surface is a long way along
a node line. All are printed unless some grid statistics are chosen, which leaves the
whole-surface distance out unless --surface asks for it; --no-surface leaves it out
(not for central or multi-chart grids, which are compared in space).
--heightfield adds the same distance over A's height-field part (triangles facing
within 60 degrees of +z and seen from +z, and the samples of B nearest to them), the
part a z-grid can represent; the benchmarks report both. With a point cloud on either
side, the distances of its points to the other side's surface are reported instead, the
direction on the first line.""")
@click.argument("a", metavar="A")
@click.argument("b", metavar="B")
@click.option("--rmse", is_flag=True, help="Root mean square of B - A.")
@click.option("--max", "max_", is_flag=True, help="Largest |B - A|.")
@click.option("--mean", is_flag=True, help="Mean |B - A| (and the signed bias).")
@click.option("--r2", is_flag=True, help="R^2 = 1 - SSE/SST.")
@click.option("--percentiles", is_flag=True, help="50th, 95th and 99th percentiles of |B - A|.")
@click.option("--count", is_flag=True, help="Number of nodes compared.")
@click.option("--surface/--no-surface", default=None,
              help="The symmetric point-to-surface distance [default: on, unless grid statistics are chosen].")
@click.option("--heightfield", is_flag=True,
              help="Also the point-to-surface distance over A's height-field part (implies --surface).")
@click.option("--samples", default=100_000, show_default=True, type=click.IntRange(100, MAX_SAMPLES),
              help="Samples per surface for --surface.")
@click.option("--seed", default=0, show_default=True, type=click.IntRange(0, 2**63 - 1),
              help="Random seed of the --surface samples.")
@click.option("--d1", type=click.FloatRange(min=0, min_open=True),
              help="Row spacing of the common grid, in A's units; in metres for a geographic grid (lon/lat).")
@click.option("--d2", type=click.FloatRange(min=0, min_open=True),
              help="Column spacing of the common grid, in A's units; in metres for a geographic grid (lon/lat).")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object instead of text lines.")
@click.option("--error-grid", metavar="FILE", help="Write the error surface B - A as a z-grid.")
@plain_option
@float32_option
@click.option("--plot", metavar="FILE.png",
              help="Write the quality plots: the error map over a hillshade, the histogram of the whole-surface "
                   "distance, residuals and normal probability.")
def command(a, b, rmse, max_, mean, r2, percentiles, count, surface, heightfield, samples, seed, d1, d2,
            as_json, error_grid, plain, float32, plot):
    from mzc.api import as_meshes
    from mzc.errors import MzcError, about
    from mzc.measure import STATISTICS, compare_surfaces
    from mzc.streams import check_distinct, check_not_input

    body = zgrid_body(plain, float32)
    check_distinct({"--error-grid": error_grid, "--plot": plot})
    for output in (error_grid, plot):
        if output:
            check_not_input(output, a, b)
    first, second = as_meshes(a, b)
    if (error_grid or plot) and (first.is_point_cloud or second.is_point_cloud):
        raise MzcError("--error-grid and --plot need two surfaces, not a point cloud", field="diff")
    chosen = [name for name, on in zip(STATISTICS, (rmse, max_, mean, r2, percentiles, count)) if on]
    with about(f"{a} vs {b}", f"comparing them ({samples} samples per surface)" if surface is not False
               else "comparing them"):
        result = compare_surfaces(first, second, chosen, surface, heightfield, samples, seed, d1, d2, names=(a, b))
    write_results(result, error_grid, body, plot)
    click.echo(json.dumps(result.report, indent=2) if as_json else format_report(result.report))


def format_report(report):
    """One ``name value`` line per figure, the whole-surface distances first (mzc.measure)."""
    return "\n".join(f"{name} {value:.6g}" if isinstance(value, float) else f"{name} {value}"
                     for name, value in report.items())


def write_results(result, error_grid, body, plot):
    """Write the error grid (its body as ``body``, options.zgrid_body, says) and the quality plots
    that were asked for: both are made in memory and staged before either is published, so a
    failing one leaves neither."""
    from mzc.formats import zgrid
    from mzc.streams import write_outputs

    outputs = []
    if error_grid:
        outputs.append((error_grid, zgrid.write(result.errors, **body)))
    if plot:
        outputs.append((plot, plot_png(result)))
    write_outputs(*outputs)


def plot_png(result):
    """The PNG of the quality panels (mzc.plots) of this comparison (a mzc.measure.Comparison)."""
    from mzc.plots import error_png

    reference, errors = result.reference, result.errors
    return error_png(errors.z, reference.z + errors.z, reference.xs(), reference.ys(), result.stats,
                     units=reference.units, distances=result.distances)
