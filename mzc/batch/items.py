"""The items of a batch: each input file and the path its output takes under the destination.

Sources are files, folders (walked recursively; hidden names and the destination are
skipped, and only files of the job's extensions are taken), glob patterns, and lists of
paths (``@LIST``: one path per line, ``@-`` for stdin). An output keeps its input's place
relative to where it was found (the folder, the fixed part of the glob, the common folder
of a list's entries; a file named alone keeps its name), with the job's extension.
"""

from __future__ import annotations

import glob
import os
import sys
from dataclasses import dataclass

from mzc.errors import MzcError

LIST_PREFIX = "@"


@dataclass(frozen=True)
class Item:
    """One unit of work: ``source``, the absolute path workers read, and ``output``, the output's
    path relative to the destination."""

    source: str
    output: str


def collect(sources, extensions, output_extension, dest):
    """The items of ``sources`` in a stable order, their outputs named with ``output_extension``;
    an MzcError (before any work) for a source that names nothing, or two inputs that would
    write the same output."""
    dest = os.path.abspath(dest)
    found = []
    for source in sources:
        pairs = list(relative_paths(source, extensions, dest))
        if not pairs:
            raise MzcError(f"no input found here (taken: {', '.join(extensions)})", source=source)
        found += pairs
    items = {}
    for path, relative in found:
        if relative.split(os.sep)[0] == os.pardir:
            raise MzcError("its output would fall outside the destination: name it without '..' after a "
                           "wildcard", source=path)
        output = os.path.splitext(relative)[0] + output_extension
        earlier = items.get(output)
        if earlier is not None and earlier.source != path:
            raise MzcError(f"{earlier.source} and {path} would both write {output}: give them in separate "
                           "folders or batches", source=path)
        items[output] = Item(path, output)
    return list(items.values())


def relative_paths(source, extensions, dest):
    """(absolute input path, path relative to where it was found) of each input ``source`` names."""
    if source.startswith(LIST_PREFIX):
        paths = [os.path.abspath(p) for p in listed_paths(source[len(LIST_PREFIX):])]
        base = os.path.commonpath([os.path.dirname(p) for p in paths]) if paths else ""
        return [(p, os.path.relpath(p, base)) for p in paths]
    if os.path.isdir(source):
        base = os.path.abspath(source)
        return [(p, os.path.relpath(p, base)) for p in walk(base, extensions, dest)]
    if glob.has_magic(source):
        base = os.path.abspath(fixed_part(source))
        paths = sorted(os.path.abspath(p) for p in glob.glob(source, recursive=True) if os.path.isfile(p))
        return [(p, os.path.relpath(p, base)) for p in paths if not inside(p, dest)]
    if not os.path.exists(source):
        raise MzcError("no such file or folder", source=source)
    return [(os.path.abspath(source), os.path.basename(source))]


def listed_paths(name):
    """The paths of a list file (or stdin for ``-``): one per line, blank lines and ``#`` comments
    skipped, relative ones taken from the list's folder; read as the file system's names are
    (os.fsdecode), so a name that is not UTF-8 names its file."""
    try:
        if name == "-":
            data = sys.stdin.buffer.read()
        else:
            with open(name, "rb") as file:
                data = file.read()
    except OSError as error:
        raise MzcError(f"cannot read the list of inputs: {error.strerror or error}", source=name) from None
    folder = "" if name == "-" else os.path.dirname(name)
    paths = []
    for number, line in enumerate(os.fsdecode(data).splitlines(), 1):
        path = line.strip()
        if not path or path.startswith("#"):
            continue
        path = os.path.join(folder, path)
        if not os.path.isfile(path):
            raise MzcError(f"no such file: {path}", source=name, line=number)
        paths.append(path)
    return paths


def walk(folder, extensions, dest):
    """The files of ``folder`` and its subfolders whose extension is one of ``extensions``, sorted,
    leaving out hidden names and anything inside ``dest``."""
    found = []
    for root, folders, files in os.walk(folder):
        folders[:] = sorted(f for f in folders if not f.startswith(".") and not inside(os.path.join(root, f), dest))
        found += [os.path.join(root, f) for f in sorted(files)
                  if not f.startswith(".") and os.path.splitext(f)[1].lower() in extensions]
    return found


def fixed_part(pattern):
    """The folder of a glob pattern before its first wildcard (``scans/2026/*/f*.ply`` -> ``scans/2026``)."""
    parts = pattern.split(os.sep)
    fixed = []
    for part in parts[:-1]:
        if glob.has_magic(part):
            break
        fixed.append(part)
    return os.sep.join(fixed) or ("." if not pattern.startswith(os.sep) else os.sep)


def inside(path, folder):
    """True when ``path`` is ``folder`` or lies within it."""
    path = os.path.abspath(path)
    return path == folder or path.startswith(folder.rstrip(os.sep) + os.sep)
