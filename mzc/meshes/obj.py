"""Wavefront OBJ: ``v`` and ``f`` lines in any dialect, read and written without a Python
loop per vertex or face.

mzc reads OBJ itself rather than through meshio, which misreads negative indices. Lines
end with ``\n``, ``\r\n`` or a lone ``\r`` (old Mac files), and a backslash at the end of
a line continues the statement on the next; a positive face index may name a vertex
defined further down, a negative one counts back from the vertices so far. Polygons
(quads, n-gons) are split into a fan of triangles about their first corner: exact for
the convex polygons scanners and exporters write (a concave one would need ear
clipping). Vertex colours (``v x y z r g b``) are read, or else the texture of the
material (``mtllib``'s ``map_Kd``, through the corners' ``vt``: ``mzc.meshes.texture``) is
sampled at the vertices. Exporters' other statements (``usemtl``, ``g``, ``o``, ``s``,
``vn``, ``l``) and comments holding any bytes are read past.
"""

import os
import re
import warnings

import numpy as np

from mzc.colours import to_8_bits
from mzc.errors import MzcError
from mzc.meshes import Mesh
from mzc.meshes.common import fan_triangulate_ragged
from mzc.numbers import is_number, unpadded

NAME = "obj"
EXTENSIONS = (".obj",)

OBJ_WHITESPACE = np.frombuffer(b" \t\r\n\v\f", dtype=np.uint8)


def sniff(data: bytes) -> bool | None:
    """True when a line near the start is a ``v`` statement; else None: an OBJ has no magic, so
    any text may be one (its reader says what is wrong with it)."""
    return True if re.search(rb"(^|[\r\n])\s*v\s", data[:4096]) else None


def read(data: bytes, source: str) -> Mesh:
    """Read Wavefront OBJ: ``v`` and ``f`` lines in any dialect (v/vt/vn, negative indices,
    polygons, CRLF or CR line ends, continued lines, trailing comments); every other statement (vt, vn, o, g, s,
    usemtl, l, ...) is read past, and what it held is named in the Mesh's ``dropped``. Works on whole
    byte arrays: no Python loop per vertex or face."""
    tokens = ObjTokens(unpadded(data))
    binary = tokens.first_nul_line()
    if binary is not None:
        raise MzcError("binary data (a NUL byte) where OBJ text was expected", source=source, line=binary)
    vertex_lines, face_lines = tokens.lines_of("v"), tokens.lines_of("f")
    if len(vertex_lines) == 0:
        raise MzcError("no 'v' lines: the OBJ file has no vertices", source=source)
    points = obj_vertices(tokens, vertex_lines, source)
    corners, flat, counts = face_corners(tokens, face_lines, vertex_lines, source)
    triangles = fan_triangulate_ragged(flat, counts) if len(face_lines) else np.empty((0, 3), dtype=np.int64)
    colors, texture = obj_colours(tokens, vertex_lines, source), None
    if colors is None and len(face_lines):
        colors, texture = texture_colours(tokens, corners, flat, counts, len(points), source)
    return Mesh(points, triangles, colors=colors, texture=texture,
                dropped=obj_dropped(tokens, vertex_lines, colors is not None and texture is None, texture is not None))


def texture_colours(tokens, corners, flat, counts, count, source):
    """((count, 3) uint8 colours of the vertices, the ``Texture``) of the texture of the file's
    material (``mtllib``, its ``map_Kd``: ``mzc.meshes.texture``), through the ``vt`` of each face
    corner (its ``v/vt`` index; a vertex's colour at the uv of a corner using it), or (None, None)
    when the file names no texture, its corners no ``vt``, or the image cannot be read (one
    warning says why)."""
    from mzc.meshes.texture import material_image, textured

    libraries = tokens.statement_words(b"mtllib")
    texture_lines = tokens.lines_of_word(b"vt")
    if not libraries or not len(texture_lines):
        return None, None
    texture_index = tokens.numbers(corners, np.int64, between_slashes=True)
    if texture_index is None or len(texture_index) != len(corners):
        return None, None   # corners without a vt index (f 1 2 3, f 1//1) or a bad one: no texture mapping
    image = material_image(source, libraries)
    if image is None:
        return None, None
    arguments = tokens.arguments(texture_lines)
    position = arguments - np.searchsorted(tokens.line, tokens.line[arguments])
    uv = tokens.numbers(arguments[position <= 2], np.float64)
    if uv is None or len(uv) != 2 * len(texture_lines):
        raise MzcError("a texture coordinate (vt) needs u v numbers", source=source)
    uv = uv.reshape(-1, 2)
    defined_before = np.searchsorted(texture_lines, tokens.line[corners])
    texture_index = np.where(texture_index < 0, texture_index + defined_before, texture_index - 1)
    if ((texture_index < 0) | (texture_index >= len(uv))).any():
        raise MzcError(f"a face refers to a texture coordinate that does not exist (there are {len(uv)})",
                       source=source)
    per_vertex = np.full((count, 2), np.nan)
    per_vertex[flat] = uv[texture_index]
    corner_uv = uv[texture_index][fan_triangulate_ragged(np.arange(len(corners)), counts)]
    return textured(image, corner_uv, per_vertex)


def vertex_arguments(tokens, vertex_lines):
    """(token indices of the ``v`` lines' arguments, each one's position on its line from 1,
    how many arguments each ``v`` line has)."""
    arguments = tokens.arguments(vertex_lines)
    line = tokens.line[arguments]
    position = arguments - np.searchsorted(tokens.line, line)  # 1 = first argument
    return arguments, position, np.bincount(np.searchsorted(vertex_lines, line), minlength=len(vertex_lines))


def obj_colours(tokens, vertex_lines, source):
    """(n, 3) uint8 colours of ``v x y z r g b`` lines, when every ``v`` line has them (floats in
    0..1, or 0..255 when one exceeds 1: ``mzc.colours.to_8_bits``), else None."""
    arguments, position, counts = vertex_arguments(tokens, vertex_lines)
    if not (counts >= 6).all():
        return None
    rgb = arguments[(position >= 4) & (position <= 6)]
    values = tokens.numbers(rgb, np.float64)
    if values is None:
        raise first_bad_token(tokens, rgb, is_number, "not a number", source)
    return to_8_bits(values.reshape(-1, 3))


def obj_dropped(tokens, vertex_lines, coloured_read, textured):
    """What an OBJ file holds beside its shape, which mzc does not keep: vertex colours (``v x y
    z r g b``) when not every vertex has them (``coloured_read``: they are read), texture
    coordinates (``vt``) and materials (``mtllib``: a texture's image) unless the texture was
    sampled (``textured``), normals (``vn``: recomputed from the triangles)."""
    coloured = 0 if coloured_read else int((vertex_arguments(tokens, vertex_lines)[2] >= 6).sum())
    counts = [(coloured, "vertex colours"), (0 if textured else tokens.statements(b"vt"), "texture coordinates (vt)"),
              (tokens.statements(b"vn"), "normals (vn; recomputed from the triangles)"),
              (0 if textured else tokens.statements(b"mtllib"), "materials (mtllib)")]
    return tuple(f"{count:,} {what}" for count, what in counts if count)


class ObjTokens:
    """The whitespace-separated tokens of OBJ bytes: where each starts and ends, and its line.

    Comments (``#`` to the end of the line, whatever bytes they hold) are blanked first. A line ends at ``\n``, or at
    ``\r`` not followed by ``\n``, unless a backslash comes just before: that line goes on on the next. ``line``
    numbers the joined lines from 0; ``number`` gives the file's line number where one of them starts.
    """

    def __init__(self, data):
        text = np.frombuffer(data, dtype=np.uint8)
        line_end = (text == ord("\n")) | ((text == ord("\r")) & (np.r_[text[1:], 0] != ord("\n")))
        self.physical = newlines = np.flatnonzero(line_end)
        if b"\\\n" in data or b"\\\r" in data:
            line_end, text = joined_lines(text, line_end)
            newlines = np.flatnonzero(line_end)
        self.newlines = newlines
        if b"#" in data:
            after_hash = last_index(text == ord("#")) > last_index(line_end)
            text = np.where(after_hash, ord(" "), text).astype(np.uint8)
        self.text = text
        space = np.isin(text, OBJ_WHITESPACE)
        begins = ~space
        begins[1:] &= space[:-1]
        self.starts = np.flatnonzero(begins)
        self.ends = np.flatnonzero(~space & np.r_[space[1:], True]) + 1
        self.token_of_byte = np.cumsum(begins, dtype=np.int32) - 1  # -1 before the first token
        self.line = np.searchsorted(newlines, self.starts)
        self.first_on_line = np.r_[True, self.line[1:] != self.line[:-1]]

    def number(self, line):
        """The file's line number (from 1) where joined line ``line`` (0-based) starts."""
        start = self.newlines[line - 1] + 1 if line > 0 else 0
        return int(np.searchsorted(self.physical, start)) + 1

    def first_nul_line(self):
        """The line number of the first line holding a NUL byte outside a comment, or None:
        exporters put any bytes in comments (ZBrush a NUL), but a NUL elsewhere means binary data."""
        nul = np.flatnonzero(self.text == 0)
        return int(np.searchsorted(self.physical, nul[0])) + 1 if len(nul) else None

    def statements(self, keyword):
        """How many lines start with the token ``keyword`` (bytes: ``b"vt"``)."""
        return len(self.lines_of_word(keyword))

    def lines_of_word(self, keyword):
        """Sorted line indices (0-based) whose first token is ``keyword`` (bytes: ``b"vt"``)."""
        length = len(keyword)
        chosen = np.flatnonzero(self.first_on_line & (self.ends - self.starts == length))
        if not len(chosen):
            return chosen
        words = np.stack([self.text[self.starts[chosen] + k] for k in range(length)], axis=1)
        return self.line[chosen[(words == np.frombuffer(keyword, dtype=np.uint8)).all(axis=1)]]

    def statement_words(self, keyword):
        """The rest of each line that starts with ``keyword`` (bytes), as text: the few ``mtllib``
        lines' file names (a name may hold spaces)."""
        return [" ".join(self.token_text(int(index)) for index in np.flatnonzero(self.line == line)[1:])
                for line in self.lines_of_word(keyword)]

    def lines_of(self, keyword):
        """Sorted line indices (0-based) whose first token is the one-letter ``keyword``."""
        is_keyword = (self.first_on_line & (self.ends - self.starts == 1)
                      & (self.text[self.starts] == ord(keyword)))
        return self.line[is_keyword]

    def arguments(self, lines):
        """Token indices of the arguments (all tokens but the keyword) on ``lines``."""
        on_lines = np.isin(self.line, lines) & ~self.first_on_line
        return np.flatnonzero(on_lines)

    def numbers(self, token_indices, dtype, cut_at_slash=False, between_slashes=False):
        """Parse the chosen tokens as numbers in one call; None when one does not parse.

        ``cut_at_slash`` keeps only what precedes the first ``/`` of each token (v/vt/vn), and
        ``between_slashes`` only what lies between its first and second (the vt of v/vt/vn).
        """
        chosen = np.zeros(len(self.starts) + 1, dtype=bool)  # the extra last slot: no token
        chosen[token_indices] = True
        keep = chosen[self.token_of_byte]
        if cut_at_slash:
            keep &= last_index(self.text == ord("/")) < self.starts[self.token_of_byte]
        if between_slashes:
            slash = self.text == ord("/")
            before = np.cumsum(slash) - slash   # slashes before each byte
            at_start = np.r_[before, 0][self.starts[self.token_of_byte]]
            keep &= (before - at_start == 1) & ~slash
        buffer = np.where(keep, self.text, ord(" ")).astype(np.uint8).tobytes()
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            try:
                values = np.fromstring(buffer, dtype=dtype, sep=" ")
            except (DeprecationWarning, ValueError):
                return None
        return values if len(values) == len(token_indices) else None

    def token_text(self, index):
        """The text of one token, for error messages."""
        return self.text[self.starts[index]:self.ends[index]].tobytes().decode("utf-8", "replace")


def joined_lines(text, line_end):
    """(line ends, text) with each line end that follows a backslash taken away, the backslash
    and a ``\r`` before the ``\n`` made spaces: the statement goes on on the next line."""
    before = np.r_[0, text[:-1]]
    crlf = (text == ord("\n")) & (before == ord("\r"))
    backslash_before = np.where(crlf, np.r_[0, 0, text[:-2]], before) == ord("\\")
    joined = line_end & backslash_before
    blank = np.zeros(len(text), dtype=bool)
    positions = np.flatnonzero(joined)
    blank[positions - 1 - crlf[positions]] = True      # the backslash
    blank[positions[crlf[positions]] - 1] = True         # the \r of \r\n
    return line_end & ~joined, np.where(blank, ord(" "), text).astype(np.uint8)


def last_index(mask):
    """For every position, the index of the latest True at or before it (-1 when none)."""
    return np.maximum.accumulate(np.where(mask, np.arange(len(mask), dtype=np.int32), np.int32(-1)))


def obj_vertices(tokens, vertex_lines, source):
    """(n, 3) x y z of the ``v`` lines; w and colour columns are ignored (``obj_colours``)."""
    arguments, position, counts = vertex_arguments(tokens, vertex_lines)
    if (counts < 3).any():
        raise MzcError("a vertex needs x y z", source=source,
                       line=tokens.number(int(vertex_lines[np.argmax(counts < 3)])))
    xyz = arguments[position <= 3]
    values = tokens.numbers(xyz, np.float64)
    if values is None:
        raise first_bad_token(tokens, xyz, is_number, "not a number", source)
    return values.reshape(-1, 3)


def face_corners(tokens, face_lines, vertex_lines, source):
    """(token index of each corner of the ``f`` lines, its vertex index from 0, the corner count of
    each face), 1-based and negative (relative) indices resolved."""
    if len(face_lines) == 0:
        return np.empty(0, dtype=np.int64), np.empty(0, dtype=np.int64), np.empty(0, dtype=np.int64)
    corners = tokens.arguments(face_lines)
    corner_line = tokens.line[corners]
    counts = np.bincount(np.searchsorted(face_lines, corner_line), minlength=len(face_lines))
    if (counts < 3).any():
        raise MzcError("a face needs at least 3 vertices", source=source,
                       line=tokens.number(int(face_lines[np.argmax(counts < 3)])))
    flat = tokens.numbers(corners, np.int64, cut_at_slash=True)
    if flat is None:
        raise first_bad_token(tokens, corners, is_index, "bad vertex index", source)
    # A negative index counts back from the vertices defined so far in the file.
    defined_before = np.searchsorted(vertex_lines, corner_line)
    flat = np.where(flat < 0, flat + defined_before, flat - 1)
    invalid = (flat < 0) | (flat >= len(vertex_lines))
    if invalid.any():
        raise MzcError(f"face refers to a vertex that does not exist (there are {len(vertex_lines)})",
                       source=source, line=tokens.number(int(corner_line[np.argmax(invalid)])))
    return corners, flat, counts


def is_index(token):
    """True when an OBJ face corner such as ``7/3/2`` or ``-1`` starts with an ASCII integer."""
    return re.fullmatch(r"[-+]?[0-9]+", token.split("/", 1)[0]) is not None


def first_bad_token(tokens, indices, accept, message, source):
    """The MzcError for the first token that ``accept`` refuses (the slow path, errors only)."""
    for index in indices:
        text = tokens.token_text(index)
        if not accept(text):
            return MzcError(f"{message}: {text[:40]!r}", source=source, line=tokens.number(int(tokens.line[index])))
    return MzcError(message, source=source)


def write(mesh: Mesh) -> bytes:
    """OBJ bytes of ``mesh``: one string-format call over the whole arrays, shortest exact floats;
    colours as ``v x y z r g b``, each the 0..1 fraction of its 8-bit level (``level / 255``,
    shortest exact, which reads back as that level)."""
    colors = mesh.colors
    if colors is not None:
        values = np.column_stack([mesh.points, colors / 255.0])
        vertices = ("v %r %r %r %r %r %r\n" * len(mesh.points)) % tuple(values.ravel().tolist())
    else:
        vertices = ("v %r %r %r\n" * len(mesh.points)) % tuple(mesh.points.ravel().tolist())
    faces = ("f %d %d %d\n" * len(mesh.triangles)) % tuple((mesh.triangles.ravel() + 1).tolist())
    return (vertices + faces).encode("ascii")


def textured(grid, mesh, obj_path, png_path):
    """[(path, bytes)] of a grid's mesh (``mesh``: points, triangles and the grid node each point
    stands for, ``triangulation.node_mesh``) as an OBJ at ``obj_path`` whose vertex k has the
    texture coordinate of its node (r, c), the centre of pixel (R - 1 - rK, cK) of the grid's R x C
    colour image, K its colour scale (the nodes' colours, K = 1, or ``fine_colors``), written as the
    PNG at ``png_path`` (its first row the grid's last: v runs up; its invalid pixels padded,
    ``texture.padded``), and the material file beside the OBJ (its name with .mtl) that names the
    PNG by its path from the OBJ's folder. A triangle whose corners are nodes of two charts (the
    seams of a multi-chart grid) takes its first corner's texture coordinate at all three (the
    image between two charts' blocks is on neither's surface); those triangles come first, so a
    reader that gives a vertex the colour at its last corner's coordinate gets its node's."""
    from mzc.grid import chart_labels, fine_mask
    from mzc.meshes.texture import padded, png_bytes

    points, triangles, node = mesh
    if grid.colors is None:
        raise MzcError("the grid has no colours to write as a texture", field="texture")
    scale = grid.colour_scale
    colours = padded(grid.colors if scale == 1 else grid.fine_colors, fine_mask(grid.valid, scale, grid.charts))
    rows, cols = colours.shape[:2]
    row, col = np.divmod(node, grid.shape[1])
    uv = np.column_stack([(col * scale + 0.5) / cols, (row * scale + 0.5) / rows])
    texels = triangles
    if grid.charts is not None:
        label = chart_labels(grid.shape, grid.charts).ravel()[node][triangles]
        across = (label != label[:, :1]).any(axis=1)
        texels = np.where(across[:, None], triangles[:, :1], triangles)
        first = np.argsort(~across, kind="stable")   # the seams' first: a vertex's last corner is its own texel's
        triangles, texels = triangles[first], texels[first]
    folder = os.path.dirname(os.path.abspath(obj_path))
    material = os.path.splitext(os.path.basename(obj_path))[0] + ".mtl"
    image = os.path.relpath(os.path.abspath(png_path), folder).replace(os.sep, "/")
    vertices = write(Mesh(points)).decode("ascii")   # the v lines alone
    texture = ("vt %r %r\n" * len(uv)) % tuple(uv.ravel().tolist())
    pairs = np.stack([triangles, texels], axis=-1) + 1   # each corner's vertex, then its texture coordinate
    corners = ("f %d/%d %d/%d %d/%d\n" * len(triangles)) % tuple(pairs.ravel().tolist())
    obj = f"mtllib {material}\nusemtl grid_colours\n{vertices}{texture}{corners}"
    mtl = f"newmtl grid_colours\nKa 1 1 1\nKd 1 1 1\nmap_Kd {image}\n"
    return [(obj_path, obj.encode("ascii")), (os.path.join(os.path.dirname(obj_path), material), mtl.encode("utf-8")),
            (png_path, png_bytes(colours[::-1]))]
