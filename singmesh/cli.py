"""The ``singmesh`` command line.

``singmesh mesh "EQUATION" -o out.ply [--box X0 X1 Y0 Y1 Z0 Z1] [--coarse N] [--fine N]
[--size curvature [--chord D] [--min-edge E] [--max-edge E]] [--no-curvature] [--no-improve] [a=1 ...]``
meshes, writes (with the per-vertex curvatures as point data in PLY, VTK
and VTU files, unless ``--no-curvature``) and prints the report (with the triangles' angles) (``--defs FILE --name NAME`` instead of
the equation meshes a definition of a SingSurf file on its own box);
``singmesh defs FILE`` lists such a file; ``singmesh classify "EQUATION" --at X Y Z``
names a singular point; ``singmesh gallery ...`` builds the gallery;
``singmesh sweep "EQUATION" --param NAME LO HI --frames N --out DIR`` meshes
a family at N values of a parameter (:mod:`singmesh.sweeps`).  Bad
input prints one error line and exits with status 2.
"""

from __future__ import annotations

import argparse
import importlib.util
import os
import re
import runpy
import sys
from pathlib import Path

from .defs import find_definition, read_definitions
from .errors import SurfaceError
from .mesh import FORMATS, LINE_FORMATS


class _Parser(argparse.ArgumentParser):
    """argparse, but a usage error is one SurfaceError line (exit status 2), not usage text."""

    #: Placeholders of :func:`_hide_leading_minus` and the words they hide,
    #: put back into error messages.
    hidden: dict[str, str] = {}

    def error(self, message: str):
        for key, word in self.hidden.items():
            message = message.replace(key, word)
        if len(message) > 200:  # an unrecognized 100 kB argument: one readable line
            message = message[:200] + "..."
        raise SurfaceError(f"{self.prog}: {message}")


_OPTION = re.compile(r"--[A-Za-z][A-Za-z0-9-]*(=.*)?", re.S)


def _hide_leading_minus(argv: list[str], takes_value: set[str]) -> tuple[list[str], dict[str, str]]:
    """``argv`` with each equation that starts with '-' (``-x^2+y^2``) replaced by a placeholder.

    argparse reads any word starting with '-' as an option; here only words
    starting with '--', '-o', '-h', and the values of options are left to
    it (``--name`` or ``--name=value``).  Returns the new list and the placeholders' words.
    """
    out, hidden = [], {}
    value_next = False
    for word in argv:
        if value_next or not word.startswith("-") or _OPTION.fullmatch(word) or word[:2] in ("-o", "-h") \
                or _is_number(word):
            value_next = word in takes_value
            out.append(word)
        else:
            key = f"\0{len(hidden)}"
            hidden[key] = word
            out.append(key)
    return out, hidden


def _parse_with_equation(p: _Parser, argv: list[str]) -> argparse.Namespace:
    """``p``'s arguments, an equation starting with '-' kept as a word and parameter values after the options.

    Intermixed: ``name=value`` may follow the options, as the README writes them.
    """
    takes_value = {o for a in p._actions if a.nargs is None for o in a.option_strings}
    argv, hidden = _hide_leading_minus(argv, takes_value)
    p.hidden = hidden
    args = p.parse_intermixed_args(argv)
    args.args = [hidden.get(a, a) for a in args.args]
    return args


def _params(items: list[str]) -> dict[str, str]:
    out = {}
    for item in items:
        if "=" not in item:
            raise SurfaceError(f"a parameter is given as name=value, not {item!r}")
        name, value = (part.strip() for part in item.split("=", 1))
        if not name.isidentifier():
            raise SurfaceError(f"{name!r} in {item!r} is not a parameter name")
        if name in out:
            raise SurfaceError(f"parameter {name} is given twice ({name}={out[name]} and {item})")
        out[name] = value
    return out


def _take_box(argv: list[str]) -> tuple[list[str], list[float] | None]:
    """``argv`` without ``--box`` and its six numbers, and the numbers.

    Taken before argparse, which reads ``-1e300`` or ``-inf`` as an option
    (only ``-1`` and ``-1.5`` look like numbers to it).
    """
    rest, given = _take_option(argv, "--box", 6, "--box is given twice")
    if given is None:
        return argv, None
    i = argv.index("--box")
    numbers = []
    for word in given:
        if not _is_number(word):
            break
        numbers.append(float(word))
    if len(numbers) < 6:
        got = f"{len(numbers)} number{'s' if len(numbers) != 1 else ''}"
        after = f", then {given[len(numbers)]!r}" if len(numbers) < len(given) else ""
        raise SurfaceError(f"--box takes six numbers X0 X1 Y0 Y1 Z0 Z1; got {got}{after}")
    if len(argv) > i + 7 and _is_number(argv[i + 7]):
        raise SurfaceError(f"--box takes six numbers X0 X1 Y0 Y1 Z0 Z1; a seventh, {argv[i + 7]!r}, follows")
    return rest, numbers


def _take_option(argv: list[str], option: str, count: int, twice: str) -> tuple[list[str], list[str] | None]:
    """``argv`` without ``option`` and the ``count`` words after it, and those words (None if absent).

    Options whose values argparse would misread (negative numbers such as
    ``-1e300``) are taken out before it; given twice is the error ``twice``.
    """
    if option not in argv:
        return argv, None
    i = argv.index(option)
    if option in argv[i + 1:]:
        raise SurfaceError(twice)
    return argv[:i] + argv[i + 1 + count:], argv[i + 1:i + 1 + count]


def _is_number(word: str) -> bool:
    try:
        float(word)
    except ValueError:
        return False
    return True


def _check_output(output: str) -> None:
    """Refuse an output path that cannot be written, before meshing."""
    path = Path(output)
    if FORMATS.get(path.suffix.lower()) is None:
        raise SurfaceError(f"cannot write {output}: unknown mesh format {path.suffix!r}: use one of "
                           f"{', '.join(sorted(FORMATS))}")
    if FORMATS[path.suffix.lower()] == "xdmf" and importlib.util.find_spec("h5py") is None:
        raise SurfaceError(f"cannot write {output}: .xdmf files need the package h5py (pip install h5py)")
    folder = path.parent
    if not folder.is_dir():
        raise SurfaceError(f"cannot write {output}: no folder {str(folder)!r}")
    if path.is_dir():
        raise SurfaceError(f"cannot write {output}: it is a folder")
    probe = folder / f".{path.name}.{os.getpid()}.probe"
    try:  # (os.access says yes to root on a read-only mount)
        probe.open("wb").close()
        probe.unlink()
    except OSError as exc:
        raise SurfaceError(f"cannot write {output}: {exc.strerror or exc}") from None


def _add_mesh_options(p: argparse.ArgumentParser) -> None:
    """mesh()'s settings, shared by ``singmesh mesh`` and ``singmesh sweep``."""
    p.add_argument("--coarse", type=int, default=32,
                   help="boxes per axis of the uniform subdivision (power of two; default 32)")
    p.add_argument("--fine", type=int, default=256,
                   help="boxes per axis at the deepest refinement (power of two; default 256)")
    p.add_argument("--size", choices=("uniform", "curvature"), default="uniform",
                   help="triangle sizes: uniform (about box/coarse; the default) or by the curvature "
                        "(edges about sqrt(8 chord / max|k|) within --min-edge .. --max-edge)")
    p.add_argument("--min-edge", type=float, help="with --size curvature: shortest edge, fraction of the box "
                   "(default 1/fine)")
    p.add_argument("--max-edge", type=float, help="with --size curvature: longest edge, fraction of the box "
                   "(default 1/8)")
    p.add_argument("--chord", type=float, help="with --size curvature: chord tolerance, fraction of the box "
                   "(default 0.001)")
    p.add_argument("--no-curvature", action="store_true",
                   help="do not write the per-vertex curvatures (gaussian_curvature, mean_curvature, k1, k2), "
                        "which go by default as point data into .ply .vtk .vtu files")
    p.add_argument("--no-improve", action="store_true",
                   help="keep the triangles as the boxes make them (vertices at the lattice crossings; "
                        "by default flips and moves on the surface make them well-shaped)")
    p.add_argument("--max-memory", metavar="SIZE",
                   help="refuse a request estimated to need more memory than this (e.g. 2G, 512M; "
                        "the machine's available memory is always a limit)")


def _mesh_settings(args: argparse.Namespace) -> dict:
    """The keyword arguments of mesh() from the options of :func:`_add_mesh_options`."""
    return {"coarse": args.coarse, "fine": args.fine, "improve": not args.no_improve, "size": args.size,
            "min_edge": args.min_edge, "max_edge": args.max_edge, "chord": args.chord,
            "max_memory": args.max_memory}


def _mesh_command(argv: list[str]) -> int:
    from .api import DEFAULT_BOX, mesh

    p = _Parser(prog="singmesh mesh", description="Mesh F(x, y, z) = 0 in a box.")
    p.add_argument("args", nargs="*", metavar="EQUATION [name=value ...]",
                   help='the equation, e.g. "4(x^2+y^2+z^2) + 16 x y z - 1", then parameter values '
                        "(with --defs: parameter values only)")
    p.add_argument("-o", "--output", help="mesh file; the format comes from the suffix "
                   "(.ply .obj .stl .vtk .vtu .off; .html: a page with the interactive 3-D view)")
    p.add_argument("--box", nargs=6, type=float, metavar=("X0", "X1", "Y0", "Y1", "Z0", "Z1"),
                   help="the region meshed (default -2 2 -2 2 -2 2, or the definition's box)")
    _add_mesh_options(p)
    p.add_argument("--defs", metavar="FILE", help="a SingSurf definition file; mesh the definition --name")
    p.add_argument("--name", help="the definition to mesh (with --defs)")
    argv, numbers = _take_box(argv)
    args = _parse_with_equation(p, argv)
    box = None if numbers is None else [numbers[0:2], numbers[2:4], numbers[4:6]]
    if args.output:
        _check_output(args.output)
    if args.defs:
        if not args.name:
            raise SurfaceError("--defs needs --name NAME: the definition to mesh (singmesh defs FILE lists them)")
        d = find_definition(read_definitions(args.defs), args.name)
        surface = d.surface(**_params(args.args))
        box = box or d.box or DEFAULT_BOX
    else:
        if args.name:
            raise SurfaceError("--name goes with --defs FILE")
        if not args.args:
            raise SurfaceError('give the equation, e.g. singmesh mesh "x^2+y^2-z^2", or --defs FILE --name NAME')
        surface = args.args[0]
        params = _params(args.args[1:])
        box = box or DEFAULT_BOX
    sizing = {"size": args.size, "min_edge": args.min_edge, "max_edge": args.max_edge, "chord": args.chord}
    m = mesh(surface, box, coarse=args.coarse, fine=args.fine, improve=not args.no_improve, **sizing,
             max_memory=args.max_memory,
             **({} if args.defs else params))
    print(m.report_text())
    if args.output:
        try:
            path = m.write(args.output, curvature=not args.no_curvature)
        except (ValueError, OSError) as exc:
            reason = exc.strerror if isinstance(exc, OSError) and exc.strerror else str(exc).splitlines()[0]
            print(f"singmesh: error: cannot write {args.output}: {reason}", file=sys.stderr)
            return 2
        print(f"written              {path}")
        if m.singular_curves and FORMATS.get(path.suffix.lower()) not in LINE_FORMATS + ("html",):
            print(f"curves written       {path.with_suffix('.curves.vtk')} (the format has no line cells)")
    return 0


def _take_param(argv: list[str]) -> tuple[list[str], tuple[str, float, float] | None]:
    """``argv`` without ``--param NAME LO HI``, and the three (numbers read as :func:`_take_box` does)."""
    rest, given = _take_option(argv, "--param", 3,
                               "--param is given twice: one parameter is swept (give the others as name=value)")
    if given is None:
        return argv, None
    if len(given) < 3 or not all(_is_number(w) for w in given[1:]):
        raise SurfaceError(f"--param takes a name and two numbers, NAME LO HI; got {' '.join(given)!r}")
    return rest, (given[0], float(given[1]), float(given[2]))


def _sweep_command(argv: list[str]) -> int:
    from .api import DEFAULT_BOX
    from .sweeps import sweep

    p = _Parser(prog="singmesh sweep",
                description="Mesh F(x, y, z; a) = 0 at N values of a: one mesh and picture per frame, "
                            "an animation and DIR/sweep.json, the singular points frame by frame.")
    p.add_argument("args", nargs="*", metavar="EQUATION [name=value ...]",
                   help='the equation with the parameter, e.g. "x^2 + y^2 - (z^2 - a)^2", then the values '
                        "of its other parameters")
    # (Taken out before argparse, as --box is: LO may be -1e-3; listed here for --help.)
    p.add_argument("--param", nargs=3, metavar=("NAME", "LO", "HI"),
                   help="the parameter swept, from LO to HI (both included)")
    p.add_argument("--frames", type=int, default=9, help="number of values of the parameter (default 9)")
    p.add_argument("--out", required=True, metavar="DIR", help="the folder written")
    p.add_argument("--box", nargs=6, type=float, metavar=("X0", "X1", "Y0", "Y1", "Z0", "Z1"),
                   help="the region meshed, the same for every frame (default -2 2 -2 2 -2 2)")
    _add_mesh_options(p)
    p.add_argument("--format", default="ply", help="the mesh files' format (suffix; default ply)")
    p.add_argument("--animation", default="sweep.gif", metavar="FILE",
                   help="the animation's file name in DIR: .gif (default sweep.gif) or .mp4 (needs "
                        "imageio-ffmpeg); 'none' for no animation")
    p.add_argument("--fps", type=float, default=4.0, help="animation frames per second (default 4)")
    p.add_argument("--picture-size", type=int, default=480, metavar="PX",
                   help="side of each frame's picture in pixels (default 480; 0: no pictures)")
    p.add_argument("--jobs", type=int, default=1, metavar="N", help="frames meshed at once (default 1)")
    p.add_argument("--scheduler", metavar="ADDRESS",
                   help="mesh the frames on Dask: 'local' (a LocalCluster of --jobs worker processes) or "
                        "a scheduler's address, e.g. tcp://10.0.0.5:8786 (same files, byte for byte)")
    p.add_argument("--quiet", action="store_true", help="no progress bar and no table")
    p.add_argument("--defs", metavar="FILE", help="a SingSurf definition file; sweep the definition --name "
                   "(on its box unless --box is given, its other parameters at the file's values)")
    p.add_argument("--name", help="the definition to sweep (with --defs)")
    argv, numbers = _take_box(argv)
    argv, swept = _take_param(argv)
    args = _parse_with_equation(p, argv)
    if swept is None:
        raise SurfaceError("give the parameter swept and its range: --param NAME LO HI")
    box = None if numbers is None else [numbers[0:2], numbers[2:4], numbers[4:6]]
    if args.defs:
        if not args.name:
            raise SurfaceError("--defs needs --name NAME: the definition to sweep (singmesh defs FILE lists them)")
        d = find_definition(read_definitions(args.defs), args.name)
        d.surface()  # a definition that does not read is said with its place in the file
        # The file's parameter values, but the one swept, under those given here.
        surface = d.equation
        params = {**{k: str(v) for k, v in d.parameters.items() if k != swept[0]}, **_params(args.args)}
        box = box or d.box
    else:
        if args.name:
            raise SurfaceError("--name goes with --defs FILE")
        if not args.args:
            raise SurfaceError('give the equation, e.g. singmesh sweep "x^2+y^2-(z^2-a)^2" --param a -1 1 '
                               "--out DIR, or --defs FILE --name NAME")
        surface, params = args.args[0], _params(args.args[1:])
    box = box or DEFAULT_BOX
    animation = None if args.animation.lower() == "none" or args.picture_size == 0 else args.animation
    result = sweep(surface, *swept, args.frames, box, out=args.out, **_mesh_settings(args),
                   curvature=not args.no_curvature, mesh_format=args.format, animation=animation,
                   fps=args.fps, picture_size=args.picture_size, jobs=args.jobs, scheduler=args.scheduler,
                   progress=not args.quiet, **params)
    if not args.quiet:
        print(result.table())
        for b in result.bifurcations:
            text = f"{_counts_text(b['forms_before'], b['curves_before'])} -> " \
                   f"{_counts_text(b['forms_after'], b['curves_after'])}"
            if b["euler_before"] != b["euler_after"] or b["components_before"] != b["components_after"]:
                text += (f"; Euler characteristic {b['euler_before']} -> {b['euler_after']}, "
                         f"components {b['components_before']} -> {b['components_after']}")
            print(f"change between {swept[0]} = {b['between'][0]:.6g} and {b['between'][1]:.6g}: {text}")
        print(f"written              {result.folder / 'sweep.json'}")
        if result.animation is not None:
            print(f"animation            {result.animation}")
    return 0


def _counts_text(points: dict, curves: dict) -> str:
    text = " + ".join(f"{n} {t}" for t, n in points.items()) or "none"
    if curves:
        text += " (curves: " + " + ".join(f"{n} {t}" for t, n in curves.items()) + ")"
    return text


def _defs_command(argv: list[str]) -> int:
    p = _Parser(prog="singmesh defs",
                                description="List the definitions of a SingSurf .defs file.")
    p.add_argument("file")
    p.add_argument("--name", help="show this definition whole")
    p.add_argument("--check", action="store_true",
                   help="read every implicit surface and say whether it reads (and why not)")
    args = p.parse_args(argv)
    definitions = read_definitions(args.file)
    if args.name:
        d = find_definition(definitions, args.name)
        print(f"{d.name}  ({' / '.join(d.group) or 'no group'}; {d.type}; {d.where})")
        print(f"box         {_fmt_box(d.box)}")
        for k, v in d.parameters.items():
            print(f"parameter   {k} = {v}")
        for k, v in d.options.items():
            print(f"option      {k}: {' '.join(f'{a}={b}' for a, b in v.items())}")
        print(d.equation)
        return 0
    group = None
    reads = refused = 0
    for d in definitions:
        if d.group != group:
            group = d.group
            print(" / ".join(group) or "(no group)")
        line = f"  {d.name:<40s} {d.type:<6s} {_fmt_box(d.box)}"
        if d.parameters:
            line += "  " + " ".join(f"{k}={v}" for k, v in d.parameters.items())
        if args.check and d.type == "asurf":
            try:
                s = d.surface()
                line += f"\n      reads: degree {s.degree}"
                reads += 1
            except SurfaceError as exc:
                line += f"\n      does not read: {exc}"
                refused += 1
        print(line)
    if args.check:
        print(f"{len(definitions)} definitions; of the implicit surfaces {reads} read, {refused} do not")
    return 0


def _fmt_box(box) -> str:
    if box is None:
        return "(default box)"
    return " x ".join(f"[{lo:g}, {hi:g}]" for lo, hi in box)


def _classify_command(argv: list[str]) -> int:
    from singmesh.skeleton.classify import classify_command

    return classify_command(argv)


def _gallery_command(argv: list[str]) -> int:
    script = Path(__file__).resolve().parent.parent / "gallery" / "generate.py"
    if not script.exists():
        print("singmesh: error: the gallery script is in the source tree (gallery/generate.py); "
              "run it from a checkout", file=sys.stderr)
        return 2
    from .extras import require

    # Before the script's imports, which would end in a traceback.
    require("singmesh gallery", ["matplotlib", "tqdm"] + (["tomli"] if sys.version_info < (3, 11) else []),
            extra="gallery")
    if "--scheduler" in argv or any(a.startswith("--scheduler=") for a in argv):
        require("--scheduler (Dask)", ["dask", "distributed"], extra="dask")
    sys.argv = [str(script)] + argv
    runpy.run_path(str(script), run_name="__main__")
    return 0


COMMANDS = {"mesh": _mesh_command, "defs": _defs_command, "classify": _classify_command,
            "gallery": _gallery_command, "sweep": _sweep_command}


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    if not argv or argv[0] in ("-h", "--help") or argv[0] not in COMMANDS:
        print("usage: singmesh {mesh,defs,classify,gallery,sweep} ...\n"
              '  singmesh mesh "x^2+y^2-z^2" -o cone.ply [--box X0 X1 Y0 Y1 Z0 Z1] [--coarse N] [a=1 ...]\n'
              "  singmesh mesh --defs FILE --name NAME -o out.ply [a=1 ...]\n"
              "  singmesh defs FILE [--check] [--name NAME]\n"
              '  singmesh classify "x^2+y^2-z^2" --at 0 0 0\n'
              "  singmesh gallery [--out DIR] [--only NAME ...] [--jobs N] [--scheduler local|ADDRESS]\n"
              '  singmesh sweep "x^2+y^2-(z^2-a)^2" --param a -1 1 --frames 9 --out DIR [--box ...] '
              "[--jobs N] [--scheduler local|ADDRESS]", file=sys.stderr)
        return 0 if argv and argv[0] in ("-h", "--help") else 2
    import warnings

    def one_line(message, category, *rest, **kw):
        # A warning is one line, as errors are: no source line under it.
        print(f"singmesh: warning: {message}", file=sys.stderr)

    warnings.showwarning = one_line
    stdout, sys.stdout = sys.stdout, _QuietPipe(sys.stdout)
    try:
        return COMMANDS[argv[0]](argv[1:])
    except SurfaceError as exc:
        print(f"singmesh: error: {exc}", file=sys.stderr)
        return 2
    except MemoryError:
        print("singmesh: error: out of memory (lower --fine or --coarse, or see --max-memory)", file=sys.stderr)
        return 2
    finally:
        sys.stdout = stdout


class _QuietPipe:
    """Standard output that a reader closing it early (``singmesh mesh ... | head``) does not stop.

    The rest of the output goes to the null device, quietly: the command
    still does its work (writes its mesh file) and exits with its own
    status, where a bare ``print`` would end in a BrokenPipeError traceback.
    """

    def __init__(self, stream):
        self._stream = stream
        self._closed = False

    def write(self, text: str) -> int:
        if not self._closed:
            try:
                return self._stream.write(text)
            except BrokenPipeError:
                self._drop()
        return len(text)

    def flush(self) -> None:
        if not self._closed:
            try:
                self._stream.flush()
            except BrokenPipeError:
                self._drop()

    def _drop(self) -> None:
        self._closed = True
        try:
            # What is still buffered goes to the null device when Python
            # flushes the stream at exit, not to the closed pipe.
            null = os.open(os.devnull, os.O_WRONLY)
            os.dup2(null, self._stream.fileno())
            os.close(null)
        except (OSError, ValueError, AttributeError):
            pass

    def __getattr__(self, name):
        return getattr(self._stream, name)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
