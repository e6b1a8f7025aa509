"""The ``mzc`` command group.

Subcommands live in ``mzc/cli/`` and are imported only when invoked, so ``mzc
--help`` stays fast. Any MzcError becomes one line on stderr and exit status 1; click
usage errors exit 2.
"""

import importlib
import os
import re
import sys
import warnings

import click

from mzc import __version__, progress
from mzc.errors import MzcError, MzcWarning

COMMANDS = {
    "slice": "Cut a mesh or point cloud into a z-grid.",
    "encode": "Compress a z-grid.",
    "decode": "Decompress an mzc file into a z-grid.",
    "densify": "Insert rows between the planes of a z-grid (the PDE step).",
    "triangulate": "Turn a z-grid into a triangle mesh.",
    "diff": "Compare two surfaces (meshes or z-grids).",
    "info": "Describe any mzc file.",
    "sample": "Write a built-in sample surface.",
    "train": "Learn a shared prior from a collection of like surfaces.",
    "batch": "Slice and encode (or decode) whole archives, on Dask.",
}


class LazyGroup(click.Group):
    """A click group that imports a subcommand's module only when it runs (``encode`` is built
    then, from the codecs registered at that moment)."""

    def list_commands(self, ctx):
        return list(COMMANDS)

    def get_command(self, ctx, name):
        if name not in COMMANDS:
            return None
        module = importlib.import_module(f"mzc.cli.{name}")
        return module.build_command() if hasattr(module, "build_command") else module.command

    def format_commands(self, ctx, formatter):
        rows = [(name, summary) for name, summary in COMMANDS.items()]
        with formatter.section("Commands"):
            formatter.write_dl(rows)


@click.group(cls=LazyGroup, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, prog_name="mzc")
def group():
    """Compress 3D surface patches into small files and rebuild dense meshes.

    Every command reads a file argument or stdin ('-' or nothing) and writes '-o FILE'
    or stdout, so they chain in pipelines:

    \b
      mzc slice a.obj | mzc encode --dwt2d --rmse 0.05 > a.mzw2
      mzc decode < a.mzw2 | mzc densify -n 3 | mzc triangulate -o b.ply
    """


def main():
    """Entry point: run the group, turning MzcError and other failures into one line on stderr."""
    one_blas_thread()
    reuse_freed_memory()
    # numpy's RuntimeWarnings and the libraries' own warnings are not for the user: mzc checks its
    # results itself (non-finite heights and coefficients are errors); only its own warnings show
    warnings.simplefilter("ignore")
    warnings.simplefilter("once", MzcWarning)
    warnings.showwarning = show_warning
    progress.install(sys.stderr)
    try:
        status = group.main(standalone_mode=False, prog_name="mzc")   # a click Exit's status, or None
        if status:
            sys.exit(status)
    except click.exceptions.Exit as done:
        sys.exit(done.exit_code)
    except click.ClickException as usage:
        click.echo(one_line(usage), err=True)
        sys.exit(usage.exit_code)
    except click.exceptions.Abort:
        click.echo("mzc: aborted", err=True)
        sys.exit(130)
    except MzcError as error:
        click.echo(f"mzc: {error.spelled(option_spellings(sys.argv[1:]))}", err=True)
        sys.exit(1)
    except BrokenPipeError:
        # The reader went away (mzc ... | head): not an error of ours.
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        sys.exit(1)
    except MemoryError:
        click.echo(f"mzc: {' '.join(sys.argv[1:])[:200]}: out of memory (the grid, densify's n or diff's "
                   "--samples asks for more than this machine has)", err=True)
        sys.exit(1)
    except Exception as error:  # noqa: BLE001 - the promise is one line, never a traceback
        if os.environ.get("MZC_DEBUG"):
            raise
        click.echo(f"mzc: internal error: {type(error).__name__}: {error} "
                   "(set MZC_DEBUG=1 for a traceback)", err=True)
        sys.exit(3)


def option_spellings(args):
    """{API name: command-line flag} of the options of the command that ``args`` run (``batch
    encode``'s for ``mzc batch encode ...``): an MzcError from the library names ``max_error``,
    the user typed ``--max-error``."""
    command, spellings = group, {}
    for word in args:
        found = command.get_command(click.Context(command), word)
        if found is None:
            continue   # an option of the group, or its value
        command = found
        spellings.update({param.name: long_flag(param) for param in command.params if isinstance(param, click.Option)})
        if not isinstance(command, click.Group):
            break
    return spellings


def long_flag(option):
    """An option's longest spelling: ``--quality``, not ``-q``."""
    return max(option.opts, key=len)


M_TRIM_THRESHOLD, M_MMAP_MAX = -1, -4   # glibc's mallopt parameters
KEPT_FREE_BYTES = 1 << 30               # freed heap memory the process keeps for reuse before returning any


def one_blas_thread():
    """Keep numpy's BLAS (OpenBLAS) to one thread in this process, unless the environment says
    otherwise; set before numpy loads. mzc hands BLAS no work worth a thread (its products are
    written out per component, mzc/vectors.py), but OpenBLAS starts a thread per core that spins
    at import: 0.06 s of CPU a command, taken from the other commands of a pipeline (f18 at
    0.5 mm, the five filters: 1.07 s of wall time instead of 1.3 on 2 cores, quiet machine)."""
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")


def reuse_freed_memory():
    """Make this process's allocator (glibc's; elsewhere nothing changes) reuse the memory
    of freed arrays. It gives every block over 32 MB pages of its own from the kernel and
    returns them when the block is freed, so each big temporary of a big grid's numpy code
    (200 MB at 25 M nodes) is pages the kernel zeroes and maps again: 20.7 s of system time
    against 15.3 s of user time in an --rmse encode of 25 M nodes. Big blocks from the heap,
    and up to KEPT_FREE_BYTES of it kept when freed: that encode's page faults fell from
    515 000 to 147 000 and its CPU time from 24.9 to 16.2 s (system 11.7 -> 3.8 s), its peak
    RSS rising from 3347 to 3558 MB (the heap's holes). A command's process, not the
    library: a host program keeps its own allocator's settings."""
    import ctypes

    try:
        libc = ctypes.CDLL("libc.so.6")
        libc.mallopt(M_MMAP_MAX, 0)
        libc.mallopt(M_TRIM_THRESHOLD, KEPT_FREE_BYTES)
    except (OSError, AttributeError):   # not glibc
        return


def one_line(problem):
    """A click usage error as one line that starts with the command and the problem, then says
    where help is: ``mzc encode: --level: 0 is outside 1..32 (see 'mzc encode --help')``."""
    context = getattr(problem, "ctx", None)
    path = context.command_path if context is not None else "mzc"
    message = problem.format_message()
    if isinstance(problem, click.BadParameter) and not isinstance(problem, click.MissingParameter) \
            and problem.param is not None:
        # click's "Invalid value for '-q': 0 is not in the range 1<=x<=100." as "-q: 0 is not in 1..100"
        hint = problem.param_hint or "/".join(getattr(problem.param, "opts", None) or [problem.param.name or ""])
        message = f"{hint}: {problem.message}"
        message = re.sub(r"is not in the range (\S+?)\.?$", lambda m: range_words(m[1]), message).rstrip(".")
    return f"{path}: {message} (see '{path} --help')"


def range_words(bounds):
    """click's range ``1<=x<=100``, ``0<x<=1e+100`` or ``x>0`` in words: ``is not in 1..100``,
    ``must be > 0 and <= 1e+100``, ``must be > 0``."""
    closed = re.fullmatch(r"(\S+?)<=x<=(\S+)", bounds)
    if closed:
        return f"is not in {closed[1]}..{closed[2]}"
    low = re.match(r"(\S+?)(<=?)x", bounds)
    high = re.search(r"x(<=?)(\S+)$", bounds)
    below = re.fullmatch(r"x(>=?)(\S+)", bounds)
    words = [f"{'>' if low[2] == '<' else '>='} {low[1]}"] if low else []
    words += [f"{high[1]} {high[2]}"] if high else []
    words += [f"{below[1]} {below[2]}"] if below else []
    return "must be " + " and ".join(words) if words else f"is not in the range {bounds}"


def show_warning(message, category, filename, lineno, file=None, line=None):
    """mzc's warnings (the only ones not ignored) as one line on stderr: ``mzc: warning: ...``."""
    progress.clear()
    click.echo(f"mzc: warning: {message}", err=True)
