"""Input from a file or stdin, and output that is written whole or not at all and never
destroys what it names.

Every command reads ``-``/no argument as stdin and writes ``-o FILE`` or stdout. Output
is produced completely in memory and only then published: a failing command leaves no
partial file, keeps an existing file untouched, and writes nothing to stdout. What an
output name gets:

- A name that is not a regular file (a device such as /dev/null or /dev/full, a
  terminal, a FIFO) or that names an open descriptor (/dev/stdout, /dev/fd/N, which lead
  into /proc) is written through: opened for writing (appending, so ``-o /dev/stdout >>
  log`` adds to the log) and never replaced by a regular file.
- A symlink is followed (os.path.realpath) and the file it points to is replaced; the
  link stays a link. A dangling link makes the file it names, when that file's directory
  exists.
- An existing regular file is replaced by a new file with its mode (and owner and group,
  where we may set them). A file we may not write is refused, as ``>`` would refuse it, and
  so is a file without any write permission bit (0444), for root too, which ``>`` lets write.
- A file with several hard links, or one in a directory we may not write, is written in
  place, so every link sees the new content, under an exclusive lock (flock), so that two
  mzc commands writing it at once take turns and it ends as one of them wrote it: space for
  the data is reserved first (posix_fallocate), so a full disk leaves the file untouched,
  then the data is written and the file cut to its length. A crash during that write
  leaves mixed content.
- Any other file is written and synced as an unnamed O_TMPFILE in the target's directory
  (Linux), then linked to a hidden ``.mzc-*`` name there and renamed over the target; a
  SIGTERM, SIGHUP, SIGINT or SIGPIPE in that short step removes the hidden name, and a
  SIGKILL can only hit that step. Where O_TMPFILE is refused, the data goes to a named
  hidden temporary (mkstemp) with the same signal cleanup; SIGKILL, which cannot be
  caught, can then leave a ``.mzc-*`` file behind.
- A command with several outputs stages them all (written and synced beside their
  targets) before it publishes any (write_outputs); check_not_input and check_distinct
  refuse bad names, outputs that are inputs (or stdin, when stdin is read) and two outputs
  that are one file before any work is done.
"""

import contextlib
import errno
import fcntl
import os
import signal
import stat
import sys

from mzc.errors import MzcError

STDIN_NAME = "<stdin>"
STDOUT_NAME = "<stdout>"
HIDDEN_PREFIX = ".mzc-"
NO_TMPFILE = (errno.EOPNOTSUPP, errno.EISDIR, errno.EINVAL)
CLEANUP_SIGNALS = tuple(getattr(signal, name) for name in ("SIGTERM", "SIGHUP", "SIGINT", "SIGPIPE")
                        if hasattr(signal, name))
pending: set[str] = set()   # named temporaries a signal must remove
saved_handlers: dict = {}   # signal number -> the handler it had


def is_stdio(path):
    """True when ``path`` means stdin or stdout."""
    return path is None or str(path) == "-"


def is_terminal(path):
    """True when ``path`` means stdout and stdout is a terminal (where binary data is no use)."""
    return is_stdio(path) and sys.stdout is not None and sys.stdout.isatty()


def path_of(path: object, name: str = "path") -> str:
    """A path argument as a string: a str or an os.PathLike, else an MzcError naming it."""
    text = os.fspath(path) if isinstance(path, (str, os.PathLike)) else None
    if not isinstance(text, str):
        raise MzcError(f"must be a file name (a str or a path), not a {type(path).__name__}", field=name)
    if "\0" in text:
        raise MzcError("a file name holds no NUL character", field=name)
    return text


def display_name(path):
    """The name used for ``path`` in error messages."""
    return STDIN_NAME if is_stdio(path) else str(path)


def output_name(path):
    """The name used for the output ``path`` in error messages."""
    return STDOUT_NAME if is_stdio(path) else str(path)


def read_input(path):
    """Return the bytes of ``path``, or of stdin when ``path`` is ``-`` or None."""
    if is_stdio(path):
        if sys.stdin is None:
            raise MzcError("stdin is closed", source=STDIN_NAME)
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
    except OSError as error:   # an I/O error, a loop of links, a name too long...
        raise failure(error, path) from None


def failure(error, path):
    """An OSError met while reading or writing ``path`` as a one-line MzcError (``no space left on device``)."""
    message = error.strerror or type(error).__name__
    return MzcError(message[:1].lower() + message[1:], source=path)


def stat_or_none(path, source):
    """os.stat of ``path`` (following links), None when there is no such file."""
    try:
        return os.stat(path)
    except FileNotFoundError:
        return None
    except OSError as error:
        raise failure(error, source) from None


def destination(path):
    """How ``path`` is written, as (how, target, info): how is ``through``, ``in place`` or
    ``replace``, target the file written, info its os.stat (None when it is new).

    Refuses, as a one-line MzcError, a name that cannot be written.
    """
    name = os.fspath(path)
    if name == "":
        raise MzcError("empty file name", source="''")
    if os.path.isdir(name):
        raise MzcError("is a directory", source=name)
    if name.endswith(os.sep) or (os.altsep and name.endswith(os.altsep)):
        raise MzcError("is a directory name", source=name)
    info = stat_or_none(name, name)
    if info is not None and (not stat.S_ISREG(info.st_mode) or names_a_descriptor(name)):
        return "through", name, info
    target = os.path.realpath(name)
    directory = os.path.dirname(target)
    if not os.path.isdir(directory):
        raise MzcError("directory does not exist", source=name)
    if info is not None and not writable(target, info):
        raise MzcError("permission denied (the file is read-only)", source=name)
    if info is not None and (info.st_nlink > 1 or not os.access(directory, os.W_OK | os.X_OK)):
        return "in place", target, info
    if not os.access(directory, os.W_OK | os.X_OK):
        raise MzcError("permission denied (cannot create a file in its directory)", source=name)
    return "replace", target, info


def writable(path, info):
    """True when we may write the file at ``path`` (its os.stat ``info``): access() allows it and
    its mode has a write bit. access() allows root any file, so a file made read-only (0444) is
    refused by its mode bits, as it is for everyone else."""
    return bool(info.st_mode & (stat.S_IWUSR | stat.S_IWGRP | stat.S_IWOTH)) and os.access(path, os.W_OK)


def is_stream(path):
    """True when ``path`` is stdout or is written through (a device, FIFO, terminal or open
    descriptor): it has no extension to tell a file format by."""
    return is_stdio(path) or destination(path)[0] == "through"


def names_a_descriptor(name):
    """True when ``name``, or a symlink on the way to its file, lies in /proc (/dev/stdout,
    /dev/fd/N): it is an open descriptor of some process, to be written through."""
    path = os.path.abspath(name)
    for _ in range(40):   # the kernel's limit on symlinks followed
        folder = os.path.realpath(os.path.dirname(path))
        if folder == "/proc" or folder.startswith("/proc/"):
            return True
        if not os.path.islink(path):
            return False
        path = os.path.join(os.path.dirname(path), os.readlink(path))
    return False


def check_not_input(output, *inputs):
    """Refuse, before any work, an output that cannot be written or that is one of the
    command's inputs; an input ``-``/None is stdin, compared when stdin is a regular file."""
    if is_stdio(output):
        return
    _, _, info = destination(output)
    if info is None or not stat.S_ISREG(info.st_mode):
        return
    for path in inputs:
        if is_stdio(path):
            if sys.stdin is not None and same_file(stdin_stat(), info):
                raise MzcError("output would overwrite the input read from stdin", source=output)
        elif os.path.exists(path) and same_file(os.stat(path), info):
            raise MzcError("output would overwrite an input file", source=output)


def stdin_stat():
    """os.fstat of file descriptor 0, None when it is closed."""
    try:
        return os.fstat(0)
    except OSError:
        return None


def same_file(first, second):
    """True when two os.stat results (``first`` may be None) are one regular file."""
    return (first is not None and stat.S_ISREG(first.st_mode)
            and (first.st_dev, first.st_ino) == (second.st_dev, second.st_ino))


def check_distinct(outputs):
    """Refuse two outputs that are one file; ``outputs`` maps each option's name to its path."""
    seen = {}
    for option, path in outputs.items():
        if not path or is_stdio(path):
            continue
        target = os.path.realpath(path)
        if target in seen:
            raise MzcError(f"the {seen[target]} and {option} outputs are the same file", source=path)
        seen[target] = option


def write_output(path, data):
    """Write ``data`` to ``path`` whole or not at all, or to stdout when ``path`` is ``-``/None.

    ``data`` is bytes-like, or an iterable of bytes-like chunks: a new file is written as the
    chunks are made (the file's bytes are never all in memory); stdout, devices and files
    written in place get them only once all are made, so a failure writes nothing there."""
    write_outputs((path, data))


def write_outputs(*outputs):
    """Write each (path, data) of ``outputs``: every one is checked and staged before any is
    published, so a failure writes none of them (short of one while publishing: a full disk
    met by a file written in place, whose space is reserved under its lock, leaves that file
    as it was and those published before it written)."""
    staged = []
    try:
        for path, data in outputs:
            staged.append(stage(path, data))
        for output in sorted(staged, key=lambda each: each.ORDER):
            output.publish()
    finally:
        for output in staged:
            output.close()


def stage(path, data):
    """The output object that will write ``data`` (``write_output``'s) to ``path``, prepared as
    far as it can be."""
    if is_stdio(path):
        return Stdout(whole(data))
    how, target, info = destination(path)
    kind = {"through": Through, "in place": InPlace, "replace": Replaced}[how]
    try:
        return kind(path, target, info, data if kind is Replaced else whole(data))
    except OSError as error:
        raise failure(error, path) from None


def whole(data):
    """``data`` as one bytes-like object: itself, or its chunks joined."""
    return data if isinstance(data, (bytes, bytearray, memoryview)) else b"".join(data)


class Stdout:
    """Data for stdout, written when published."""

    ORDER = 2

    def __init__(self, data):
        if sys.stdout is None:
            raise MzcError("stdout is closed", source=STDOUT_NAME)
        self.data = data

    def publish(self):
        """Write the data to stdout; a reader that went away stays a BrokenPipeError."""
        try:
            sys.stdout.buffer.write(self.data)
            sys.stdout.buffer.flush()
        except BrokenPipeError:
            raise
        except OSError as error:
            raise failure(error, STDOUT_NAME) from None

    def close(self):
        """Nothing to release."""


class Through:
    """A device, FIFO or descriptor name, opened now and written through when published."""

    ORDER = 0

    def __init__(self, path, target, info, data):
        self.path, self.data = path, data
        self.fd = os.open(target, os.O_WRONLY | os.O_APPEND | os.O_CLOEXEC)

    def publish(self):
        """Write the data to the open file."""
        try:
            write_all(self.fd, self.data)
        except BrokenPipeError:
            raise
        except OSError as error:
            raise failure(error, self.path) from None

    def close(self):
        """Close the file."""
        os.close(self.fd)


class InPlace:
    """An existing file written in its own inode (hard links, a read-only directory): opened now,
    written when published."""

    ORDER = 1

    def __init__(self, path, target, info, data):
        self.path, self.data = path, data
        self.fd = os.open(target, os.O_WRONLY | os.O_CLOEXEC)

    def publish(self):
        """Overwrite the file with the data, cut it to the data's length and sync it, holding an
        exclusive lock on it: another mzc writing it at once waits, so it cannot cut this data
        short or leave its own tail after it. The space is reserved under the lock (another
        writer's cut would free space reserved before it); the lock goes when the file is closed."""
        try:
            fcntl.flock(self.fd, fcntl.LOCK_EX)
            reserve(self.fd, len(self.data))
            write_all(self.fd, self.data, offset=0)
            os.ftruncate(self.fd, len(self.data))
            os.fsync(self.fd)
        except OSError as error:
            raise failure(error, self.path) from None

    def close(self):
        """Close the file."""
        os.close(self.fd)


class Replaced:
    """A new file written (chunk by chunk, as they are made) and synced beside the target now,
    renamed over it when published."""

    ORDER = 3

    def __init__(self, path, target, info, data):
        self.path, self.target = path, target
        self.fd, self.temp = new_file(os.path.dirname(target))
        try:
            for chunk in [data] if isinstance(data, (bytes, bytearray, memoryview)) else data:
                write_all(self.fd, chunk)
            if info is not None:
                keep_mode_and_owner(self.fd, info)
            os.fsync(self.fd)
        except BaseException:   # KeyboardInterrupt too: the named temporary must go
            self.close()
            raise

    def publish(self):
        """Link the unnamed file straight to a target that does not exist; otherwise give it a hidden
        name beside the target (unless it has one) and rename that over the target. Only a SIGKILL
        between that link and the rename, which nothing can catch, leaves the hidden name behind."""
        try:
            if self.temp is None and link_unnamed(self.fd, self.target):
                return
            if self.temp is None:
                self.temp = hidden_link(self.fd, os.path.dirname(self.target))
            os.replace(self.temp, self.target)
            forget(self.temp)
            self.temp = None
        except OSError as error:
            raise failure(error, self.path) from None

    def close(self):
        """Close the file and remove its hidden name if it was not published."""
        os.close(self.fd)
        if self.temp is not None:
            try:
                os.unlink(self.temp)
            except FileNotFoundError:
                pass
            forget(self.temp)
            self.temp = None


def new_file(directory):
    """(descriptor, name) of a new file in ``directory`` with the umask's mode: unnamed (name
    None, O_TMPFILE) where the system can, else a named hidden temporary, removed by signals."""
    mode = 0o666
    if hasattr(os, "O_TMPFILE"):
        try:
            return os.open(directory, os.O_TMPFILE | os.O_WRONLY | os.O_CLOEXEC, mode), None
        except OSError as error:
            if error.errno not in NO_TMPFILE:
                raise
    import tempfile  # here, not at the top: only where O_TMPFILE is refused (its imports cost every command)

    with signals_held():   # a signal that comes meanwhile waits until the handler knows the name
        fd, name = tempfile.mkstemp(prefix=HIDDEN_PREFIX, dir=directory)
        remember(name)
    os.fchmod(fd, mode & ~current_umask())   # mkstemp makes it 0600; a new file should follow the umask
    return fd, name


def link_unnamed(fd, path):
    """Give the unnamed file ``fd`` the name ``path``; False, and nothing done, if a file has it.
    /proc/self/fd lets an unprivileged process link it; a directory descriptor makes os.link follow."""
    folder = os.open(os.path.dirname(path), os.O_PATH | os.O_DIRECTORY | os.O_CLOEXEC)
    try:
        os.link(f"/proc/self/fd/{fd}", os.path.basename(path), dst_dir_fd=folder)
        return True
    except FileExistsError:
        return False
    finally:
        os.close(folder)


def hidden_link(fd, directory):
    """Link the unnamed file ``fd`` to a fresh hidden name in ``directory`` (remembered for signal
    cleanup) and return that name."""
    while True:
        name = os.path.join(directory, HIDDEN_PREFIX + os.urandom(6).hex())
        remember(name)
        try:
            if link_unnamed(fd, name):
                return name
        except OSError:
            forget(name)
            raise
        forget(name)


def keep_mode_and_owner(fd, info):
    """Give the new file the replaced file's owner and group where we may (root may set both,
    others their own groups), then its mode (fchown clears the set-user-ID bits)."""
    try:
        os.fchown(fd, info.st_uid, info.st_gid)
    except OSError:
        pass
    os.fchmod(fd, info.st_mode & 0o7777)


def reserve(fd, size):
    """Reserve disk space for the first ``size`` bytes of the file ``fd`` (posix_fallocate), so
    that writing them cannot fail for want of space; a failure leaves the file as it was."""
    if not size:
        return
    length = os.fstat(fd).st_size
    try:
        os.posix_fallocate(fd, 0, size)
    except OSError:
        os.ftruncate(fd, length)   # a failed reservation may have made the file longer
        raise


def write_all(fd, data, offset=None):
    """Write all of ``data`` to ``fd`` (at ``offset`` onwards when given)."""
    view, done = memoryview(data), 0
    while done < len(view):
        if offset is None:
            done += os.write(fd, view[done:])
        else:
            done += os.pwrite(fd, view[done:], offset + done)


@contextlib.contextmanager
def signals_held():
    """Hold CLEANUP_SIGNALS back from this thread inside the block and deliver them after it (a
    SIGHUP between creating a temporary and remembering its name had left the file behind);
    nothing is held where the system has no signal masks."""
    if not hasattr(signal, "pthread_sigmask"):
        yield
        return
    previous = signal.pthread_sigmask(signal.SIG_BLOCK, CLEANUP_SIGNALS)
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, previous)


def remember(name):
    """Add ``name`` to the temporaries a signal removes, installing the handlers for the first."""
    if not pending:
        for number in CLEANUP_SIGNALS:
            try:
                if signal.getsignal(number) == signal.SIG_DFL:
                    saved_handlers[number] = signal.signal(number, remove_and_die)
            except ValueError:   # not the main thread: signals cannot be handled here
                break
    pending.add(name)


def forget(name):
    """Remove ``name`` from the temporaries a signal removes, restoring the handlers after the last."""
    pending.discard(name)
    if not pending:
        for number, handler in saved_handlers.items():
            signal.signal(number, handler)
        saved_handlers.clear()


def remove_and_die(number, frame):
    """Signal handler: remove the pending temporaries, then die of the signal as we would have."""
    for name in list(pending):
        try:
            os.unlink(name)
        except OSError:
            pass
    signal.signal(number, signal.SIG_DFL)
    os.kill(os.getpid(), number)


def current_umask():
    """The process's file-creation mask (reading it means setting it, so set it straight back)."""
    mask = os.umask(0)
    os.umask(mask)
    return mask
