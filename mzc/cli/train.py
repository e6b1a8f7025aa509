"""``mzc train FILES -o faces.mzp``: learn a shared prior from a collection of like surfaces."""

import click

prior_option = click.option("--prior", metavar="FILE",
                            help="A prior written by mzc train (a collection's mean surface on one lattice).")


@click.command(help="""Learn a shared prior from a collection of like surfaces (faces, say).

Cuts every mesh or point cloud on one lattice (their union's default grid, --d1 and --d2
when given, grown to cover them all), and writes their mean, a value at every node, as a
prior file (mzc-prior 1.0, spec/prior.md), named by the SHA-256 of its bytes. Then

\b
  mzc slice --prior faces.mzp a.ply | mzc encode --prior faces.mzp -o a.mzw2
  mzc decode --prior faces.mzp a.mzw2 -o a.zg

code a surface as its residual from the mean when that is smaller (else as a plain dwt2d
file, which needs no prior).""")
@click.argument("files", nargs=-1, required=True, metavar="FILES...")
@click.option("-o", "--output", required=True, metavar="FILE", help="Write the prior here (atomically).")
@click.option("--d1", type=click.FloatRange(0, min_open=True), metavar="F",
              help="Row spacing of the lattice [default: the surfaces' own].")
@click.option("--d2", type=click.FloatRange(0, min_open=True), metavar="F",
              help="Column spacing of the lattice [default: the surfaces' own, else d1].")
def command(files, output, d1, d2):
    from mzc.api import train
    from mzc.progress import step
    from mzc.streams import check_not_input, is_terminal, write_output

    if is_terminal(output):
        raise click.UsageError("a prior is binary: give -o FILE")
    for path in files:
        check_not_input(output, path)
    with step(f"training a prior on {len(files)} surfaces"):
        prior = train(list(files), d1=d1, d2=d2)
    write_output(output, prior.data)
