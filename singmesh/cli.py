"""The ``singmesh`` command line.

``singmesh mesh "EQUATION" -o out.ply [--box X0 X1 Y0 Y1 Z0 Z1] [--coarse N] [--fine N] [a=1 ...]``
meshes, writes and prints the report; ``singmesh classify "EQUATION" --at X Y Z``
names a singular point; ``singmesh gallery ...`` builds the gallery.  Bad
input prints one error line and exits with status 2.
"""

from __future__ import annotations

import argparse
import runpy
import sys
from pathlib import Path

from .errors import SurfaceError


def _params(items: list[str]) -> dict[str, str]:
    out = {}
    for item in items:
        if "=" not in item:
            raise SurfaceError(f"a parameter is given as name=value, not {item!r}")
        name, value = item.split("=", 1)
        out[name.strip()] = value.strip()
    return out


def _mesh_command(argv: list[str]) -> int:
    from .api import DEFAULT_BOX, mesh

    p = argparse.ArgumentParser(prog="singmesh mesh", description="Mesh F(x, y, z) = 0 in a box.")
    p.add_argument("equation", help='e.g. "4(x^2+y^2+z^2) + 16 x y z - 1"')
    p.add_argument("params", nargs="*", metavar="name=value", help="parameter values")
    p.add_argument("-o", "--output", help="mesh file; the format comes from the suffix "
                   "(.ply .obj .stl .vtk .vtu .off)")
    p.add_argument("--box", nargs=6, type=float, metavar=("X0", "X1", "Y0", "Y1", "Z0", "Z1"),
                   help="the region meshed (default -2 2 -2 2 -2 2)")
    p.add_argument("--coarse", type=int, default=32,
                   help="boxes per axis of the uniform subdivision (power of two; default 32)")
    p.add_argument("--fine", type=int, default=256,
                   help="boxes per axis at the deepest refinement (power of two; default 256)")
    args = p.parse_args(argv)
    box = DEFAULT_BOX if args.box is None else [args.box[0:2], args.box[2:4], args.box[4:6]]
    m = mesh(args.equation, box, coarse=args.coarse, fine=args.fine, **_params(args.params))
    print(m.report_text())
    if args.output:
        try:
            path = m.write(args.output)
        except (ValueError, OSError) as exc:
            print(f"singmesh: error: cannot write {args.output}: {exc}", file=sys.stderr)
            return 2
        print(f"written              {path}")
    return 0


def _classify_command(argv: list[str]) -> int:
    from singmesh.skeleton.classify import classify_command

    return classify_command(argv)


def _gallery_command(argv: list[str]) -> int:
    script = Path(__file__).resolve().parent.parent / "gallery" / "generate.py"
    if not script.exists():
        print("singmesh: error: the gallery script is in the source tree (gallery/generate.py); "
              "run it from a checkout", file=sys.stderr)
        return 2
    sys.argv = [str(script)] + argv
    runpy.run_path(str(script), run_name="__main__")
    return 0


COMMANDS = {"mesh": _mesh_command, "classify": _classify_command, "gallery": _gallery_command}


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    if not argv or argv[0] in ("-h", "--help") or argv[0] not in COMMANDS:
        print("usage: singmesh {mesh,classify,gallery} ...\n"
              '  singmesh mesh "x^2+y^2-z^2" -o cone.ply [--box X0 X1 Y0 Y1 Z0 Z1] [--coarse N] [a=1 ...]\n'
              '  singmesh classify "x^2+y^2-z^2" --at 0 0 0\n'
              "  singmesh gallery [--out DIR] [--only NAME ...] [--jobs N]", file=sys.stderr)
        return 0 if argv and argv[0] in ("-h", "--help") else 2
    try:
        return COMMANDS[argv[0]](argv[1:])
    except SurfaceError as exc:
        print(f"singmesh: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
