"""Parameter sweeps (singmesh sweep), Dask scale-out, friendly missing extras (issue #14, items 3-5).

The family swept is the textbook A3 transition x^2 + y^2 - (z^2 - a)^2
under a float rotation and shift, typed as 15-digit decimals: no singular
point for a < 0, an A3 at the centre for a = 0, two A1 (cones) at
z = +-sqrt(a) for a > 0.  The expected table comes from sympy's solutions
of F = grad F = 0 of the unrotated family at each frame's value (exact
rationals), mapped through the rotation, and the branches from
tests/oracles.py's count on a small sphere; the meshes read back from the
files are checked against F evaluated here with numpy.
"""

from __future__ import annotations

import json
import sys
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest
import sympy

import meshcheck as mc
import singmesh
from oracles import branches_on_sphere
from singmesh.cli import main
from singmesh.errors import SurfaceError

ROOT = Path(__file__).resolve().parent.parent
BOX = ((-1.0, 1.0),) * 3
LO, HI, FRAMES = -0.3, 0.3, 5
SMALL = {"coarse": 16, "fine": 64}
xs, ys, zs, As = sympy.symbols("x y z a", real=True)


def _family(seed: int = 20261125) -> tuple[str, np.ndarray, np.ndarray]:
    """The family's text (15-digit decimals, in x, y, z and a), its rotation q and shift c.

    With u = q (p - c): F = u0^2 + u1^2 - (u2^2 - a)^2.
    """
    rng = np.random.default_rng(seed)
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    c = rng.uniform(-0.2, 0.2, 3)
    p = (xs, ys, zs)
    u = [sum(sympy.Float(q[i, j], 17) * (p[j] - sympy.Float(c[j], 17)) for j in range(3)) for i in range(3)]
    poly = sympy.Poly(sympy.expand(u[0] ** 2 + u[1] ** 2 - (u[2] ** 2 - As) ** 2), xs, ys, zs, As)
    terms = [f"{float(k):+.15g}" + "".join(f" {v}^{n}" for v, n in zip("xyza", e) if n) for e, k in poly.terms()]
    return " ".join(terms), q, c


def _expected(value: float, q: np.ndarray, c: np.ndarray) -> list[tuple[np.ndarray, str]]:
    """Singular points of the frame by sympy on the unrotated family, and their types.

    Type: A1 where the Hessian has rank 3; the only other point, at a = 0,
    is x^2 + y^2 - z^4, the normal form of A3 (Hessian rank 2).
    """
    a = sympy.Rational(Fraction(value))
    f = xs ** 2 + ys ** 2 - (zs ** 2 - a) ** 2
    eqs = [f] + [sympy.diff(f, v) for v in (xs, ys, zs)]
    out = []
    for sol in sympy.solve(eqs, [xs, ys, zs], dict=True):
        u = np.array([float(sol.get(v, v)) for v in (xs, ys, zs)])
        rank = sympy.hessian(f, (xs, ys, zs)).subs(sol).rank()
        out.append((c + q.T @ u, "A1" if rank == 3 else "A3"))
    return out


@pytest.fixture(scope="module")
def family_sweep(tmp_path_factory):
    text, q, c = _family()
    out = tmp_path_factory.mktemp("sweep")
    result = singmesh.sweep(text, "a", LO, HI, FRAMES, BOX, out=out, picture_size=160, **SMALL)
    return result, text, q, c


def test_sweep_table_is_the_a3_transition(family_sweep):
    result, text, q, c = family_sweep
    frames = result.frames
    assert [f["value"] for f in frames] == [-0.3, -0.15, 0.0, 0.15, 0.3]
    counts = []
    for fr in frames:
        assert not fr.get("error"), fr
        want = _expected(fr["value"], q, c)
        got = fr["singular_points"]
        assert len(got) == len(want), (fr["value"], got, want)
        for point, kind in want:
            d = [np.linalg.norm(np.array(g["point"]) - point) for g in got]
            g = got[int(np.argmin(d))]
            assert min(d) < 1e-6, (fr["value"], g["point"], point)
            assert g["type"] == kind
            # Two sheets meet at a cone (A1) and at two cones touching (A3).
            F = _numpy_f(q, c, fr["value"])
            assert g["branches"] == branches_on_sphere(F, point, 0.02) == 2
        counts.append(fr["counts"])
    # a < 0: none; a = 0: A3; a > 0: two A1.  The table says where it changes.
    assert counts == [{}, {}, {"A3": 1}, {"A1": 2}, {"A1": 2}]
    # By hand, the box cutting each end in one circle: a tube (annulus) for
    # a < 0; two discs touching at the A3 (1 + 1 - 1); two discs and the
    # sphere between the A1 points, glued at them (1 + 2 + 1 - 2).
    assert [fr["euler"] for fr in frames] == [0, 0, 1, 2, 2]
    assert [fr["components"] for fr in frames] == [1] * FRAMES
    assert [(b["frames"], b["before"], b["after"]) for b in result.bifurcations] == [
        ([1, 2], {}, {"A3": 1}), ([2, 3], {"A3": 1}, {"A1": 2})]
    on_disk = json.loads((result.folder / "sweep.json").read_text(encoding="utf-8"))
    assert on_disk["frames"] == frames and on_disk["parameter"] == "a"
    assert on_disk["settings"]["coarse"] == 16 and on_disk["settings"]["fine"] == 64
    assert "time" not in json.dumps(on_disk)  # timings go to times.json, apart
    times = json.loads((result.folder / "times.json").read_text(encoding="utf-8"))
    assert len(times["frames"]) == FRAMES and all(t > 0 for t in times["frames"])
    assert "A3" in result.table().splitlines()[2] and "2 A1" in result.table().splitlines()[3]


def _numpy_f(q: np.ndarray, c: np.ndarray, a: float):
    """F of the frame, evaluated here (not through singmesh) on (..., 3) points."""
    def f(p):
        u = (np.asarray(p, float) - c) @ q.T
        return u[..., 0] ** 2 + u[..., 1] ** 2 - (u[..., 2] ** 2 - a) ** 2
    return f


def test_sweep_files_are_the_meshes_and_the_animation(family_sweep):
    import imageio.v3 as iio
    import meshio

    result, text, q, c = family_sweep
    for fr in result.frames:
        m = meshio.read(result.folder / fr["mesh"])
        v, f = m.points, m.cells_dict["triangle"]
        assert len(f) == fr["faces"] > 100
        F = _numpy_f(q, c, fr["value"])
        h = 1e-6
        grad = np.stack([(F(v + h * e) - F(v - h * e)) / (2 * h) for e in np.eye(3)], axis=1)
        dist = np.abs(F(v)) / np.maximum(np.linalg.norm(grad, axis=1), 1e-3)
        assert dist.max() < 1e-6
        assert mc.euler(v, f) == fr["euler"]
        assert not mc.non_manifold_edges(f)
        assert mc.boundary_edges_off_box(v, f, np.array(BOX)) == []
        picture = iio.imread(result.folder / fr["picture"])
        assert picture.shape[:2] == (160, 160)
    gif = iio.imread(result.animation, index=None)
    assert result.animation.name == "sweep.gif" and gif.shape[:3] == (FRAMES, 160, 160)
    assert np.abs(gif[0].astype(int) - gif[-1].astype(int)).max() > 0  # the frames differ: it moves
    # A fixed box and camera: the box's faint frame lines are at the same pixels.
    assert np.array_equal(gif[0][:4], gif[-1][:4])


def test_sweep_a_failing_frame_is_recorded_and_the_others_are_meshed(tmp_path):
    # 1/a is undefined at a = 0, the middle frame, only.
    result = singmesh.sweep("x^2 + y^2 + z^2 - 1 + 0.01/a", "a", -1, 1, 3, BOX, out=tmp_path, coarse=8, fine=32,
                            picture_size=0, animation=None)
    errors = [bool(fr.get("error")) for fr in result.frames]
    assert errors == [False, True, False]
    assert result.frames[0]["faces"] > 0 and result.frames[2]["faces"] > 0
    assert "error" in result.table().splitlines()[1]
    assert result.bifurcations == []


def test_sweep_bad_input_is_one_line(tmp_path, capsys):
    with pytest.raises(SurfaceError, match="does not depend on a"):
        singmesh.sweep("x^2 + y^2 - z^2 - 1", "a", 0, 1, 3, out=tmp_path / "never")
    with pytest.raises(SurfaceError, match="unknown symbol a"):
        singmesh.sweep("x^2 + y^2 - z^2 - a", "b", 0, 1, 3, out=tmp_path / "never")
    with pytest.raises(SurfaceError, match="frames"):
        singmesh.sweep("x^2 + y^2 - z^2 - a", "a", 0, 1, 0, out=tmp_path / "never")
    # mesh()'s settings are refused once, before the frames, not in each.
    with pytest.raises(SurfaceError, match="at least coarse"):
        singmesh.sweep("x^2 + y^2 - z^2 - a", "a", 0, 1, 2, out=tmp_path / "never", coarse=64, fine=32)
    with pytest.raises(SurfaceError, match="size must be"):
        singmesh.sweep("x^2 + y^2 - z^2 - a", "a", 0, 1, 2, out=tmp_path / "never", size="tiny")
    with pytest.raises(SurfaceError, match="cannot also be given"):
        singmesh.sweep("x^2 + y^2 - z^2 - a", "a", 0, 1, 2, out=tmp_path / "never", a=1)
    assert not (tmp_path / "never").exists()
    for argv, words in [
        (["sweep", "x^2 - a", "--out", str(tmp_path / "never")], "--param NAME LO HI"),
        (["sweep", "x^2 - a", "--param", "a", "0", "--out", str(tmp_path / "never")], "--param takes"),
        (["sweep", "x^2 - a", "--param", "x", "0", "1", "--out", str(tmp_path / "never")], "not a parameter"),
        (["sweep", "x^2 - a", "--param", "a", "0", "1", "--out", str(tmp_path / "never"), "--animation", "s.avi"],
         ".gif or .mp4"),
    ]:
        assert main(argv) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and err[0].startswith("singmesh: error:") and words in err[0], err
    assert not (tmp_path / "never").exists()


def test_cli_sweep_on_a_local_dask_cluster_writes_what_the_python_sweep_writes(tmp_path, capsys):
    pytest.importorskip("distributed", reason="dask.distributed is not installed (pip install 'singmesh[dask]')")
    # A negative bound in exponent notation is a number, not an option.
    args = ["x^2 + y^2 - z^2 - a", "--param", "a", "-2e-1", "0.2", "--frames", "3", "--box", "-1", "1", "-1", "1",
            "-1", "1", "--coarse", "8", "--fine", "32", "--picture-size", "96"]
    # --scheduler local: a LocalCluster of two worker processes, started and closed by the sweep.
    assert main(["sweep", *args, "--out", str(tmp_path / "cli"), "--jobs", "2", "--scheduler", "local",
                 "--quiet"]) == 0
    assert json.loads((tmp_path / "cli" / "times.json").read_text())["scheduler"] == "local"
    local = singmesh.sweep("x^2 + y^2 - z^2 - a", "a", -0.2, 0.2, 3, BOX, out=tmp_path / "py", coarse=8, fine=32,
                           picture_size=96)
    assert local.frames[1]["counts"] == {"A1": 1}  # the cone at a = 0 only
    _same_files(tmp_path / "cli", tmp_path / "py", skip={"times.json"})
    assert main(["sweep", *args, "--out", str(tmp_path / "shown")]) == 0
    out = capsys.readouterr().out
    assert "a = 0 " in out and "1 A1" in out and "change between a = -0.2 and 0: none -> 1 A1" in out


def _same_files(a: Path, b: Path, skip=()) -> None:
    names = sorted(p.name for p in a.iterdir() if p.name not in skip)
    assert names == sorted(p.name for p in b.iterdir() if p.name not in skip) and names
    for name in names:
        assert (a / name).read_bytes() == (b / name).read_bytes(), name


# ---------------------------------------------------------------- Dask
def test_sweep_and_gallery_on_dask_are_byte_for_byte_the_local_runs(tmp_path):
    pytest.importorskip("distributed", reason="dask.distributed is not installed (pip install 'singmesh[dask]')")
    from distributed import Client, LocalCluster

    text, q, c = _family()
    settings = dict(coarse=8, fine=32, picture_size=96)
    local = singmesh.sweep(text, "a", 0.0, 0.3, 3, BOX, out=tmp_path / "local", **settings)
    gallery = _load_generate()
    only = ["--only", "sphere", "cross-cap", "--coarse", "8", "--fine", "32", "--size", "96", "--quiet"]
    assert gallery.main(["--out", str(tmp_path / "gallery_local"), *only]) == 0
    # A scheduler and two worker processes on this machine: the gallery reaches
    # it by address, the sweep through a Client of the caller's (left open).
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster, \
            Client(cluster) as client:
        address = cluster.scheduler_address
        on_dask = singmesh.sweep(text, "a", 0.0, 0.3, 3, BOX, out=tmp_path / "dask", scheduler=client,
                                 **settings)
        assert client.status == "running"
        assert gallery.main(["--out", str(tmp_path / "gallery_dask"), "--scheduler", address, *only]) == 0
    assert on_dask.data == local.data
    assert local.frames[0]["counts"] == {"A3": 1} and local.frames[2]["counts"] == {"A1": 2}
    _same_files(tmp_path / "local", tmp_path / "dask", skip={"times.json"})
    assert "Client" in json.loads((tmp_path / "dask" / "times.json").read_text())["scheduler"]
    files = [p.name for p in (tmp_path / "gallery_local").iterdir() if p.suffix in (".ply", ".obj", ".png")]
    assert len(files) == 6
    for name in files:
        assert (tmp_path / "gallery_local" / name).read_bytes() == (tmp_path / "gallery_dask" / name).read_bytes()
    records = [json.loads((tmp_path / d / "report.json").read_text())["entries"] for d in ("gallery_local",
                                                                                          "gallery_dask")]
    for r in records:  # the timings, which report.json holds beside the results
        for e in r:
            e.pop("time"), e.pop("render_time")
            e["report_text"] = [line for line in e["report_text"].splitlines() if not line.startswith("time ")]
    assert records[0] == records[1] and all(e["ok"] for e in records[0])


def _load_generate():
    import importlib.util

    spec = importlib.util.spec_from_file_location("gallery_generate_for_dask", ROOT / "gallery" / "generate.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


# ---------------------------------------------------------------- missing extras
@pytest.mark.parametrize("blocked, argv, extra", [
    ("tqdm", ["gallery", "--only", "sphere"], "gallery"),
    ("matplotlib", ["gallery", "--only", "sphere"], "gallery"),
    ("imageio", ["sweep", "x^2+y^2-z^2-a", "--param", "a", "0", "1"], "sweep"),
    ("matplotlib", ["sweep", "x^2+y^2-z^2-a", "--param", "a", "0", "1", "--animation", "none"], "sweep"),
    ("distributed", ["sweep", "x^2+y^2-z^2-a", "--param", "a", "0", "1", "--scheduler", "local"], "dask"),
    ("distributed", ["gallery", "--only", "sphere", "--scheduler", "local"], "dask"),
])
def test_a_missing_extra_is_one_line_naming_the_install(blocked, argv, extra, monkeypatch, tmp_path, capsys):
    # None in sys.modules: the import fails as for a package not installed.
    monkeypatch.setitem(sys.modules, blocked, None)
    out = tmp_path / "out"
    assert main([*argv, "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("singmesh: error:"), err
    assert f"pip install 'singmesh[{extra}]'" in err[0] and blocked in err[0]
    assert not out.exists()  # said before any work


def test_the_renderer_without_matplotlib_names_the_install(monkeypatch):
    import importlib

    from singmesh.extras import MissingExtraError

    monkeypatch.setitem(sys.modules, "matplotlib", None)
    monkeypatch.delitem(sys.modules, "singmesh.render", raising=False)
    with pytest.raises(MissingExtraError, match=r"drawing pictures needs matplotlib.*pip install 'singmesh\[sweep\]'"):
        importlib.import_module("singmesh.render")


DEFS = """\
<definition name="A3 family" type="asurf">
x^2 + y^2 - (z^2 - a)^2 + b;
<parameter name="a" value="0.1" />
<parameter name="b" value="0.5" />
<variable name="x" min="-1" max="1">
<variable name="y" min="-1" max="1">
<variable name="z" min="-0.9" max="0.9">
</definition>
"""


def test_cli_sweeps_a_definition_of_a_defs_file(tmp_path):
    path = tmp_path / "family.defs"
    path.write_text(DEFS, encoding="utf-8")
    args = ["sweep", "--defs", str(path), "--name", "A3 family", "--param", "a", "0", "0.25", "--frames", "2",
            "--coarse", "8", "--fine", "32", "--picture-size", "0", "--quiet"]
    # b = 0.5 from the file: x^2 + y^2 + 0.5 = (z^2 - a)^2 has no singular point (F = 0.5 there).
    assert main([*args, "--out", str(tmp_path / "file")]) == 0
    data = json.loads((tmp_path / "file" / "sweep.json").read_text())
    assert data["box"] == [[-1, 1], [-1, 1], [-0.9, 0.9]] and data["params"] == {"b": "0.5"}
    assert [f["counts"] for f in data["frames"]] == [{}, {}]
    # b = 0 given here: the A3 at a = 0, two A1 at z = +-0.5 at a = 0.25.
    assert main([*args, "b=0", "--out", str(tmp_path / "given")]) == 0
    frames = json.loads((tmp_path / "given" / "sweep.json").read_text())["frames"]
    assert [f["counts"] for f in frames] == [{"A3": 1}, {"A1": 2}]
    assert sorted(p["point"][2] for p in frames[1]["singular_points"]) == pytest.approx([-0.5, 0.5], abs=1e-9)


def test_sweep_mp4_animation(tmp_path):
    pytest.importorskip("imageio_ffmpeg", reason="MP4 needs imageio-ffmpeg (pip install 'singmesh[video]')")
    import imageio.v3 as iio

    result = singmesh.sweep("x^2 + y^2 - z^2 - a", "a", -0.2, 0.2, 3, BOX, out=tmp_path, coarse=8, fine=32,
                            picture_size=96, animation="cone.mp4", fps=2)
    frames = iio.imread(result.animation, index=None, extension=".mp4")
    assert frames.shape[:3] == (3, 96, 96)
    # Lossy, but each frame is its picture: nearer to it than to the other frames' pictures.
    pictures = [iio.imread(tmp_path / f["picture"])[..., :3].astype(float) for f in result.frames]
    for i, f in enumerate(frames.astype(float)):
        d = [np.abs(f - p).mean() for p in pictures]
        assert int(np.argmin(d)) == i, d


def test_a_change_of_topology_between_frames_is_a_bifurcation(tmp_path):
    # x^2 + y^2 - z^2 = a in [-1, 1]^3: for a < 0 the two caps of a
    # hyperboloid of two sheets (two discs: Euler characteristic 2, two
    # pieces), for a > 0 one sheet (an annulus: 0, one piece).  The cone
    # between them is at a = 0, no frame: no singular point is seen, the
    # change is.
    result = singmesh.sweep("x^2 + y^2 - z^2 - a", "a", -0.3, 0.3, 2, BOX, out=tmp_path, coarse=16, fine=64,
                            picture_size=0, animation=None, progress=False)
    assert [fr["counts"] for fr in result.frames] == [{}, {}]
    assert [(fr["euler"], fr["components"]) for fr in result.frames] == [(2, 2), (0, 1)]
    [b] = result.bifurcations
    assert b["frames"] == [0, 1] and set(b["changed"]) == {"euler", "components"}
    assert (b["euler_before"], b["euler_after"]) == (2, 0)


def test_a_change_of_real_form_is_a_bifurcation(tmp_path):
    # x^2 + y^2 + a z^2 + z^3 at the origin: a cone (indefinite) for a < 0,
    # an isolated point (definite) for a > 0: an A1 in both frames, of two
    # real forms.
    result = singmesh.sweep("x^2 + y^2 + z^2 (z + a)", "a", -0.3, 0.3, 2, BOX, out=tmp_path, coarse=16, fine=64,
                            picture_size=0, animation=None, progress=False)
    assert [fr["counts"] for fr in result.frames] == [{"A1": 1}, {"A1": 1}]
    [b] = result.bifurcations
    assert "real_form_counts" in b["changed"] and b["forms_before"] != b["forms_after"]
    assert sum(b["forms_before"].values()) == sum(b["forms_after"].values()) == 1


def test_sweep_refusals_before_any_frame(tmp_path):
    with pytest.raises(SurfaceError, match="100000000 frames is more than a sweep takes"):
        singmesh.sweep("x^2 + y^2 + z^2 - a", "a", 0, 1, 100_000_000, BOX, out=tmp_path / "many")
    assert not (tmp_path / "many").exists()
    # A misspelt parameter is named.
    with pytest.raises(SurfaceError, match="the equation has no parameter c"):
        singmesh.sweep("x^2 + y^2 - (z^2 - a)^2", "c", 0, 1, 3, BOX, out=tmp_path / "c")
    # A folder that cannot be written into: said before the frames are meshed.
    blocker = tmp_path / "file"
    blocker.write_text("x")
    with pytest.raises(SurfaceError, match="cannot"):
        singmesh.sweep("x^2 + y^2 + z^2 - a", "a", 0, 1, 3, BOX, out=blocker / "sub")


def test_cli_parameter_values_after_the_options(tmp_path, capsys):
    # As the README writes them: name=value at the end of the line.
    out = tmp_path / "m.ply"
    assert main(["mesh", "x^2 + y^2 - (z^2 - a)^2", "-o", str(out), "--coarse", "16", "--fine", "64",
                 "a=0.1"]) == 0
    assert out.exists()
    assert main(["sweep", "x^2 + y^2 - (z^2 - a)^2 + b", "--param", "a", "-0.3", "0.3", "--frames", "2",
                 "--coarse", "16", "--fine", "64", "--picture-size", "0", "--quiet", "--out", str(tmp_path / "s"),
                 "b=0.1"]) == 0
    data = json.loads((tmp_path / "s" / "sweep.json").read_text(encoding="utf-8"))
    assert data["params"] == {"b": "0.1"} and data["range"] == [-0.3, 0.3]
    # An unknown short option is named as typed, not as a placeholder.
    assert main(["mesh", "x^2 + y^2 + z^2 - 1", "-o", str(out), "-q"]) == 2
    err = capsys.readouterr().err
    assert "-q" in err and "\0" not in err and len(err.strip().splitlines()) == 1
