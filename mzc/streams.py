"""Input from a file or stdin, and output that is written whole or not at all.

Every command reads ``-``/no argument as stdin and writes ``-o FILE`` or stdout. Output
is produced completely in memory or in a temporary file and only then published: a
failing command leaves no partial file, keeps an existing file untouched, and writes
nothing to stdout.
"""

import contextlib
import os
import sys
import tempfile

from mzc.errors import MzcError

STDIN_NAME = "<stdin>"


def is_stdio(path):
    """True when ``path`` means stdin or stdout."""
    return path is None or str(path) == "-"


def display_name(path):
    """The name used for ``path`` in error messages."""
    return STDIN_NAME if is_stdio(path) else str(path)


def read_input(path):
    """Return the bytes of ``path``, or of stdin when ``path`` is ``-`` or None."""
    if is_stdio(path):
        return sys.stdin.buffer.read()
    try:
        with open(path, "rb") as handle:
            return handle.read()
    except FileNotFoundError:
        raise MzcError("no such file", source=path) from None
    except IsADirectoryError:
        raise MzcError("is a directory, not a file", source=path) from None
    except PermissionError:
        raise MzcError("permission denied", source=path) from None


def check_not_input(output, *inputs):
    """Refuse to write ``output`` over one of the command's own input files."""
    if is_stdio(output) or not os.path.exists(output):
        return
    for path in inputs:
        if not is_stdio(path) and os.path.exists(path) and os.path.samefile(path, output):
            raise MzcError("output would overwrite an input file", source=output)


@contextlib.contextmanager
def atomic_path(output):
    """Yield a temporary path beside ``output``; rename it to ``output`` on success.

    Used where a library (meshio, matplotlib) wants a file name to write to.
    """
    directory = os.path.dirname(os.path.abspath(output))
    suffix = os.path.splitext(output)[1]
    try:
        handle, temp = tempfile.mkstemp(prefix=".mzc-", suffix=suffix, dir=directory)
    except FileNotFoundError:
        raise MzcError("directory does not exist", source=output) from None
    except PermissionError:
        raise MzcError("permission denied", source=output) from None
    os.close(handle)
    os.chmod(temp, 0o666 & ~current_umask())  # mkstemp makes it 0600; a new file should follow the umask
    try:
        yield temp
        os.replace(temp, output)
    finally:
        if os.path.exists(temp):
            os.unlink(temp)


def current_umask():
    """The process's file-creation mask (reading it means setting it, so set it straight back)."""
    mask = os.umask(0)
    os.umask(mask)
    return mask


def write_output(path, data):
    """Write ``data`` (bytes) to ``path`` atomically, or to stdout when ``path`` is ``-``/None."""
    if is_stdio(path):
        sys.stdout.buffer.write(data)
        sys.stdout.buffer.flush()
        return
    with atomic_path(path) as temp:
        with open(temp, "wb") as handle:
            handle.write(data)
