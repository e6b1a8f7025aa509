"""The exception type that the command line turns into a one-line error message, and the
warning it prints as one line."""

import contextlib


class MzcError(ValueError):
    """Bad input or an impossible request (a ValueError, so callers may catch either).

    The command line prints it as one line on stderr (``source:line: field: message``)
    and exits with status 1; it never shows a traceback.

    ``options`` names the options (as the API spells them: ``max_error``) that the message
    mentions, so that the command line can spell them as its own (``--max-error``, ``spelled``).
    """

    def __init__(self, message, *, source=None, line=None, field=None, options=()):
        super().__init__(message)
        self.message = message
        self.source = source
        self.line = line
        self.field = field
        self.options = tuple(options)

    def located(self, *, source=None, line=None, field=None):
        """Return this error with missing location parts filled in."""
        return MzcError(
            self.message,
            source=self.source or source,
            line=self.line if self.line is not None else line,
            field=self.field or field,
            options=self.options,
        )

    def spelled(self, spellings):
        """This error with the options it names spelled by ``spellings`` (an API name -> a command
        line flag): its ``options`` in the message, and its field when that is one of them or the
        error names no file (a field of a file's header keeps the file's name for it)."""
        import re

        message = self.message
        for name in self.options:
            message = re.sub(rf"(?<![\w-]){re.escape(name)}(?![\w-])", spellings.get(name, name), message)
        field = spellings.get(self.field, self.field) if self.source is None or self.field in self.options \
            else self.field
        return MzcError(message, source=self.source, line=self.line, field=field, options=())

    def __str__(self):
        where = ""
        if self.source:
            where = str(self.source)
            if self.line is not None:
                where += f":{self.line}"
            where += ": "
        elif self.line is not None:
            where = f"line {self.line}: "
        field = f"{self.field}: " if self.field else ""
        return f"{where}{field}{self.message}"


def first_line(error):
    """The first line of a library's error message, or the name of its type when it has none."""
    text = str(error).strip()
    return text.splitlines()[0] if text else type(error).__name__


@contextlib.contextmanager
def about(source, step):
    """Let an MzcError raised inside name ``source`` (a file name) when it names none: a
    problem found in the data read from a file is reported as that file's. Running out of
    memory there becomes an MzcError naming the file and the ``step`` (``decoding it``). A
    long step shows on a terminal as it runs (``mzc.progress``)."""
    from mzc.progress import step as progress_step

    try:
        with progress_step(f"{source}: {step}"):
            yield
    except MzcError as error:
        raise error.located(source=source) from None
    except MemoryError:
        raise MzcError(f"out of memory while {step}", source=source) from None


class MzcWarning(UserWarning):
    """A result that is valid but likely not what the user wants (a grid that sees little of
    the surface); the command line prints it once as ``mzc: warning: ...``."""
