"""SingSurf definition files (``.defs``): read their surfaces.

SingSurf keeps its models in XML-like files::

    <group name="Cubics">
    <definition name="Cayley's Cubic" type="asurf">
    //# A cubic surface with 4 nodes
    4 (x^2+y^2+z^2) + 16 x y z - 1;
    <parameter name="a" value="1" />
    <variable name="x" min="-1.14" max="1.03">
    ...
    </definition>
    </group>

The files are not well-formed XML (``<parameter ...>`` tags are often left
open, some carry stray characters such as ``"}, >``, comments hold HTML),
so they are read line by line: SingSurf's own tags outside ``//`` comments
are taken out, and inside a definition what is left of each line
(comments included) is the equation's text, at its column in the file.
Groups nest.  :func:`read_definitions` returns one :class:`Definition`
per ``<definition>``, with the file line of each, so that an error in an
equation is reported at its line and column in the file.
"""

from __future__ import annotations

import difflib
import re
from dataclasses import dataclass, field
from pathlib import Path

from .errors import SurfaceError

#: The tags SingSurf writes; other ``<...>`` (HTML in comments) are text.
_TAG = re.compile(r"<\s*(/?)\s*(group|definition|parameter|variable|option|colour|color|clipping)\b([^<>]*)>",
                  re.IGNORECASE)
_ATTRIBUTE = re.compile(r"([A-Za-z_][\w-]*)\s*=\s*\"([^\"]*)\"")
_COMMENT_MARKUP = re.compile(r"<[^<>]*>")

#: The ``type`` of SingSurf's implicit surfaces; other types (parametric
#: surfaces ``psurf``, curves ``acurve`` ...) are listed but not meshed.
IMPLICIT_SURFACE = "asurf"


@dataclass(frozen=True)
class Definition:
    """One ``<definition>`` of a SingSurf file.

    Attributes
    ----------
    name : str
    group : tuple of str
        The enclosing ``<group>`` names, outermost first.
    type : str
        SingSurf's module, ``"asurf"`` for an implicit surface.
    equation : str
        The equation text as written (statements, ``//`` comments); line
        ``k`` of it is line ``first_line + k - 1`` of the file.
    parameters : dict of str to str
        ``<parameter name value>`` tags: the values as written.
    box : ((x0, x1), (y0, y1), (z0, z1)) or None
        From the ``<variable name min max>`` tags of x, y and z.
    options : dict of str to dict
        Any other tag inside the definition, by tag (or ``name``
        attribute), with its attributes.
    path : str
        The file.
    line : int
        Line of the ``<definition>`` tag.
    first_line : int
        Line of the first line of ``equation``.
    """

    name: str
    group: tuple
    type: str
    equation: str
    parameters: dict = field(default_factory=dict)
    box: tuple | None = None
    options: dict = field(default_factory=dict)
    path: str = ""
    line: int = 0
    first_line: int = 0

    @property
    def description(self) -> str:
        """The ``//`` comments of the equation, markup removed, as one line."""
        parts = []
        for raw in self.equation.splitlines():
            i = raw.find("//")
            if i >= 0:
                text = _COMMENT_MARKUP.sub(" ", raw[i + 2:]).lstrip("#").strip()
                if text:
                    parts.append(" ".join(text.split()))
        return " ".join(parts)

    @property
    def where(self) -> str:
        return f"{Path(self.path).name}, line {self.line}"

    def surface(self, **params):
        """The :class:`singmesh.Surface`, with ``params`` over the file's values.

        Raises
        ------
        SurfaceError
            If the definition is not an implicit surface or does not read;
            the message gives the file, line and column.
        """
        from .surface import Surface

        if self.type != IMPLICIT_SURFACE:
            raise SurfaceError(f"{self.where}: {self.name!r} is a SingSurf {self.type!r} definition, "
                               f"not an implicit surface ({IMPLICIT_SURFACE!r})")
        values = {**self.parameters, **params}
        try:
            # The file's own parameters may go unused (and be given values:
            # the gallery passes them all); others the caller gives may not.
            return Surface._parse(self.equation, values, optional=frozenset(self.parameters))
        except SurfaceError as exc:
            raise self._located(exc) from None

    def mesh(self, box=None, *, coarse: int = 32, fine: int = 256, **params):
        """:func:`singmesh.mesh` of this definition, on its own box unless ``box`` is given."""
        from .api import DEFAULT_BOX, mesh

        return mesh(self.surface(**params), box if box is not None else (self.box or DEFAULT_BOX),
                    coarse=coarse, fine=fine)

    def _located(self, exc: SurfaceError) -> SurfaceError:
        """The error with its place in the file instead of in the equation."""
        line = getattr(exc, "line", None)
        if line is None:
            return SurfaceError(f"{self.where} ({self.name!r}): {exc}")
        file_line = self.first_line + line - 1
        source = getattr(exc, "source", "").strip()
        err = SurfaceError(f"{Path(self.path).name}, line {file_line}, column {exc.column} ({self.name!r}): "
                           f"{exc.reason}" + (f" in {source!r}" if source else ""))
        err.reason, err.line, err.column, err.source = exc.reason, file_line, exc.column, exc.source
        return err


def read_definitions(path) -> list[Definition]:
    """All definitions of a SingSurf ``.defs`` file, in file order.

    Parameters
    ----------
    path : str or Path

    Raises
    ------
    SurfaceError
        If the file cannot be read, or a definition is left open.
    """
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8", errors="replace")
    except OSError as exc:
        raise SurfaceError(f"cannot read {path}: {exc.strerror or exc}") from None
    return parse_definitions(text, str(path))


def parse_definitions(text: str, path: str = "<text>") -> list[Definition]:
    """The definitions in the text of a ``.defs`` file (see :func:`read_definitions`)."""
    out: list[Definition] = []
    groups: list[str] = []
    current: dict | None = None
    name = Path(path).name
    for number, line in enumerate(text.splitlines(), start=1):
        pos = 0
        for m in [*_tags(line), None]:
            end = len(line) if m is None else m.start()
            if current is not None and line[pos:end].strip():
                # The equation's text, at its columns in the file.
                row = current["lines"].setdefault(number, [" "] * len(line))
                row[pos:end] = line[pos:end]
            if m is None:
                break
            pos = m.end()
            closing, tag, attrs = m.group(1) == "/", m.group(2).lower(), dict(_ATTRIBUTE.findall(m.group(3)))
            if tag == "group":
                if closing:
                    if groups:
                        groups.pop()
                else:
                    groups.append(attrs.get("name", "").strip() or "unnamed group")
            elif tag == "definition" and not closing:
                if current is not None:
                    raise SurfaceError(f"{name}, line {number}: a <definition> inside the definition "
                                       f"{current['name']!r} of line {current['line']} (missing </definition>)")
                current = {"name": attrs.get("name", "").strip() or f"definition of line {number}",
                           "type": attrs.get("type", "").strip(), "line": number, "lines": {},
                           "parameters": {}, "variables": {}, "options": {}, "group": tuple(groups)}
            elif tag == "definition":
                if current is None:
                    raise SurfaceError(f"{name}, line {number}: </definition> without a <definition>")
                out.append(_finish(current, path))
                current = None
            elif current is None or closing:
                continue
            elif tag == "parameter" and "name" in attrs:
                current["parameters"][attrs["name"].strip()] = attrs.get("value", "").strip()
            elif tag == "variable" and "name" in attrs:
                current["variables"][attrs["name"].strip()] = attrs
            else:
                current["options"][attrs.get("name", tag)] = attrs
    if current is not None:
        raise SurfaceError(f"{name}, line {current['line']}: the definition {current['name']!r} "
                           "is not closed by </definition>")
    return out


def _tags(line: str) -> list:
    """The SingSurf tags of a line, except those inside a ``//`` comment."""
    matches = list(_TAG.finditer(line))
    start = 0
    while True:
        c = line.find("//", start)
        if c < 0:
            return matches
        inside = [m for m in matches if m.start() < c < m.end()]
        if not inside:
            return [m for m in matches if m.start() < c]
        start = inside[0].end()


def _finish(current: dict, path: str) -> Definition:
    """A Definition from what the scanner collected."""
    rows = current["lines"]
    first = min(rows, default=current["line"] + 1)
    # Keep the file's line numbering: lines between that hold only tags are blank.
    body = ["".join(rows.get(k, "")).rstrip() for k in range(first, max(rows, default=first - 1) + 1)]
    box = None
    v = current["variables"]
    try:
        if all(a in v for a in "xyz"):
            box = tuple((float(v[a]["min"]), float(v[a]["max"])) for a in "xyz")
    except (KeyError, ValueError):
        box = None  # a range that is not two numbers: the default box
    return Definition(name=current["name"], group=current["group"], type=current["type"],
                      equation="\n".join(body), parameters=current["parameters"], box=box,
                      options=current["options"], path=path, line=current["line"], first_line=first)


def find_definition(definitions: list[Definition], name: str) -> Definition:
    """The definition called ``name`` (exactly, else ignoring case).

    Raises
    ------
    SurfaceError
        Naming the closest names when there is none.
    """
    for d in definitions:
        if d.name == name:
            return d
    folded = [d for d in definitions if d.name.casefold() == name.casefold()]
    if folded:
        return folded[0]
    names = [d.name for d in definitions]
    close = difflib.get_close_matches(name, names, n=3, cutoff=0.5)
    hint = f"; did you mean {', '.join(repr(c) for c in close)}?" if close else ""
    raise SurfaceError(f"no definition named {name!r} among {len(names)}{hint}")
