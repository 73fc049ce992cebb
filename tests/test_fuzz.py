"""Random surfaces through an independent judge (issue #13).

A fast seeded sample of the fuzz cases of :mod:`fuzzcases` (the thousand
are ``make fuzz``), and every failure found by the fuzzing and fixed,
kept as a named case.  The judge checks the mesh with its own F (sympy
rationals), its own singular points and its own sign sample: see
:mod:`fuzzcases`.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest
import sympy as sp

import fuzzcases as fc

#: The sample: seed 2 (``make fuzz`` runs seed 1), coarse 8 / fine 64.
SAMPLE_SEED = 2
SAMPLE_SIZE = 100

#: Cases of the sample the mesher still gets wrong, by name: what the judge
#: finds.  Strict: each is judged, and one that comes out clean fails the
#: test until it is removed from here.
KNOWN: dict[str, str] = {}


def _rotated(text: str, seed: int, shift) -> str:
    """``text`` in coordinates u = Q p - shift (Q from numpy's QR of a seeded
    normal matrix), expanded, its coefficients typed with 15 digits."""
    q, _ = np.linalg.qr(np.random.default_rng(seed).normal(size=(3, 3)))
    u = [sum(float(q[i, j]) * v for j, v in enumerate(fc.XYZ)) - shift[i] for i in range(3)]
    e = sp.sympify(text.replace("^", "**"), locals=dict(zip("xyz", fc.XYZ)))
    p = sp.Poly(sp.expand(e.subs(dict(zip(fc.XYZ, u)), simultaneous=True)), *fc.XYZ)
    terms = []
    for mon, c in zip(p.monoms(), p.coeffs()):
        if abs(float(c)) > 1e-13:
            digits = np.format_float_positional(float(c), precision=15, unique=False, fractional=False, trim="-")
            terms.append("*".join([digits] + [f"{v}^{k}" for v, k in zip("xyz", mon) if k]))
    return " + ".join(terms).replace("+ -", "- ")



def _tilted(text: str, axis, angle: float, centre, shift) -> str:
    """``text`` turned by ``angle`` (radians) about ``axis`` through ``centre`` and
    moved by ``shift``: in coordinates u = c + R (p - c - shift), R the
    rotation (Rodrigues), expanded, its coefficients typed with 15 digits.
    A small turn keeps a surface near the face of the box it was near."""
    k = np.asarray(axis, float) / np.linalg.norm(axis)
    cross = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    q = np.eye(3) + np.sin(angle) * cross + (1 - np.cos(angle)) * cross @ cross
    c, d = np.asarray(centre, float), np.asarray(shift, float)
    u = [float(c[i]) + sum(float(q[i, j]) * (v - float(c[j] + d[j])) for j, v in enumerate(fc.XYZ))
         for i in range(3)]
    e = sp.sympify(text.replace("^", "**"), locals=dict(zip("xyz", fc.XYZ)))
    p = sp.Poly(sp.expand(e.subs(dict(zip(fc.XYZ, u)), simultaneous=True)), *fc.XYZ)
    terms = []
    for mon, cf in zip(p.monoms(), p.coeffs()):
        if abs(float(cf)) > 1e-13:
            digits = np.format_float_positional(float(cf), precision=15, unique=False, fractional=False, trim="-")
            terms.append("*".join([digits] + [f"{v}^{k}" for v, k in zip("xyz", mon) if k]))
    return " + ".join(terms).replace("+ -", "- ")


def _tilted_product(factors, axis, angle: float, centre, shift) -> str:
    """The product of the ``factors`` each :func:`_tilted` alike (the judge sees the factors)."""
    return "*".join(f"({_tilted(f, axis, angle, centre, shift)})" for f in factors)


#: s1-610's factors and box: their double curve runs 0 to 3 cells inside
#: the box's face y = 1.49 (fine 64), where the two sheets' traces are less
#: than a cell apart.
S1_610 = ("-1*y^2 + 7/3*x*z - 6*x*y + 1", "-9/5*z^2 - 7*x*y - 8/7*x - 6/5")
S1_610_BOX = ((-1.78, 0.1399999999999999), (-0.7, 1.49), (-0.03566070717459713, 2.0975177570115155))
#: Two sheets crossing at 14 degrees (slopes +-8) along a parabola 2 cells
#: (fine 64) inside the face y = 1 of [-1, 1]^3, from z = -1 to z = 1: their
#: traces on that face are half a cell apart.
NEAR_FACE = ("y - 0.9375 - 8*(x - 0.1 - 0.2*z^2)", "y - 0.9375 + 8*(x - 0.1 - 0.2*z^2)")

#: Failures the fuzzing found and were fixed: (name, equation as typed, box,
#: coarse, fine).  The judge is the sample's.
REGRESSIONS = [
    # The double curve's ends on the box were placed by three rounds of
    # Newton and a slide along the chord, 1.8e-6 and 3.1e-5 of the box off
    # the two sheets (skeleton/singular_curves.py _clip).
    ("s1-954 curve end on the box",
     "(1.85703211655165*y*z - 0.412406314921561*y^2 - 1.21492690973525*x*z + 0.681677646659092)"
     "*(5*y^2*z + 4/5*x^2 + 1*z + 2/3)", ((-1.0, 1.0),) * 3, 8, 64),
    ("s1-618 curve ends on z = -1",
     "(7*y^3 + 2*x*y*z + 1/4*z + 1/2*y)*(6/7*z^3 + 4/7*y^2*z - 4/3*x*y*z - 3*x*y^2 - 1/2*y*z - 3*x^2 + 8/7)",
     ((-1.0, 1.0),) * 3, 8, 64),
    # The chord from the last vertex inside to the first outside runs nearly
    # along the face y = 0.3517 and the curve bulges out of the box between:
    # rounds that do not shrink the slide wandered along the face (three
    # curve vertices outside the box, one 1.7e-4 of the box off F = 0).
    # Then the second piece's end was still 3.8e-5 of the box off F = 0,
    # the slides having gone the other way along the face; it is bisected
    # now (skeleton/singular_curves.py _bisect_exit); the open edges that
    # came with it (a triangle from one piece's end to the other piece's
    # third vertex, where the curve comes back 7 x-cells further on) went
    # with it.
    ("s1-394 chord along the face",
     "(2.59350408598806*z^3 + 0.874085785897391*x*y*z - 0.464611977952322*x^2*z - 0.391153082439888*x^3"
     " + 0.642097615780808*x*y - 1.48625639687518)*(-1/4*y^2*z - 6*y^3 - 3*x^2*y + 1*x^3 - 8/5*x*z)",
     ((-1.7595813682582748, 0.8984820222372951), (-0.7331491867706155, 0.3516743653565406), (-1.03, 1.07)), 8, 64),
    # A trace's first vertex, a sample of the locus, met only a sample's
    # residual: 8.3e-9 of the box off F = 0 (skeleton/singular_curves.py
    # trace_curves).
    ("s1-220 trace start on the curve", "4/7*y^5 - 1/2*x^3*y^2 - 9/2*x^4*z", ((-1.0, 1.0),) * 3, 8, 64),
    # The pinch point next to the degenerate origin: Newton stopped with a
    # residual under the vertex's but 2.1e-9 of the box off F = 0
    # (skeleton/singular_curves.py _type_changes).
    ("s1-72 pinch point on the curve", "7*x*y*z^4 + 1/2*x^3*y*z^2 + 1*x^4*z^2 - 3/8*x^5*z - 1/3*x^5 - 8*y^3*z",
     ((-2.0, 2.0), (-1.0, 1.0), (-0.5, 0.5)), 8, 64),
    # Two branches of the double curve within a step of each other were
    # merged at a "crossing" Newton left 0.025 off F = 0, 0.0062 of the
    # box by |F| / |grad F| (skeleton/singular_curves.py _crossing_point).
    ("s1-638 crossing off the curve",
     "(0.50443749619891*y*z - 2.75237021685692*x*y - 2.2279695506216*x^2 - 2.3657511302834*x + 0.129930238689852)"
     "*(1*z^2 + 4/3*y*z + 1/3*x)", ((-0.5, 0.5), (-1.0, 1.0), (-2.0, 2.0)), 8, 64),
    # A U-shaped double curve (y (1 - 8 z^2) = 1 in the plane) whose bottom
    # turns within a cell (radius 1/16, the trace's step 1/4): the trace
    # was lost there and the other arm never traced (6 triangles on the
    # traced arm's edges).  Shorter steps follow it round
    # (skeleton/singular_curves.py _trace_one_way, back_at_start).
    ("s1-278 a U-turn within a cell", "(1/2*z - 2/7*y - 7*x)*(8*y*z^2 - 1*y + 1)",
     ((-1.0, 1.0), (-2.0, 2.0), (-1.5, 1.5)), 8, 64),
    # The trace from a sample on the face x = -1 set out along the
    # samples' chord, 45 degrees off the curve, and was lost at once: the
    # curve's end there an "end of the trace" (edges of 8 triangles).  It
    # now sets out again along its first step the other way.
    ("s1-542 a trace starting on a face",
     "(-2.75739675050444*x*y^2 + 1.32011893949751*x^3 - 1.74577391702034*y*z + 0.821208895230908*x*y"
     " - 2.60263968664138)*(0.0562854465832934*z + 1.30049828584968*y - 1.63876856385203)",
     ((-1.0, 1.0), (-2.0, 2.0), (-1.0, 1.0)), 8, 64),
    # Double curves running a cell or a few from a face between their ends
    # on two other faces: the half-sheets between curve and face leave
    # pieces of trace on it, side by side in opposite senses; each piece's
    # ends were fanned to the nearest curve end (edges of 8 and 12
    # triangles).  They are chained along the face (facets/tubes.py
    # _chain_on_faces).
    ("s1-746 a curve along a face",
     "(-2*y^3 + 4*x^2*z + 3/2*x*z + 1/2)*(1*z + 6/7*y + 8*x - 8/3)",
     ((-2.0, 2.0), (-0.5, 0.5), (-0.5, 0.5)), 8, 64),
    ("s1-690 a curve within a cell of a face",
     "(1*x*y^2 + 6*x^3 + 6/5*x*z + 8/3)*(1.29540471556219*x*z^2 + 1.15441990317525*x^3"
     " - 0.724212516849265*y^2 - 1.01369146646664*x^2 + 2.51158703842985)", ((-1.0, 1.0),) * 3, 8, 64),
    # The double curve crosses the thin box (y in -0.5 .. 0.5) at a small
    # angle: a piece of 16 cells asked for a 13-cell tube, which filled it
    # and reached both faces (5 open edges, 69 curve edges with other than
    # 4 triangles; skeleton/singular_curves.py _tube_widths).
    ("s1-242 small angle across a thin box",
     "(2.80271574643564*x*y - 0.138602685654024*z)*(2.14558460746148*y*z - 1.53281678435219*y^2"
     " + 1.69046662791925*x*y + 0.16909525811052)", ((-2.0, 2.0), (-0.5, 0.5), (-2.0, 2.0)), 8, 64),
    # Double curves a few cells inside a face of the box over all their
    # length (facets/tubes.py face_rail_events, face_chords, _end_walk).
    # Both planes' line runs 0-0.1 from the face x = -0.5, ending on it
    # and on y = -1: the half-sheet between the line and that face leaves
    # the tube only through the box, and its face links all lay within 8
    # cells (measured in the largest cell, 3/64 along z: 0.375 of a
    # 0.63-long line) of the two ends and were dropped: no rail, 19 line
    # edges with 3 triangles.
    ("s1-38 planes along a face", "(-5*z + 4/5*y + 7/4*x + 5/2)*(-5/4*z - 6/7*y - 6*x - 3)",
     ((-0.5, 0.5), (-1.0, 1.0), (-1.5, 1.5)), 8, 64),
    # Two curves each within 5 cells of an edge of the box (x = -1 and
    # z = +-1) from end to end: the half-sheet towards the edge had no
    # rail (33 edges with 3 triangles); with one, the middle of its trace
    # was fanned from both ends to the same curve end (edges of 5).
    ("s1-462 curves along box edges",
     "(2.01381147847187*x*z^2 - 0.504053152187985*x*y*z - 0.919590596196772*z^2 - 2.33565567683326*y^2"
     " - 1.23693836648928*y + 2.14465786662238)*(6*y^3 - 6/7*x*y*z + 4/5*x*y - 1/4*z + 1/2)",
     ((-1.0, 1.0),) * 3, 8, 64),
    # Two arcs from the face z = -1 back to it (and from z = 1), a few
    # cells deep: 79 edges with 5 or 3 triangles.
    ("s1-930 arcs from a face back to it",
     "(-1.59933898735838*z + 2.05497510462756*x)*(1.75469666008593*y*z - 2.39686508622322*y^2"
     " - 0.143887023415543)", ((-1.0, 1.0),) * 3, 8, 64),
    # An arc 8.6 cells deep from the face x = 0.5 back to it: the
    # half-sheet between the arc and the face is all inside the tube, its
    # rail the trace on the face from one end to the other (16 edges with
    # 3 triangles).
    ("s1-374 a half-sheet between an arc and the face",
     "(2.53522033705807*z^2 + 0.475118141672158*x*z + 2.81229876039505*x*y + 0.764400439463936)"
     "*(2/7*z^3 - 5*x*y^2 - 7/8*x^2*y + 4/7*x + 5/7)", ((-0.5, 0.5), (-1.0, 1.0), (-1.5, 1.5)), 8, 64),
    # The plane crosses the cubic cone 48 y^3 = x^2 z along curves near
    # the faces: rails along a face from one curve end to another zipped
    # their first links to the end, 18 triangles flat in the face (two
    # vertices closer than 1e-9 of the box).  Clean on main, where those
    # links were dropped (4 flat triangles there); guards the face rails.
    ("s1-186 no strip triangle in a face",
     "(-0.664277349692132*z - 1.21322696457437*y + 2.39550331995201*x + 0.69329417454361)*(6*y^3 - 1/8*x^2*z)",
     ((-1.0, 1.0),) * 3, 8, 64),
    # The z-axis is an isolated line of type A3 (-0.16 z^3 x^2 - 0.08 z y^4),
    # and a sheet comes within 0.85 y = -0.16 z^3 of it near z = 0.  Newton
    # in the normal plane dropped the y^2-small singular value (relative
    # cut 1e-12): vertices stayed 5e-7 off the line (|F| / |grad F| 2e-8
    # of the box); samples and a joined end stopped in the valley beside
    # it (residual 1e-11 that Newton cannot reduce), 0.0066 of the box off
    # (skeleton/singular_curves.py _correct, _explained, trace_curves).
    ("s1-73 A3 isolated line and a valley",
     "-0.0799072211047704*y^4*z - 0.157753613904362*x^2*z^3 + 1.35864870043953*x^2*y^3"
     " - 0.0430908047221177*x^2*y^2 - 0.851124432437971*x^2*y", ((-1.5, 1.5), (-1.5, 1.5), (-2.0, 2.0)), 8, 64),
    # Its only singular point is the origin; the sheets y = 0 and
    # 1.62 z + 1.74 x^3 = 0 nearly cross along a curve where F = -0.076 z^4
    # (~x^12): traced as a double curve whose vertices were a minimum of
    # the residual beside the sheets, up to 0.0073 of the box off F = 0.
    ("s1-377 a near-crossing is no curve",
     "-0.0762280240763551*z^4 - 2.13439765881766*y^2*z^2 - 1.74360244306392*x^3*y - 1.79380398411766*y*z^2"
     " - 1.61729187406932*y*z", ((-1.0, 1.0),) * 3, 8, 64),
    # The x-axis is a curve of corank 2 (0.74 y z^3 + 0.69 x y^4 - 1.12 x^2
    # z^3): with no cut at all on the normal plane's singular values Newton
    # divided by rounding-sized ones and left 43 curve vertices up to 1.1e-6
    # of the box off it.  Clean on main; guards CURVE_SVD_PLANE_RTOL.
    ("s1-745 a corank-2 curve",
     "-1.90011951797286*y^4*z^2 - 1.67561223642793*x*y^4*z + 0.693165363737196*x*y^4"
     " - 1.11981173309511*x^2*z^3 + 0.736973026383562*y*z^3", ((-1.5, 1.5), (-1.5, 1.5), (-2.0, 2.0)), 8, 64),
    # Lattice lines (x, z) = (+-1/512, -1/512) pass 1.4e-5 of the box beside
    # the surface by the degenerate origin (y^2 z + x^6 - 3 z^6, Milnor
    # number 35): F along them is a quadratic in y whose maximum is
    # -1.85e-17 (its terms 3e-16), roots 0.18 a^3 +- 6e-8 i; the pair was
    # taken for a touching, and its vertex was 1.4e-5 of the box off F = 0
    # (boxes/edges.py _drop_false_touchings).
    ("s1-472 a complex pair is no touching", "-3*z^6 + 1/5*y^2*z^4 + 8/3*x^6 + 6/7*x^2*y*z^2 + 7/3*y^2*z",
     ((-1.0, 1.0),) * 3, 8, 64),
    # Of the same class, rotated (seed 5) and shifted: x^2 (y + z^3) + z y^4
    # has the isolated A3 line x = y = 0 with the sheet y = -z^3 nearing
    # it; one curve vertex was 3.8e-5 of the box off F = 0.
    # Two double curves 12 cells apart (16 of the thin box's z-cells):
    # the tubes' walls nearly touch between them, and a rail along one
    # came nearer the other for an event or two; its strip stepped across
    # to the other curve and back, triangles from one curve to the other
    # (facets/tubes.py _one_piece).
    ("s1-614 a rail's excursion to another curve",
     "(-0.161417369676522*y*z - 0.395186720158192*x^2 - 0.803556517882911*y + 0.665933386426941)"
     "*(7/4*x*z - 1/2*z + 1/5*x)", ((-2.0, 2.0), (-2.0, 2.0), (-0.5, 0.5)), 8, 64),
    ("s1-302 a rail's excursion to another curve",
     "(2/7*x^2*z + 1*x^3 - 8/3*x*z + 6/5*x*y + 6/7*x^2 - 2)*(1*z^2 - 3*y*z + 1*x*y)", ((-2.0, 2.0),) * 3, 8, 64),
    ("A3 isolated line and a sheet, rotated", _rotated("x^2*(y + z^3) + z*y^4", 5, (0.05, -0.1, 0.02)),
     ((-1.0, 1.0),) * 3, 8, 64),
    # The x-axis lies on the surface, tangent to the face y = 0 along it
    # (F = -0.715 x^2 y + ... there), and the hyperbola's other branch
    # crosses the cells beside it (x = 0.25 .. 0.28).  On the faces x =
    # 0.25 and 0.28 (no graph axis: F's saddle is inside) the corner on the
    # axis has an event on each edge; paired along the boundary "each
    # start with the next end", each went to the other branch, which was
    # joined to the axis (edges of 4 triangles; boxes/faces.py
    # _corner_events).
    ("s1-533 a branch joined to a line on the lattice",
     "-2.666004875266*x*z^2 - 0.715015552404059*x^2*y + 2.63107313588995*y*z", ((-1.0, 1.0),) * 3, 8, 64),
    # Of the same class with other coefficients, the line on the z-axis.
    ("z-axis on the surface, tangent to x = 0",
     "2.71828182845905*x*y - 1.41421356237310*z*y^2 - 0.577215664901533*z^2*x", ((-1.0, 1.0),) * 3, 8, 64),
    # The node of the cone (origin) is 0.36 from the plane; their double
    # curve ran 8 cells from it, through the node's star cube (grown over
    # the non-simple leaves to [-0.5, 0.5] x [-0.125, 0.125] x [-0.5, 0.5]):
    # the tube took 31 of its leaves and fanned the star's boundary links
    # to the curve (an isolated triangle, 3 open edges; facets/stars.py
    # star_cubes reaches half-way to the curves).
    ("s1-674 a node's star and a double curve",
     "(-1.50888575821945*z - 2.384556003321*y + 1.01948773647118)*(2/7*z^2 - 1/3*y*z + 8/3*x*y + 2*x^2)",
     ((-2.0, 2.0), (-0.5, 0.5), (-2.0, 2.0)), 8, 64),
    # Of the same class: a cone x^2 + y^2 = z^2 and a plane 0.3 from its
    # apex, rotated (seed 3) and shifted (3 open edges on main).
    ("a cone's node near a plane, rotated",
     f"({_rotated('x^2 + y^2 - z^2', 3, (0.05, -0.1, 0.02))})"
     f"*({_rotated('x + 0.3*y - 0.3', 3, (0.05, -0.1, 0.02))})",
     ((-1.0, 1.0),) * 3, 8, 64),
    # A double curve 0.05 deep in the box from the face z = -0.05 (see
    # SHORT_ARCS): Newton across its tangent (pinv, then the step along the
    # tangent dropped) jittered at a residual of 1e-8 where the tangent was
    # not the kernel direction it was started along; two points on it were
    # taken for isolated non-simple points (8 close vertex pairs, a vertex
    # 1.4e-8 of the box off F = 0; skeleton/singular.py gauss_newton).
    ("s1-682 Newton across a curved curve",
     "(6*x^2*y - 3*z)*(-2.57625135148072*y^3 - 0.255252270004791*x^2*z - 0.709279785999579*z^2"
     " - 1.74424755898056)", ((-1.1621297997164315, 1.7299395124368098),
                              (-1.595886277199356, 0.9796144187808289), (-0.05, 1.0899999999999999)), 8, 64),
    # The origin is a non-simple point (Hessian zero; on main a cloud of 22
    # "non-simple points" there).  Centred as one, its star has a 2-event
    # cycle whose skeleton node (x-direction: F_x = 0 on all of x = 0) fell
    # on an event of another cycle at x = 0: two vertices 3e-31 apart
    # (skeleton/curves.py skeleton_links_many, NODE_ON_OTHER).
    ("s1-324 a spoke's node on another cycle's event", "-9*y*z^5 + 3/7*x^5*z + 3*x^2*y^2*z - 4*y^3",
     ((-1.0, 1.0), (-0.5, 0.5), (-0.5, 0.5)), 8, 64),
    # The origin is the only singular point (sympy's Groebner basis of
    # F, grad F: x + ..., y^5, z^3), a non-simple germ ~ x^2 - y^6 - z^4
    # (corank 2, zero cubic).  F and grad F are below 1e-12 up to 4e-3 from
    # it, where points read as E6 and were not centred: 12 "E6 points", one
    # vertex 4e-8 of the box off F = 0 (skeleton/centre.py _NON_SIMPLE).
    # test_non_simple_germ_is_one_point checks the report.
    ("s1-877 a non-simple germ",
     "-2.02039170670759*z^4 + 1.83785346374069*x*y^3 + 1.73940194134003*x^2*y + 2.54458067248033*x^2",
     ((-0.5, 0.5), (-2.0, 2.0), (-1.0, 1.0)), 8, 64),
    # The double curve runs 0 to 3 cells inside the face y = 1.49; the
    # half-sheets between it and the face end there, their traces on it
    # (the tube's rails) less than a cell apart.  Those squares have no
    # graph axis: their links were left out of the rails, and where one
    # square held both traces, paired along its boundary, one trace was
    # joined to the other: a half-sheet's strip missing (23 edges of 3
    # triangles) or made twice (edges of 6).  The face curve is now
    # followed across such squares (boxes/faces.py traced_pairs).
    ("s1-610 traces less than a cell apart on a face", "*".join(f"({f})" for f in S1_610), S1_610_BOX, 8, 64),
    # Of the same class: s1-610 with the face moved 0.01 out, and turned
    # 0.1 rad (15-digit coefficients); two sheets at 14 degrees along a
    # curve 2 cells inside a face, turned (40 edges of 6 triangles on main).
    ("s1-610 with the face moved", "*".join(f"({f})" for f in S1_610),
     (S1_610_BOX[0], (-0.7, 1.5), S1_610_BOX[2]), 8, 64),
    ("s1-610 turned", _tilted_product(S1_610, (1, -2, 1), 0.1, (-0.12, 1.44, 0.3), (0.013, -0.004, 0.021)),
     S1_610_BOX, 8, 64),
    ("two sheets at a small angle near a face, turned",
     _tilted_product(NEAR_FACE, (2, 0, 1), 0.03, (0.1, 0.95, 0.0), (0.0013, 0.0, -0.0021)), ((-1.0, 1.0),) * 3, 8, 64),
    # What that tracing must not do: join a face trace between a curve's
    # two ends on one face (the curve dips 22 cells into the box) into a
    # rail (s1-354: 64 edges of 3 triangles), nor make a face event next to
    # a corank-2 curve 0.01 inside the face a rail vertex (s1-704: 1.9e-9
    # of the box off F = 0).  Both clean on main; the rails alone read the
    # traced links, away from the curve.
    ("s1-354 a face trace between a curve's two ends",
     "(-1*y^2*z - 8/3*y*z - 1/2)*(2.04487238258283*z^2 + 1.38447019979468*y^2 - 0.345692485738249*x*z"
     " - 0.504466901936883)", ((-1.0, 1.0),) * 3, 8, 64),
    ("s1-704 face events next to a corank-2 curve", "3/2*z^6 + 5*x*y*z^4 - 4/5*x^2*y^3*z + 2/5*x*y^4",
     ((-0.6883937731600414, 0.9255983774225047), (-1.7072045285851571, 0.28921517033651534), (-0.01, 0.87)), 8, 64),
    # The parabolic cylinder 7 y^2 = x / 5 touches the split plane x = 0
    # along the lattice line x = y = 0, every lattice point of which is a
    # zero (an event with the point's key).  The boxes round the line are
    # of different sizes (some failed the simplicity test, some not): the
    # polygons of the larger ones ran along it from corner to corner, of
    # the smaller ones through every lattice point between (65 edges of one
    # triangle; facets/polygons.py split_lattice_edges).
    ("s1-314 a sheet touching a split plane along a lattice line",
     "(7*y^2 - 1/5*x)*(0.252890243588101*z^2 + 1.3518127774103*x*z - 2.42289169494478*x*y - 1.86884130986558)",
     ((-1.5, 1.5), (-1.5, 1.5), (-1.0, 1.0)), 8, 64),
    # Of the same class: the cylinder along the x-axis touching y = 0 (the
    # axes permuted), and along the lattice line x = 0.375, y = -0.1875
    # (shifted; 20 and 24 open edges on main).
    ("a cylinder touching y = 0 along the x-axis",
     "(-y/5 + 7*z^2)*(0.252890243588101*x^2 + 1.3518127774103*x*y - 2.42289169494478*y*z - 1.86884130986558)",
     ((-1.5, 1.5), (-1.0, 1.0), (-1.5, 1.5)), 8, 64),
    ("a cylinder touching x = 0.375 along a lattice line",
     "(-x/5 + 7*y^2 + 2.625*y + 0.32109375)*(-2.42289169494478*x*y + 1.3518127774103*x*z - 0.454292192802146*x"
     " + 0.908584385604292*y + 0.252890243588101*z^2 - 0.506929791528862*z - 1.69848173756478)",
     ((-1.5, 1.5), (-1.5, 1.5), (-1.0, 1.0)), 8, 64),
    # Every term has x or y: the surface holds the z-axis, one sheet
    # through it tangent to y = 0 there (crossing the split plane x = 0),
    # another less than a cell above it in y > 0.  On the squares of x = 0
    # between them F is zero on the axis side and negative beside it, so
    # F + eps = 0 runs along that side; the boundary pairing joined its
    # corners to the other sheet's trace instead, and the boxes in y > 0
    # had polygons along the axis too (12 edges of 4 triangles;
    # boxes/faces.py _zero_side_events).
    ("s2-136 a sheet through a lattice line, another a cell away",
     "-1/5*x^2*z^3 - 2/7*y*z^3 + 3/4*y^2*z^2 - 5/3*x^3*z + 5/2*y^2*z + 3/4*y^3", ((-1.0, 1.0),) * 3, 8, 64),
    # (Its piece 2.3 cells across on the face z = 1 between the two sheets,
    # left out, is meshed since the leaves of pieces cut off by the box's
    # faces are split: facets/cycles.py lens_leaves.)
    # Of the same class: the axes permuted (the line is the x-axis), and
    # shifted to the lattice line x = 0.375, y = -0.1875 (15-digit
    # coefficients; 12 and 4 edges of 4 triangles on main).
    ("s2-136 permuted", "-1/5*x^3*y^2 - 2/7*x^3*z + 3/4*x^2*z^2 - 5/3*x*y^3 + 5/2*x*z^2 + 3/4*z^3",
     ((-1.0, 1.0),) * 3, 8, 64),
    ("s2-136 shifted",
     "-1.66666666666667*x^3*z - 0.2*x^2*z^3 + 1.875*x^2*z + 0.15*x*z^3 - 0.703125*x*z + 0.75*y^3"
     " + 0.75*y^2*z^2 + 2.5*y^2*z + 0.421875*y^2 - 0.285714285714286*y*z^3 + 0.28125*y*z^2 + 0.9375*y*z"
     " + 0.0791015625*y - 0.0816964285714286*z^3 + 0.0263671875*z^2 + 0.17578125*z + 0.00494384765625",
     ((-1.0, 1.0),) * 3, 8, 64),
    # A cone (3/5 x^2 = 9/4 y z, its apex a singular point) and another
    # sheet crossing it along a curve that passes by the apex's star: the
    # star's sector link on the star's face got a node (the sector's
    # split), the tube's strip across that link, made later, did not (a
    # triangle's hole, 3 open edges; facets/polygons.py add_strips).
    ("s2-2 a tube's strip across a star's split link",
     "(-9/4*y*z + 3/5*x^2)*(2.97841050879985*z^2 - 1.0286079054028*x*z - 2.61568249904869*x - 1.92117362349853)",
     ((-2.0, 2.0), (-2.0, 2.0), (-1.5, 1.5)), 8, 64),
    # Of the same class: the axes permuted, and the apex shifted to
    # (0.25, -0.125, 0.09375) (15-digit coefficients; 3 open edges on main).
    ("s2-2 permuted",
     "(-2.25*x*y + 0.6*z^2)*(2.97841050879985*y^2 - 1.0286079054028*y*z - 2.61568249904869*z - 1.92117362349853)",
     ((-2.0, 2.0), (-1.5, 1.5), (-2.0, 2.0)), 8, 64),
    ("s2-2 shifted",
     "(0.6*x^2 - 0.3*x - 2.25*y*z + 0.2109375*y - 0.28125*z + 0.0638671875)*(-1.0286079054028*x*z"
     " - 2.51925050791718*x + 2.97841050879985*z^2 - 0.301299994049272*z - 1.26518356040674)",
     ((-2.0, 2.0), (-2.0, 2.0), (-1.5, 1.5)), 8, 64),
    # The y-axis and the line x = 0, y = 1/4 lie on the quadric, crossing at
    # a lattice point where its tangent plane is the split plane x = 0.  The
    # facet of a coarse box beside finer ones along the axis has their
    # vertices on the axis and is folded (part of it flat in x = 0), so
    # every triangulation has a triangle facing away: the first, chosen on
    # that tie, had two flat triangles among the axis vertices, dropped (4
    # open edges at every coarse / fine; facets/triangulate.py FLAT_QUALITY).
    ("s4-36 a line of the quadric on a lattice line", "-4*y*z + 3*x*z - 1/5*x*y + 1*z",
     ((-0.5, 0.5), (-1.0, 1.0), (-1.5, 1.5)), 8, 64),
    ("s4-36 at 16 / 128", "-4*y*z + 3*x*z - 1/5*x*y + 1*z", ((-0.5, 0.5), (-1.0, 1.0), (-1.5, 1.5)), 16, 128),
    # The same in the split plane y = 0, which holds the line x = -z / 9^(1/3)
    # of the surface (not a lattice line): the vertices of finer boxes on it
    # in a coarse box's folded facet (6 open edges on main).
    ("s3-600 a line of the surface in a split plane", "-1*x*z^4 - 2/5*x^3*y*z + 4/5*x^3*y^2 - 9*x^4*z - 4*y^3*z",
     ((-1.5, 1.5), (-1.5, 1.5), (-0.5, 0.5)), 8, 64),
    # Two planes crossing along a line 0-3.3 cells inside the face x = -1,
    # 5.7 degrees off it: the tube's face squares within 1.5 cells of the
    # line were not traced, one sheet's trace joined the other's (edges of
    # six triangles; facets/tubes.py untraced_points).
    ("s3-726 planes crossing by a face",
     "(1*z + 2*y + 1*x + 1/7)*(1.47779658339878*z + 2.65397611087319*y - 1.15247915671842)",
     ((-1.0, 1.0),) * 3, 8, 64),
    # Of the same class: a double curve a cell or so inside the face z = 1
    # (36 edges of six triangles on main).
    ("s4-426 curve by the face z = 1",
     "(5/3*y*z^2 + 3/4*x^2*z - 1/4*z^2 - 3/4)*(1*z - 3*y - 1/8*x + 6/7)", ((-1.0, 1.0),) * 3, 8, 64),
    # A double curve within 3 cells of a face, leaving it at 8 degrees
    # (5 edges of six triangles on main): clean since short runs of a rail
    # round a box edge are chained as stubs (facets/tubes.py _join_stubs).
    ("s3-234 curve by a face, its end by a box edge",
     "(-7/3*y*z^2 + 9*x^2*y - 2/7*z^2 - 1*z - 4/5*x)*(1.65617258640352*y^2 + 2.85775483572458*x^2"
     " + 0.938214260532233*z - 0.119432098223332*y - 2.1539479278296)", ((-1.0, 1.0),) * 3, 8, 64),
    # A double curve 0-6 cells inside the face y = -1.5 ending on z = 2,
    # 6.3 cells from that box edge: a sheet's trace on y = -1.5 turning
    # back beside the curve's end there was cut within 8 cells of it, and
    # both pieces were fanned to the end (8 edges of six and eight
    # triangles on main; facets/tubes.py face_chords).
    ("s3-410 curve by a face, its end by a box edge",
     "(1/2*y^2*z - 3*x*z^2 - 1/3*x^2*y - 3/5*x^2 - 1/2*x)*(-1.03837671056409*x*z^2 - 1.10203670434999*x^2*y"
     " + 1.51732818844902*y + 2.29179336709926)", ((-1.5, 1.5), (-1.5, 1.5), (-2.0, 2.0)), 8, 64),
    # Of the same class: a curve from z = -2 to y = 1 within 4 cells of
    # z = -2 (15 edges of three and five triangles on main): a rail's end
    # was fanned to the curve end whose walk went back over part of its
    # own strip (facets/tubes.py _end_walk).
    ("s3-818 curve from a face to a face",
     "(-2/5*z - 1*x)*(-0.884779432772045*x^2*z + 2.37684124086963*x^2*y - 1.77438327389)",
     ((-2.0, 2.0), (-1.0, 1.0), (-2.0, 2.0)), 8, 64),
    # A double curve cutting the corner by the box edge x = -1, y = 1 (its
    # end on x = -1 2.4 cells from y = 1): clean on main, broken (edges of
    # six) by cutting the sheets' traces on a face only near the curve ends
    # on that face, a rule tried for s3-410 and left out.
    ("s3-978 curve cutting a box edge",
     "(-1*y*z - 6/5*x*y + 4*z + 4/7)*(2.68392668968489*z + 0.00940053183485556*y - 0.718225555041655*x"
     " + 0.740281944691867)", ((-1.0, 1.0),) * 3, 8, 64),
    # A plane through a cubic's line at 3.6 degrees (the line's wide tube)
    # and the other branches of their curve 1.4 to 15 cells from it: the
    # wide tube held them and the sheet between had no rail (open edges).
    # Clean on a5ab96f only by a false crossing that cut the line.
    ("s4-838 wide tube beside another curve", "(-2/7*y + 3/2*x)*(7*y^2*z - 8/3*y^3 - 8*x^2 + 8/7*y - 9*x)",
     ((-0.32, 0.32), (-0.6807690826262665, 2.1236539676916917), (-1.3482142494226852, 1.3944050195806525)), 8, 64),
    # Stretches of a double curve 2.4 to 5 cells apart (fine 64) sharing one
    # tube: edges of three triangles and open edges between them; the
    # lattice is made one level finer for them now (CURVE_GAP_LEAST).
    ("s3-2 arms of a curve 2.4 cells apart",
     "(-0.759290625094244*x*z^2 + 1.62665227788866*x^3 + 0.0079675053827799)*(5*z^3 - 2*x*z^2 - 8/3*x^3 - 1/4*y)",
     ((-1.0, 1.0), (-2.0, 2.0), (-0.5, 0.5)), 8, 64),
    ("s3-534 curves 4 cells apart", "(4*x^2 - 5/3*y)*(-9*y^2*z - 8*x*z^2 - 6/7*x*y^2 + 6/5*z^2 + 6/7*z)",
     ((-1.0, 1.0),) * 3, 8, 64),
    ("s3-950 arms of a curve 3.2 cells apart", "(-5*z + 6*x)*(1/4*y^2 - 2*x*y + 8*x^2 - 2*z)",
     ((-2.0, 2.0), (-1.5, 1.5), (-1.5, 1.5)), 8, 64),
    ("s4-542 arms of a curve 5 cells apart",
     "(3/2*z - 1/2*y - 1*x + 5/4)*(-0.166667770474241*y^3 + 0.615248984501005*x*z^2 - 0.67931481614932*x^2*y"
     " - 2.62257286516497*y^2)", ((-1.5, 1.5),) * 3, 8, 64),
    # Newton from the boxes beside a traced curve (for points beside it)
    # ended on arcs of the double curve that were not traced (s1-494: 49
    # non-simple "points" with stars) or read as A12/A13 points (s3-566, a
    # vertex off the surface; s4-498, close vertices and open edges): such
    # ends are traced along the locus now (skeleton/singular.py _continues).
    ("s1-494 ends on untraced arcs", "(1/2*x^2*y + 8*x^3 - 2/7*z^2 - 6/7*x)*(-9*y^2 + 3*x*z - 1/2*x*y - 1/8*y)",
     ((-2.0, 2.0), (-1.0, 1.0), (-0.5, 0.5)), 8, 64),
    ("s3-566 short arc read as points",
     "(1/2*z^3 - 7/3*y^2*z - 3*y^3 + 1*z^2 - 7*x*y)*(1.30368103590988*y*z^2 + 1.28031267053934*x*y^2"
     " + 1.78407141978226*x^3 - 2.16287016839143*x*y + 0.264696842804438*x)", ((-2.0, 2.0), (-1.5, 1.5), (-1.0, 1.0)),
     8, 64),
    ("s4-498 curve near a box edge",
     "(0.420938814319004*z - 0.151677491934424*y)*(4/7*y*z^2 + 7/5*y^3 + 3/4*y*z - 4*x*y - 2*x - 2/3)",
     ((-1.0, 1.0),) * 3, 8, 64),
    # A lens thinner than a cell round a cuspidal edge: all tube, the mesh
    # was empty; made again on finer lattices (THIN_RETRIES).
    ("s3-925 lens round a cuspidal edge",
     "-2.9223338669653*z^4 + 0.609126391864046*x*y*z^2 + 0.747860898702115*x^3*y + 0.575562523538086*z^3"
     " - 1.2068778495843*x^2", ((-1.0, 1.0), (-0.5, 0.5), (-2.0, 2.0)), 8, 64),
    # A sliver of the first factor cut off by the box's edge x = y = -0.5,
    # 25 cells long, inside one coarse leaf: a link cycle of two events, no
    # polygon, left out without a word (facets/cycles.py lens_leaves).
    ("s4-26 sliver at an edge of the box",
     "(1/3*y*z^2 - 2*y^2*z + 2*y^3 - 9/4*x*z^2 + 7/8*x + 5/7)"
     "*(-3/8*x*z^2 + 1/3*x^2*z - 7*x^2*y - 5*x^2 + 2*z + 7*x + 8)", ((-0.5, 0.5), (-0.5, 0.5), (-2.0, 2.0)), 8, 64),
    # Pieces cut off by a face of the box whose coarse leaves' cycles have
    # all their events on one face of the leaf (two on one edge, or a few
    # on the face beside finer leaves): no polygon but a flat one, the
    # piece dropped (s3-905: a cap 6 cells across, 65 cells from the mesh)
    # or cut short by 5 or 6 cells (facets/cycles.py lens_leaves).
    ("s3-905 cap through a face of the box",
     "0.873643488270333*z^3 - 2.78395585173907*y^2*z + 1.31207443026209*x^3 + 1.57454945828593*x*z"
     " + 1.51717805482981", ((-1.0, 1.0),) * 3, 8, 64),
    ("s3-337 bulge cut short at a face of the box",
     "-1.5508961677063*y*z^5 - 0.72691094488225*x^5*z - 0.306650547967136", ((-1.0, 1.0), (-2.0, 2.0), (-1.5, 1.5)),
     8, 64),
    ("s3-383 bulge cut short at z = -0.85", "-3/5*y^4 + 9*x^2*y^2 + 4*z - 1*x + 4/7*(x^2+y^2+z^2)^2 - 5/8",
     ((-0.1, 1.84), (0.74, 2.72), (-1.81, -0.85)), 8, 64),
    ("s4-141 bulge cut short at z = -1.82",
     "-1.66303191679936*x^2*z - 1.23203916219725*x^2*y + 2.73111174252144*x^3 - 0.337454775234424*x*y"
     " - 0.255598634093233", ((-1.37, 1.41), (0.58, 3.22), (-1.82, -0.98)), 8, 64),
    # A non-simple point at the origin with the x-axis on the surface, flat
    # to order 5 along it (test_a_flat_line_through_a_non_simple_point_is_one_point):
    # four points 1e-5 apart along the axis, clashing stars, 130 open edges
    # (skeleton/singular.py _one_per_flat_point).
    ("s6-688 a flat line through a non-simple point", "-6*z^6 - 1/2*x^5*y - 1*x*y^2*z + 1*y^2*z",
     ((-1.0, 1.0),) * 3, 8, 64),
    # The judge's own failure: its search for tangencies of the two factors
    # raised LinAlgError on normal equations singular to rounding at a few
    # of its 200 starts (tests/fuzzcases.py _solve_each); the mesh is clean.
    ("s6-666 the judge's tangency search", "(3*y + 3/5*x)*(-8*y^2*z - 4*x^2 + 2/5)", ((-1.0, 1.0),) * 3, 8, 64),
    # Seed 6 and 7 failures on ba35d69 (edges of six triangles on a double
    # curve; close vertex pairs, vertices off F = 0) that came out clean once
    # the points beside curves, pinch-point rails and box-edge slivers were
    # merged (not bisected to one of them).
    ("s6-42 a cubic and a plane through the origin",
     "(-3*y*z^2 + 5*x*y*z + 5/3*x*z - 2/3*x*y + 9*x^2)*(7/2*z + 8/3*y - 7/3*x)", ((-1.0, 1.0),) * 3, 8, 64),
    ("s7-434 two cubics, close vertices",
     "(-0.314474537864719*x*y^2 + 0.736754626016244*x^2*y + 1.06037425242556*y*z - 2.39457567998562*y^2"
     " - 0.454551157144459)*(-4/3*x*z^2 - 9/2*x^2 + 1/2)", ((-1.5, 1.5), (-2.0, 2.0), (-1.5, 1.5)), 8, 64),
    ("s7-662 a plane and a cubic, close vertices",
     "(2.40770069278573*z + 0.504086449835711*x + 2.53398054843064)*(-2/7*z^3 + 2/3*y^3 - 6/5*x*z^2"
     " - 3/4*x*y^2 - 5/4*x^2*z + 2/3*x^2)", ((-1.5, 1.5), (-0.5, 0.5), (-1.5, 1.5)), 8, 64),
    # The wide tube of one curve (a corank-2 edge, a tacnode edge) went
    # round every vertex of every curve: sheets between curves that need
    # no wide tube were all tube, with no rail, and left out (11.1 and 2
    # cells off the mesh on main).  s6-486 and s7-962 (open cases on main:
    # edges of six, and of five triangles) are clean with the wide tube
    # round the wide pieces only too (facets/tubes.py wide_vertices).
    ("s4-246 a sheet between double curves beside a wide tube",
     "(5/2*y*z - 1*x*y + 2*z - 2*y)*(9/7*z^2 - 2*y^2)", ((-1.0, 1.0),) * 3, 8, 64),
    ("s4-294 a sheet between double curves beside a wide tube",
     "(-0.397099534634836*x^2*y - 1.09301846688618*x^3 - 1.25766364619521*y*z)*(-2.38820860116564*y*z^2"
     " + 1.97140976835885*x*y*z + 2.16669666072768*x^3 - 2.21493441155288*x^2)", ((-1.0, 1.0),) * 3, 8, 64),
    ("s6-486 a cubic and a quadric beside a wide tube",
     "(8/3*y^2*z + 9/4*x*z^2 - 1/2*x*y*z + 1/8*x^2*y - 3*z^2 + 6/7)*(9/2*z^2 - 3*y^2 - 3/4*x*z - 6/7)",
     ((-1.0, 1.0),) * 3, 8, 64),
    ("s7-962 a cubic and a quadric beside a wide tube",
     "(-1.87481254009134*y*z^2 - 1.77523112637793*x^2*z - 1.75675312134313*x*y)*(-5/2*y*z - 3/2*x*z"
     " - 8*x^2 + 3/4)", ((-1.0, 1.0), (-2.0, 2.0), (-1.5, 1.5)), 8, 64),
]


@pytest.mark.parametrize("name, text, box, coarse, fine", REGRESSIONS, ids=[r[0] for r in REGRESSIONS])
def test_fuzz_regression(name, text, box, coarse, fine):
    if text is None:  # a case of the generator, judged on one class
        case = fc.make_case(1, int(name.split()[0].split("-")[1]))
        v = fc.judge(case, coarse, fine)
        assert "outside-box" not in v.failures and "exception" not in v.failures, v.detail
        return
    case = fc.case_from_text(name, text, box)
    v = fc.judge(case, coarse, fine)
    if name in UNCOVERED_OPEN:
        # Right in the class it guards; the piece of surface left out is open.
        assert set(v.failures) <= {"uncovered"}, f"{text} on {box}: {v.detail}"
        assert v.failures, f"{name}: nothing left out any more: remove it from UNCOVERED_OPEN"
        pytest.xfail(f"{UNCOVERED_OPEN[name]}: {v.detail}")
    assert v.status == "clean", f"{text} on {box}: {v.detail}"


#: Regressions that the judge's check of pieces left out (``uncovered``:
#: roots of F on lattice lines more than 1.5 cells from the mesh), added
#: after them, finds wrong: right in the class each guards, open in this one.
UNCOVERED_OPEN = {
    "s1-354 a face trace between a curve's two ends":
        "sheets of both factors 2 to 4.6 cells from the mesh beside the double curve near the face x = -1",
    "s1-186 no strip triangle in a face":
        "the plane's sheet up to 8.5 cells from the mesh beside the cubic's cuspidal and tacnode edges",
    "s3-978 curve cutting a box edge": "the plane's sheet 2.8 cells from the mesh where the curve leaves by a box edge",
    "s4-838 wide tube beside another curve": "both factors' sheets 2.5 cells from the mesh beside a wide tube",
}


#: Non-simple isolated points, each one singular point of F = 0 (where it is
#: and its real branches: from sympy / oracles, not from the mesher).
NON_SIMPLE = [
    ("s1-877", "-2.02039170670759*z^4 + 1.83785346374069*x*y^3 + 1.73940194134003*x^2*y + 2.54458067248033*x^2",
     ((-0.5, 0.5), (-2.0, 2.0), (-1.0, 1.0)), None, None),
    # Arnold's X9 (corank 2, zero cubic, four distinct lines in the quartic)
    # and W-type x^2 - y^6 - z^4 (the germ of s1-877), rotated and shifted:
    # on main 12 "D4 points" and 26 "E6 points", none of them a vertex.
    ("X9 rotated", "z^2 - x^4 - y^4", ((-1.0, 1.0),) * 3, 3, (0.05, -0.1, 0.02)),
    ("W x^2 - y^6 - z^4 rotated", "x^2 - y^6 - z^4", ((-1.0, 1.0),) * 3, 5, (0.05, -0.1, 0.02)),
    # W12 and W under another rotation: the 2- and 3-jet conditions fix
    # the point along y only to ~(eps / 5!)**(1/2), (eps / 6!)**(1/3) (on
    # main 3e-9 and 5e-7 off); g's order along y fixes it to rounding.
    ("W12 x^2 + y^5 + z^4 rotated", "x^2 + y^5 + z^4", ((-1.0, 1.0),) * 3, 7, (0.013, 0.021, -0.034)),
    ("W x^2 - y^6 - z^4 rotated 7", "x^2 - y^6 - z^4", ((-1.0, 1.0),) * 3, 7, (0.013, 0.021, -0.034)),
    # J10, E12 and E13 (corank 2, the cubic a cube X^3; beyond E8): on main
    # read as an E8, a cloud of A3/E6/E8 and of A4/D8/E7 points 1e-4..3e-3 off.
    ("J10 rotated", "x^3 + y^6 + z^2", ((-1.0, 1.0),) * 3, 5, (0.05, -0.1, 0.02)),
    ("E12 rotated", "x^3 + y^7 + z^2", ((-1.0, 1.0),) * 3, 7, (0.013, 0.021, -0.034)),
    # ... and E12 on the split planes: Gauss-Newton from the 8 boxes round
    # it left them all (to y ~ 0.2), and on main the point was silently lost.
    ("E12", "x^3 + y^7 + z^2", ((-1.0, 1.0),) * 3, None, None),
    ("E13 rotated", "x^3 + x*y^5 + z^2", ((-1.0, 1.0),) * 3, 5, (0.05, -0.1, 0.02)),
    # P8 (corank 3, a cubic cone with three real lines), rotated.
    ("P8 rotated", "x^3 + y^3 + z^3 - 4*x*y*z", ((-1.0, 1.0),) * 3, 11, (-0.03, 0.07, 0.1)),
]


@pytest.mark.parametrize("name, text, box, seed, shift", NON_SIMPLE, ids=[c[0] for c in NON_SIMPLE])
def test_non_simple_germ_is_one_point(name, text, box, seed, shift):
    """A non-simple germ is reported as one non-simple point, a vertex with
    its branches, never as a cloud of simple ones around it."""
    import warnings

    import meshcheck as mc
    import oracles
    import singmesh

    if seed is None:
        apex = np.zeros(3)
        # The singular points of F by sympy (exact rationals): the origin only.
        case = fc.case_from_text(name, text, box)
        F = case.poly
        gb = sp.groebner([F] + [F.diff(v) for v in fc.XYZ], *fc.XYZ, order="lex")
        assert sp.solve_poly_system(gb.exprs, *fc.XYZ) == [(0, 0, 0)]
    else:
        text = _rotated(text, seed, shift)
        q, _ = np.linalg.qr(np.random.default_rng(seed).normal(size=(3, 3)))
        apex = np.linalg.solve(q, np.array(shift))
        case = fc.case_from_text(name, text, box)
    with warnings.catch_warnings():
        warnings.simplefilter("error", singmesh.SingularPointWarning)
        m = singmesh.mesh(text, box, coarse=8, fine=64)
    assert len(m.singularities) == 1, [str(s) for s in m.singularities][:3]
    s = m.singularities[0]
    assert s.classification.name == "non-simple"
    # The centre of the rounded polynomial is within rounding of the exact
    # point (skeleton/centre.py), along flat directions too.
    assert np.linalg.norm(np.asarray(s.point) - apex) <= 1e-12
    assert s.vertex is not None
    assert fc.judge(case, 8, 64).status == "clean"
    if name in ("E12 rotated", "E13 rotated"):
        # Their link on a sphere of radius 0.1 is a cusp too thin for a
        # lat/lon grid (E13: 5 to 14 curves as the grid is refined), and the
        # mesh's fans at them are not right either (E12, a graph over the
        # (y, z) plane with one curve: 3 fans).  Position and count only.
        return
    branches = oracles.branches_on_sphere(fc.Field(case.poly).value, apex, 0.1, n_lat=960, n_lon=1920)
    assert mc.fans_at(m.faces, s.vertex) == branches


#: s6-688's surface: a non-simple point at the origin, and the x-axis on the
#: surface through it, tangent to the plane y = 0 along it, where |grad F|
#: = |x|^5 / 2: F and grad F are below 1e-12 of F's terms for |x| < 5e-3.
FLAT_AXIS = "-6*z^6 - 1/2*x^5*y - 1*x*y^2*z + 1*y^2*z"


@pytest.mark.parametrize("seed, shift", [(None, None), (3, (0.013, -0.021, 0.007))], ids=["s6-688", "rotated 3"])
def test_a_flat_line_through_a_non_simple_point_is_one_point(seed, shift):
    """The non-simple point where a line of the surface is flat to order 5
    is one singular point, a vertex of the mesh within 1e-4 of the box of
    the exact point (its centre is fixed only along the line, where F = 0
    to rounding), with no open edge inside the box, no edge of more than
    two triangles and every vertex on F = 0 (sympy's polynomial, checked
    here).  On main centring ended 1e-5 apart along the line: four points
    at s6-688 (their stars clashed: 130 open edges) and, rotated, a vertex
    6e-4 of the box off the surface."""
    import warnings

    import meshcheck as mc
    import singmesh

    box = ((-1.0, 1.0),) * 3
    if seed is None:
        text, apex = FLAT_AXIS, np.zeros(3)
    else:
        text = _rotated(FLAT_AXIS, seed, shift)
        q, _ = np.linalg.qr(np.random.default_rng(seed).normal(size=(3, 3)))
        apex = np.linalg.solve(q, np.array(shift))
    case = fc.case_from_text("flat axis", text, box)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        m = singmesh.mesh(text, box, coarse=8, fine=64)
    V, F = np.asarray(m.vertices), np.asarray(m.faces)
    b = case.box_array()
    near = [s for s in m.singularities if np.linalg.norm(np.asarray(s.point) - apex) <= 0.1]
    assert len(near) == 1, [np.asarray(s.point).tolist() for s in near]
    assert np.linalg.norm(np.asarray(near[0].point) - apex) <= 1e-4 * 2.0 and near[0].vertex is not None
    counts = mc.edge_counts(F)
    wrong = [k for e, k in counts.items() if k > 2 or (k == 1 and not mc._same_box_face(V[e[0]], V[e[1]], b))]
    assert not wrong, f"{len(wrong)} open or non-manifold edges"
    # On F = 0: |F| within 1e-9 of the box times |grad F|, or within
    # rounding of F's terms (at the point and along the line grad F ~ 0).
    field = fc.Field(case.poly)
    val = np.abs(field.value(V))
    allowed = 1e-9 * 2.0 * np.linalg.norm(field.grad(V), axis=1) + 64 * np.finfo(float).eps * field.abs_terms(V)
    assert (val <= allowed).all(), int((val > allowed).sum())
    assert fc.judge(case, 8, 64).status == "clean"


def _parabola_plane_arc(seed: int = 11, depth: float = 0.06, a: float = 8.0) -> str:
    """A parabolic cylinder z = a x^2 times the plane y = z / 10, each
    rotated (numpy QR of ``seed``) and shifted, their parabola's vertex
    ``depth`` inside the box [-1, 1]^3 from its face x = 1, opening out of
    it: an arc 0.2 long (its length outside the box, which it leaves
    through that face)."""
    q, _ = np.linalg.qr(np.random.default_rng(seed).normal(size=(3, 3)))
    shift = tuple(round(float(v), 6) for v in q @ np.array([1 - depth, 0.1, -0.2]))
    opening = 1 if q[2, 0] > 0 else -1   # +z of the rotated coordinates is q[2] in the box's
    return (f"({_rotated(f'{opening}*z - {a}*x^2', seed, shift)})"
            f"*({_rotated('y - 0.1*z', seed, shift)})")


#: Products whose double curve is a short arc from a face of the box back
#: to it (shorter than the two trace steps asked of a curve).
SHORT_ARCS = [
    # f1 = f2 = 0 dips 0.05 (2.8 cells along z) below z = 0 into the box
    # from its face z = -0.05, 0.34 long: its samples were taken for an
    # isolated point's and not traced; Newton across its tangent (pinv,
    # then the step along it dropped) jittered at a residual of 1e-8 and
    # two points on it were reported as "non-simple" points (close
    # vertices, a vertex 1.4e-8 of the box off F = 0).
    ("s1-682", "(6*x^2*y - 3*z)*(-2.57625135148072*y^3 - 0.255252270004791*x^2*z - 0.709279785999579*z^2"
     " - 1.74424755898056)", ((-1.1621297997164315, 1.7299395124368098),
                              (-1.595886277199356, 0.9796144187808289), (-0.05, 1.0899999999999999))),
    # Of the same class: seen as no curve at all on main (no edge of four
    # triangles).
    ("parabola of a cylinder and a plane, rotated", _parabola_plane_arc(), ((-1.0, 1.0),) * 3),
]


def _common_zeros(f1, f2, box, n: int = 41) -> np.ndarray:
    """Points of f1 = f2 = 0 in ``box``: Newton (min-norm) on (f1, f2) from
    the grid points near both surfaces."""
    g = fc._grid(box, n).reshape(-1, 3)
    size = float(np.ptp(box, axis=1).max())
    near = np.ones(len(g), bool)
    for f in (f1, f2):
        near &= np.abs(f.value(g)) <= 2.0 * size / n * np.linalg.norm(f.grad(g), axis=1)
    p = g[near]
    for _ in range(30):
        J = np.stack([f1.grad(p), f2.grad(p)], axis=1)              # (K, 2, 3)
        r = np.stack([f1.value(p), f2.value(p)], axis=1)
        p = p - np.einsum("kij,kj->ki", np.linalg.pinv(J), r)
    ok = (np.abs(f1.value(p)) < 1e-12) & (np.abs(f2.value(p)) < 1e-12)
    ok &= ((p > box[:, 0]) & (p < box[:, 1])).all(axis=1)
    return p[ok]


#: Not traced yet: keeping the short clusters and traces that reach the box
#: (skeleton/singular_curves.py, tried) traced both, but broke fuzz s1-66
#: and s1-350 (their newly traced arcs' tubes left edges of 3 triangles).
#: Meshing again at fine 128 whenever a curve is left untraced traced both
#: arcs (and s3-566, s4-498), but broke s3-378 and s3-385 (edges of three,
#: vertices 1e-7 off F = 0 on their curves traced at 128): reverted.
SHORT_ARCS_TODO = "a double curve shorter than two trace steps is taken for an isolated point's samples"


@pytest.mark.xfail(strict=True, reason=SHORT_ARCS_TODO)
@pytest.mark.parametrize("name, text, box", SHORT_ARCS, ids=[c[0] for c in SHORT_ARCS])
def test_short_arc_of_double_curve_is_traced(name, text, box):
    """The arc is followed by mesh edges with four triangles (two sheets
    crossing), checked at its points found here by Newton on the factors."""
    import meshcheck as mc
    import singmesh
    from scipy.spatial import cKDTree

    case = fc.case_from_text(name, text, box)
    assert case.factors
    b = case.box_array()
    arc = _common_zeros(*(fc.Field(f) for f in case.factors), b)
    assert len(arc) >= 10
    m = singmesh.mesh(text, box, coarse=8, fine=64)
    counts = mc.edge_counts(m.faces)
    edges = np.array([e for e, k in counts.items() if k == 4])
    assert len(edges), "no edge where the two sheets cross"
    on = np.concatenate([m.vertices[edges[:, 0]], m.vertices[edges[:, 1]],
                         0.5 * (m.vertices[edges[:, 0]] + m.vertices[edges[:, 1]])])
    cell = float(np.ptp(b, axis=1).max()) / 64
    far = cKDTree(on).query(arc)[0]
    assert far.max() <= cell, f"arc points {far.max() / cell:.2g} cells from the crossing edges"
    assert fc.judge(case, 8, 64).status == "clean"


@pytest.mark.parametrize("name, text, box", SHORT_ARCS, ids=[c[0] for c in SHORT_ARCS])
def test_an_untraced_arc_is_said(name, text, box):
    """Until such arcs are traced, a mesh that does not follow one says so
    (a warning, not only a note in the report): never silently wrong."""
    import singmesh

    case = fc.case_from_text(name, text, box)
    arc = _common_zeros(*(fc.Field(f) for f in case.factors), case.box_array())
    assert len(arc) >= 10  # the arc is there (Newton on the two factors)
    with pytest.warns(singmesh.SingularPointWarning, match="could not be traced"):
        singmesh.mesh(text, box, coarse=8, fine=64)


@pytest.mark.parametrize("seed, depth", [(11, 0.06), (11, 0.059), (11, 0.055), (11, 0.065), (12, 0.06)])
def test_a_short_arc_is_not_read_as_a_point(seed, depth):
    """The rotated parabola's arc (a few cells long, turning within two) and
    its shifted and turned copies: along it F is flat to rounding and its
    jet reads A12 to A15 at points of the arc.  None of them is reported as
    an isolated point, and the arc is traced or said, whatever rounding
    does (on main: A15 and A12 reported at depth 0.06, and at 0.059 an A13
    and no word of a curve)."""
    import singmesh

    text = _parabola_plane_arc(seed, depth)
    box = ((-1.0, 1.0),) * 3
    case = fc.case_from_text("arc", text, box)
    arc = _common_zeros(*(fc.Field(f) for f in case.factors), case.box_array())
    assert len(arc) >= 10  # the arc is there (Newton on the two factors)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        m = singmesh.mesh(text, box, coarse=8, fine=64)
    said = any("could not be traced" in str(w.message) for w in caught)
    assert said or m.singular_curves
    cell = 2.0 / 64
    for s in m.singularities:
        d = np.linalg.norm(arc - np.asarray(s.point), axis=1).min()
        assert d > 4 * cell, f"{s.name} at {s.point}, {d / cell:.2g} cells from the arc"


#: s1-270's factors: a quadric through the origin and a cubic cone with
#: its apex there; their double curves meet at the apex.
S1_270 = ("0.118365959345834*z^2 + 1.25814257648041*y^2 - 1.53978595412845*x*y - 2.37437628712255*x",
          "-1*y*z^2 - 1*x*y^2 - 3/4*x^2*z - 7/2*x^2*y")
#: (name, equation, apex): the apex of a cubic cone on a double curve,
#: where F vanishes to fourth order (the quadric's first order times the
#: cone's third): s1-270, and cones on quadrics turned (0.3 rad about
#: (1, 2, 3)) with the apex moved to (0.05, -0.03, 0.02).
APEX_ON_CURVES = [
    ("s1-270", "*".join(f"({f})" for f in S1_270), (0.0, 0.0, 0.0)),
    ("s1-270 turned", _tilted_product(S1_270, (1, 2, 3), 0.3, (0.0, 0.0, 0.0), (0.05, -0.03, 0.02)),
     (0.05, -0.03, 0.02)),
    ("another quadric, turned", _tilted_product(("x - 0.4*y^2 + 0.3*z^2 - 0.2*y*z", S1_270[1]), (1, 2, 3), 0.3,
                                                (0.0, 0.0, 0.0), (0.05, -0.03, 0.02)), (0.05, -0.03, 0.02)),
]


@pytest.mark.parametrize("name, text, apex", APEX_ON_CURVES, ids=[c[0] for c in APEX_ON_CURVES])
def test_cone_apex_on_a_curve_is_a_vertex(name, text, apex):
    """Where the curves meet at a point of higher type, the special point is
    that point (to the 1e-8 that F, vanishing to fourth order there, allows
    in doubles) and a mesh vertex: on main the traces lost near the apex
    were joined 0.009 (s1-270) to 0.05 (turned) from it."""
    import warnings

    import singmesh

    case = fc.case_from_text(name, text, ((-1.0, 1.0),) * 3)
    f = fc.Field(case.poly)
    apex = np.array(apex)
    # The apex is a zero of F and grad F (exact rationals of the typed
    # coefficients, the turned ones to their rounding).
    assert abs(f.value(apex[None])[0]) < 1e-12 and np.abs(f.grad(apex[None])).max() < 1e-12
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        m = singmesh.mesh(text, ((-1.0, 1.0),) * 3, coarse=8, fine=64)
    special = np.array([s.point for s in m.special_points])
    assert np.linalg.norm(special - apex, axis=1).min() <= 1e-6, special
    assert np.linalg.norm(np.asarray(m.vertices) - apex, axis=1).min() <= 1e-6


@pytest.mark.parametrize("index", range(SAMPLE_SIZE))
def test_fuzz_sample(index):
    case = fc.make_case(SAMPLE_SEED, index)
    v = fc.judge(case)
    right = v.status in ("clean", "empty")
    if case.name in KNOWN:
        # Judged first: a known case that comes out right says so.
        assert not right, f"{case.name} fixed: remove it from KNOWN"
        pytest.xfail(f"{KNOWN[case.name]}: {v.detail}")
    assert right, f"{case.text} on {case.box}: {v.detail}"


def test_generator_is_deterministic():
    a = [(c.text, c.box) for c in fc.cases(5, 12)]
    b = [(c.text, c.box) for c in fc.cases(5, 12)]
    assert a == b
    assert len({t for t, _ in a}) == 12


def test_sample_covers_every_kind_and_box():
    cs = fc.cases(SAMPLE_SEED, SAMPLE_SIZE)
    kinds = {(c.kind, c.name.rsplit("-", 1)[1]) for c in cs}
    assert kinds == {(k, b) for k in fc.KINDS for b in fc.BOXES}
    degrees = {sp.Poly(c.poly, *fc.XYZ).total_degree() for c in cs}
    assert degrees == set(range(1, 7))


# ------------------------------------------------------- the judge itself

def test_judge_sees_sign_change_and_its_absence():
    box = fc.np.array([[-1.0, 1.0]] * 3)
    sphere = fc.Field(fc.X**2 + fc.Y**2 + fc.Z**2 - sp.Rational(1, 4))
    assert fc.sign_sample(sphere, box) == (True, True)
    far = fc.Field(fc.X**2 + fc.Y**2 + fc.Z**2 + sp.Rational(1, 100))
    assert fc.sign_sample(far, box) == (True, False)
    assert fc.bernstein_sign(far, box) == 1
    # Touching zero (x^2 + y^2 + z^2 at 0) is no proof of a sign.
    assert fc.bernstein_sign(fc.Field(fc.X**2 + fc.Y**2 + fc.Z**2), box) == 0


def test_judge_finds_singular_points():
    box = fc.np.array([[-1.0, 1.0]] * 3)
    cone = fc.Field(fc.X**2 + fc.Y**2 - (fc.Z - sp.Rational(1, 3))**2)
    pts = fc.singular_points(cone, box)
    assert len(pts) == 1 and fc.np.allclose(pts[0], [0, 0, 1 / 3], atol=1e-9)
    assert len(fc.singular_points(fc.Field(fc.X**2 + fc.Y**2 + fc.Z**2 - 1), box)) == 0


def test_judge_flags_a_broken_mesh(monkeypatch):
    """The judge fails a mesh with a hole, one off the surface and an empty one."""
    import numpy as np

    import singmesh

    case = fc.Case("sphere", "x^2+y^2+z^2-1/4", fc.X**2 + fc.Y**2 + fc.Z**2 - sp.Rational(1, 4),
                   ((-1.0, 1.0),) * 3, "rational")
    assert fc.judge(case).status == "clean"
    real = singmesh.mesh

    def holed(*a, **k):
        m = real(*a, **k)
        m.faces = m.faces[1:]
        return m

    monkeypatch.setattr(singmesh, "mesh", holed)
    assert "open-edge" in fc.judge(case).failures

    def moved(*a, **k):
        m = real(*a, **k)
        m.vertices = m.vertices * (1 + 1e-6)
        return m

    monkeypatch.setattr(singmesh, "mesh", moved)
    assert "off-surface" in fc.judge(case).failures

    def empty(*a, **k):
        m = real(*a, **k)
        m.faces = np.zeros((0, 3), np.int64)
        return m

    monkeypatch.setattr(singmesh, "mesh", empty)
    assert "empty-with-sign-change" in fc.judge(case).failures


@pytest.mark.parametrize("name, text, seed, shift", [
    ("W x^2 - y^6 - z^4 rotated", "x^2 - y^6 - z^4", 5, (0.05, -0.1, 0.02)),
    ("J10 rotated", "x^3 + y^6 + z^2", 5, (0.05, -0.1, 0.02)),
])
def test_non_simple_germ_at_the_defaults_is_one_point(name, text, seed, shift):
    """At the default coarse 32 / fine 256, the Newton ends round a very
    flat point (|grad F| ~ d^5 a distance d from it) spread over more than
    eight boxes of the point search like the ends along a curve: on main
    they were dropped as 'a curve of singular points that could not be
    traced', and the point was lost."""
    import warnings

    import singmesh

    text = _rotated(text, seed, shift)
    q, _ = np.linalg.qr(np.random.default_rng(seed).normal(size=(3, 3)))
    apex = np.linalg.solve(q, np.array(shift))
    with warnings.catch_warnings():
        warnings.simplefilter("error", singmesh.SingularPointWarning)
        m = singmesh.mesh(text, ((-1.0, 1.0),) * 3)
    assert len(m.singularities) == 1
    s = m.singularities[0]
    assert s.classification.name == "non-simple"
    assert np.linalg.norm(np.asarray(s.point) - apex) <= 1e-12
    assert s.vertex is not None


@pytest.mark.parametrize("name, text, apex", APEX_ON_CURVES[:2], ids=[c[0] for c in APEX_ON_CURVES[:2]])
def test_curve_edges_follow_the_curve(name, text, apex):
    """Every edge of the traced curves runs along the curve f1 = f2 = 0 at
    its ends (its tangent grad f1 x grad f2, from the factors here), away
    from the apex where grad f2 vanishes.  On main s1-270's loop, whose two
    branches meet tangentially at the apex, was stepped past it onto the
    double curve crossing there: vertices on that curve, joined to the
    loop by edges across it."""
    import singmesh

    case = fc.case_from_text(name, text, ((-1.0, 1.0),) * 3)
    f1, f2 = (fc.Field(f) for f in case.factors)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        m = singmesh.mesh(text, ((-1.0, 1.0),) * 3, coarse=8, fine=64)
    assert m.singular_curves
    cell = 2.0 / 64
    worst = 1.0
    for c in m.singular_curves:
        p = np.asarray(c.points)
        e = np.diff(p, axis=0)
        e /= np.linalg.norm(e, axis=1, keepdims=True)
        for end, ends in ((e, p[:-1]), (e, p[1:])):
            t = np.cross(f1.grad(ends), f2.grad(ends))
            # Off the apex by a cell's fraction: the tangent is read there.
            keep = np.linalg.norm(ends - np.asarray(apex), axis=1) > 0.1 * cell
            t = t[keep] / np.linalg.norm(t[keep], axis=1, keepdims=True)
            if len(t):
                worst = min(worst, float(np.abs(np.einsum("ij,ij->i", end[keep], t)).min()))
    assert worst >= 0.9, f"a curve edge {np.degrees(np.arccos(worst)):.0f} degrees off the curve's tangent"


def _crossing_sheets_meshed(name: str, text: str, least: int = 20):
    """Mesh a product of two factors on [-1, 1]^3 (coarse 8, fine 64) and
    check it against the factors: each edge inside the box has two
    triangles or four (two sheets crossing), and every point of f1 = f2 = 0
    found by Newton on the factors lies on (or a cell from) an edge of
    four.  Returns the fuzz case, the mesh's vertices, its edges of four
    and the fine cell."""
    import meshcheck as mc
    import singmesh
    from scipy.spatial import cKDTree

    box = ((-1.0, 1.0),) * 3
    case = fc.case_from_text(name, text, box)
    b = case.box_array()
    curve = _common_zeros(*(fc.Field(f) for f in case.factors), b)
    assert len(curve) >= least
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        m = singmesh.mesh(text, box, coarse=8, fine=64)
    V = np.asarray(m.vertices)
    counts = mc.edge_counts(m.faces)
    wrong = [(k, V[e[0]].round(3).tolist()) for e, k in counts.items()
             if k not in (2, 4) and not (k == 1 and mc._same_box_face(V[e[0]], V[e[1]], b))]
    assert not wrong, wrong[:5]
    four = np.array([e for e, k in counts.items() if k == 4], np.int64).reshape(-1, 2)
    assert len(four), "no edge of four triangles (two sheets crossing)"
    on = np.concatenate([V[four[:, 0]], V[four[:, 1]], 0.5 * (V[four[:, 0]] + V[four[:, 1]])])
    cell = 2.0 / m.stats["fine"]
    far = cKDTree(on).query(curve)[0]
    assert far.max() <= cell, f"curve points {far.max() / cell:.2g} cells from the crossing edges"
    return case, V, four, cell


#: s2-126's factors: a plane and a quadric meeting along a hyperbola whose
#: two branches pass 10.3 fine cells apart (fine 64), one of them an arc
#: 1.6 cells deep from the face x = 1 back to it.
S2_126 = ("7/5*z + 3*y - 3/4*x", "-3/7*z^2 - 4/5*x*z + 1/5*x^2 - 6/5*y - 1/8*x + 1/5")
CLOSE_BRANCHES = [
    ("s2-126", "*".join(f"({f})" for f in S2_126)),
    ("s2-126 turned", _tilted_product(S2_126, (1, -2, 1), 0.05, (0.9, 0.35, -0.25), (-0.01, 0.02, 0.01))),
]


@pytest.mark.parametrize("name, text", CLOSE_BRANCHES, ids=[c[0] for c in CLOSE_BRANCHES])
def test_close_branches_of_a_double_curve(name, text):
    """Two branches of the double curve closer than two tubes' width: the
    sheets between them are meshed (no open edge inside the box, no edge
    of three triangles), and every point of f1 = f2 = 0 found here by
    Newton on the factors lies on edges of four triangles.  On main the
    tubes merged between the branches: the arc's 7 edges nearest the
    other branch had no triangle (line cells), the other's 2."""
    case = _crossing_sheets_meshed(name, text)[0]
    assert fc.judge(case, 8, 64).status == "clean"


#: s2-66's factors: a cubic with a singular point at the origin (quadratic
#: part x (3 z - 5 y), an A2 point) and a plane 0.033 above it, tangent to
#: the cubic there: four branches of the double curve from that crossing,
#: 1.3 fine cells (fine 64) from the cubic's singular point.
S2_66 = ("4*y^2*z + 8/7*x*y*z - 2/3*x^2*y + 3*x*z - 5*x*y", "6*z - 1/7*y + 4/7*x - 1/5")
CROSSING_BESIDE_A_POINT = [
    ("s2-66", "*".join(f"({f})" for f in S2_66)),
    ("s2-66 turned", _tilted_product(S2_66, (2, 1, -1), 0.2, (0.0, 0.0, 0.0), (0.03, -0.02, 0.01))),
]


@pytest.mark.parametrize("name, text", CROSSING_BESIDE_A_POINT, ids=[c[0] for c in CROSSING_BESIDE_A_POINT])
def test_crossing_of_curves_beside_a_singular_point(name, text):
    """Each curve edge has four triangles (two sheets crossing) and every
    other edge inside the box two; the points of f1 = f2 = 0 found here by
    Newton on the factors lie on edges of four.  On main the rails round
    the crossing, ten cells out on sheets bent by the cubic's singular
    point, went out along a third branch and back: edges of six."""
    _crossing_sheets_meshed(name, text)


#: s4-210's factors: a quadric cone with its apex at (-0.4212, 0, 0) on a
#: saddle; both hold the x-axis, so their curve has four branches from the
#: apex, two of them along the axis.
S4_210 = ("-2.64932357459892*z^2 - 0.833721672478706*y*z - 0.770174577670161*y^2 - 1.49020364208456*x*y"
          " - 0.627603706123609*y", "-9/7*x*y - 4/7*z")


def _hairpin(seed: int, slope: float, k: float) -> str:
    """The plane z = 0 times the sheet z = slope (y - k x^2), each rotated
    (seed) and shifted: two sheets at atan(slope) along a parabola whose tip
    turns within 1 / (2 k) (a fifth of a fine cell at k = 100, fine 64) and
    whose arms stay 2 to 6 cells apart for half their length."""
    shift = (0.05, -0.1, 0.02)
    return f"({_rotated('z', seed, shift)})*({_rotated(f'z - {slope}*(y - {k}*x^2)', seed, shift)})"


TRACED_THROUGH = [
    ("s4-210", "*".join(f"({f})" for f in S4_210)),
    ("hairpin, seed 5", _hairpin(5, 0.5, 100)),
    ("hairpin, seed 7", _hairpin(7, 0.3, 150)),
    ("hairpin, seed 3", _hairpin(3, 0.5, 100)),
]


@pytest.mark.parametrize("name, text", TRACED_THROUGH, ids=[c[0] for c in TRACED_THROUGH])
def test_curve_traced_through_an_apex_and_round_a_hairpin(name, text):
    """Every point of f1 = f2 = 0 found here by Newton on the factors lies
    within half a cell of the traced curves (no trace ends inside the box),
    and the mesh passes the judge.  On main the traces were lost at the
    cone's apex (s4-210: the axis beyond it never traced, an edge of six
    triangles) and at the hairpin's tip, its other arm then not traced
    (seeds 5 and 7, 0.9 and 5.5 cells off; seed 7 edges of six); seed 3,
    clean on main, guards against a step from one arm to the other (the
    loop traced twice, a false crossing)."""
    import singmesh
    from scipy.spatial import cKDTree

    box = ((-1.0, 1.0),) * 3
    case = fc.case_from_text(name, text, box)
    curve = _common_zeros(*(fc.Field(f) for f in case.factors), case.box_array(), n=81)
    assert len(curve) >= 1000
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        m = singmesh.mesh(text, box, coarse=8, fine=64)
    assert not [s.describe() for s in m.special_points if s.kind == "end of the trace"]
    # The polylines, each edge sampled at eighths.
    u = np.linspace(0.0, 1.0, 9)[:, None, None]
    on = np.concatenate([(np.asarray(c.points)[:-1] * (1 - u) + np.asarray(c.points)[1:] * u).reshape(-1, 3)
                         for c in m.singular_curves])
    cell = 2.0 / 64
    far = cKDTree(on).query(curve)[0]
    assert far.max() <= 0.5 * cell, f"curve points {far.max() / cell:.2g} cells from the traced curves"
    v = fc.judge(case, 8, 64)
    assert v.status == "clean", v.detail


#: (slope, a, turn axis, angle, shift): the plane x = 0 times the sheet
#: x = slope y - a y^2 z, turned and shifted (15-digit coefficients).  Both
#: hold the z-axis, crossing along it at atan(slope) = 7-9 degrees: 1.5
#: cells apart only 9-10 cells out, so the axis gets the wide tube.  Their
#: other curve, the hyperbola y z = slope / a in x = 0, passes 5 to 19
#: cells from the axis over most of the box (the feature of fuzz s4-838,
#: a plane through a cubic's line at 3.6 degrees).
WIDE_BESIDE_A_CURVE = [
    (0.151, 0.612, (0.33, -1.303, 0.905), 0.156, (0.033, -0.009, 0.005)),
    (0.122, 0.524, (0.547, -0.736, -0.163), 0.126, (-0.005, -0.037, -0.01)),
    (0.151, 0.649, (-0.506, 0.594, 0.891), 0.247, (-0.031, 0.03, -0.031)),
]


@pytest.mark.parametrize("slope, a, axis, angle, shift", WIDE_BESIDE_A_CURVE,
                         ids=[f"slope {c[0]} a {c[1]}" for c in WIDE_BESIDE_A_CURVE])
def test_wide_tube_beside_another_curve(slope, a, axis, angle, shift):
    """Two sheets crossing at a few degrees along a line, and another curve
    of theirs within the line's wide tube: checked as
    :func:`_two_factor_mesh_checked`.  On main (and on a5ab96f, where a
    false crossing of the traces cut the line) the wide tube held both
    curves and the sheet between them had no rail: triangles from a rail
    12 cells out to both curves (open edges, edges of three)."""
    text = _tilted_product(("x", f"x - {slope}*y + {a}*y^2*z"), axis, angle, (0.0, 0.0, 0.0), shift)
    _two_factor_mesh_checked(f"wide {slope} {a}", text, ((-1.0, 1.0),) * 3)


def _two_factor_mesh_checked(name: str, text: str, box) -> None:
    """Mesh a product of two factors (coarse 8, fine 64) and check it against
    the factors: every edge inside the box has two triangles or four,
    every point of f1 = f2 = 0 found by Newton on the factors lies within
    half a (fine 64) cell of a mesh edge whose ends are on both factors,
    and the judge passes."""
    import meshcheck as mc
    import singmesh
    from scipy.spatial import cKDTree

    case = fc.case_from_text(name, text, box)
    b = case.box_array()
    curve = _common_zeros(*(fc.Field(f) for f in case.factors), b)
    assert len(curve) >= 1000
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        m = singmesh.mesh(text, box, coarse=8, fine=64)
    V = np.asarray(m.vertices)
    wrong = [(k, V[e[0]].round(3).tolist()) for e, k in mc.edge_counts(m.faces).items()
             if k not in (2, 4) and not (k == 1 and mc._same_box_face(V[e[0]], V[e[1]], b))]
    assert not wrong, wrong[:5]
    # The mesh's edges between vertices on both factors, each sampled at eighths.
    both = np.ones(len(V), bool)
    for f in case.factors:
        fld = fc.Field(f)
        both &= np.abs(fld.value(V)) <= 1e-9 * np.maximum(np.linalg.norm(fld.grad(V), axis=1), 1e-300)
    e = np.array([e for e in mc.edge_counts(m.faces) if both[e[0]] and both[e[1]]], np.int64).reshape(-1, 2)
    u = np.linspace(0.0, 1.0, 9)[:, None, None]
    on = (V[e[:, 0]] * (1 - u) + V[e[:, 1]] * u).reshape(-1, 3)
    cell = float(np.ptp(b, axis=1).max()) / 64
    far = cKDTree(on).query(curve)[0]
    assert far.max() <= 0.5 * cell, f"curve points {far.max() / cell:.2g} cells from mesh edges on the curve"
    v = fc.judge(case, 8, 64)
    assert v.status == "clean", v.detail


#: s4-530's factors: a cubic cone (apex at the origin, outside the box's
#: curve) and a quadric; their double curve turns within a cell at
#: (-0.18, 0.12, 0.42), and two stretches of it pass 5.6 to 5.9 fine cells
#: apart (max norm; the box is four times thinner in z): closer than two
#: tubes' width (CREASE_MIN_GAP), under the old CURVE_GAP_LEAST of 6.
S4_530 = ("-3/4*z^3 + 8/3*y*z^2 + 3/5*x*y*z + 5*x*y^2 - 3*x^3",
          "-2.81367693149033*x*y + 2.19362086299765*x^2 - 2.49478317102428*z + 1.00106264290257*y"
          " + 0.798474291009399")
S4_530_BOX = ((-2.0, 2.0), (-1.5, 1.5), (-0.5, 0.5))
CLOSE_STRETCHES = [
    ("s4-530", "*".join(f"({f})" for f in S4_530)),
    ("s4-530 turned 1", _tilted_product(S4_530, (0.346, 0.822, 0.33), 0.143, (0.0, 0.0, 0.0), (-0.011, -0.005, 0.02))),
    ("s4-530 turned 2", _tilted_product(S4_530, (0.581, 0.365, 0.294), 0.118, (0.0, 0.0, 0.0), (0.002, -0.01, 0.017))),
    ("s4-530 turned 3", _tilted_product(S4_530, (-0.276, 1.294, 1.007), 0.145, (0.0, 0.0, 0.0), (0.013, 0.002, -0.013))),
]


@pytest.mark.parametrize("name, text", CLOSE_STRETCHES, ids=[c[0] for c in CLOSE_STRETCHES])
def test_close_stretches_of_a_double_curve_are_parted(name, text):
    """Two stretches of the double curve 2 to 6 cells apart share one tube
    at fine 64; the lattice is made one level finer (CURVE_GAP_LEAST), and
    every edge inside the box has two triangles or four, every point of
    f1 = f2 = 0 found here by Newton on the factors lies within half a
    (fine 64) cell of a mesh edge whose ends are on both factors, and the
    judge passes.  On main the sheet between the stretches had no rail:
    36 curve edges of three triangles and open edges between the curves
    (fuzz s4-530; clean on a5ab96f only where a false crossing cut the
    curve and one of its arms was not traced, 7 cells off)."""
    _two_factor_mesh_checked(name, text, S4_530_BOX)


#: A plane through the axis of a hyperboloid of two sheets, z^2 - x^2 - y^2
#: = a: their double curve is the hyperbola z^2 - x^2 = a, whose branches
#: pass 2 sqrt(a) apart, here 3.5 to 5 fine cells (fine 64) before the
#: turn (axis, angle in radians, shift): closer than 10 cells after one
#: level more (fuzz s3-350, s4-410, s6-570 and s6-710:
#: traces of a double curve 2.9 to 4.5 cells apart at fine 64).
HYPERBOLA_TURNS = [(3.5, (0.581, 0.365, 0.294), 0.477, (0.004, -0.017, 0.029)),
                   (4.0, (-0.482, 0.599, 0.04), 0.302, (-0.03, -0.024, 0.025)),
                   (4.5, (-0.276, 1.294, 1.007), 0.581, (0.022, 0.004, -0.022)),
                   (5.0, (0.774, 0.281, -0.554), 0.381, (-0.035, -0.007, 0.017))]


def _close_hyperbola(cells: float, axis, angle: float, shift) -> str:
    """The plane y = 0 times the hyperboloid z^2 - x^2 - y^2 = a whose
    hyperbola's branches are ``cells`` fine cells (fine 64 on [-1, 1]^3)
    apart, turned and shifted (:func:`_tilted_product`)."""
    h = cells / 64.0
    return _tilted_product(("y", f"z^2 - x^2 - y^2 - {h * h!r}"), axis, angle, (0.0, 0.0, 0.0), shift)


@pytest.mark.xfail(strict=True, reason="branches 5 to 9 cells apart one level finer still share a tube; two levels "
                   "(CURVE_GAP_MAX_RAISE 2, open12 318f1c3) part them but break s3-950 and the Seepferdchen")
@pytest.mark.parametrize("cells, axis, angle, shift", HYPERBOLA_TURNS,
                         ids=[f"{c} cells" for c, *_ in HYPERBOLA_TURNS])
def test_branches_a_few_cells_apart_get_tubes_of_their_own(cells, axis, angle, shift):
    """The two branches of a double curve 3.5 to 5 cells apart at fine 64
    (2.5 to 4.5 in the max norm after the turn) are at most 9 apart one
    level finer, where they still share a tube; the lattice should be made
    finer until they are about 10 cells apart (two levels here): every edge
    inside the box has two triangles or four, every point of f1 = f2 = 0
    found by Newton on the factors lies within half a (fine 64) cell of a
    mesh edge whose ends are on both factors, and the judge passes.  On
    main (one level) the sheet between the branches has no rail: 14 to 22
    curve edges of three triangles and two open edges."""
    _two_factor_mesh_checked(f"hyperbola {cells}", _close_hyperbola(cells, axis, angle, shift), ((-1.0, 1.0),) * 3)


def _line_factor(n, p) -> str:
    """The plane through p with normal n as text, 15 digits (as users give them)."""
    return f"({n[0]:.15g}*x + {n[1]:.15g}*y + {n[2]:.15g}*z + {-float(np.dot(n, p)):.15g})"


def _near_face(kind: str, depth: float, angle: float) -> str:
    """Two planes crossing along a line, or a plane and a sphere along a circle, ``depth`` fine cells
    (of 64 on [-1, 1]) inside the face x = -1 at (0.113, -0.071), at ``angle`` degrees to it."""
    a = np.radians(angle)
    p0 = np.array([-1.0 + depth * 2.0 / 64, 0.113, -0.071])
    if kind == "planes":
        t = np.array([np.sin(a), np.cos(a) * np.cos(0.7), np.cos(a) * np.sin(0.7)])
        u = np.cross(t, [0.3, 0.5, 0.8])
        u /= np.linalg.norm(u)
        v = np.cross(t, u)
        n1, n2 = np.cos(0.4) * u + np.sin(0.4) * v, np.cos(1.5) * u + np.sin(1.5) * v
        return _line_factor(n1, p0) + "*" + _line_factor(n2, p0)
    # The circle of radius 0.6 round p0 in the tilted plane; the sphere's
    # centre 0.35 off it (the sheets cross at 30 degrees).
    m = np.array([np.cos(a), np.sin(a) * np.cos(0.7), np.sin(a) * np.sin(0.7)])
    c = p0 + 0.35 * m
    sphere = f"((x - {c[0]:.15g})^2 + (y - {c[1]:.15g})^2 + (z - {c[2]:.15g})^2 - {0.6 ** 2 + 0.35 ** 2:.15g})"
    return _line_factor(m, p0) + "*" + sphere


#: (kind, depth in cells, angle to the face in degrees): planes d2 a4 and
#: d0 a2 fail on main (12 edges of six triangles by the face), as does
#: planes d3 a4 (its end on y = 1 5.6 cells from x = -1: 5 edges of six).
NEAR_A_FACE = [("planes", d, a) for d, a in ((0, 4), (1, 4), (2, 4), (3, 4), (0, 2), (2, 2), (3, 8), (1, 0),
                                             (3, 0))] + [
    ("sphere", d, a) for d, a in ((0, 5), (1, 5), (2, 0), (3, 5))]
@pytest.mark.parametrize("kind, depth, angle", NEAR_A_FACE, ids=[f"{k} d{d} a{a}" for k, d, a in NEAR_A_FACE])
def test_double_curve_near_a_face(kind, depth, angle):
    """Edges of more than two triangles only on the curve (four, two
    sheets crossing), open edges only on the box's faces, and the curve's
    points (Newton on the two factors) on edges of four.  On main, where
    the line ran 0-1.5 cells inside the face x = -1, the tube's face
    squares were not traced: one sheet's trace on the face was joined to
    the other's, the rails broke and a piece of one was zipped to the
    curve twice (fuzz s3-726: edges of six triangles)."""
    text = _near_face(kind, depth, angle)
    case, V, four, cell = _crossing_sheets_meshed(f"{kind} {depth} {angle}", text, least=100)
    _four_on_the_curve(case, V, four, cell)


def _four_on_the_curve(case, V, four, cell):
    """Each edge of four triangles lies on f1 = f2 = 0: its midpoint's Newton
    (min-norm) step onto the factors' common zeros is short (the chord of a
    circle sags 1e-3 cell); and no two vertices are closer than 1e-9 of the box."""
    from scipy.spatial import cKDTree

    f1, f2 = (fc.Field(f) for f in case.factors)
    mid = 0.5 * (V[four[:, 0]] + V[four[:, 1]])
    q = mid.copy()
    for _ in range(20):
        J = np.stack([f1.grad(q), f2.grad(q)], axis=1)
        r = np.stack([f1.value(q), f2.value(q)], axis=1)
        q = q - np.einsum("kij,kj->ki", np.linalg.pinv(J), r)
    assert np.linalg.norm(q - mid, axis=1).max() <= 0.05 * cell
    side = float(np.max(np.diff(case.box_array(), axis=1)))
    assert not len(cKDTree(V).query_pairs(1e-9 * side)), "two vertices closer than 1e-9 of the box"


def _number(v: float) -> str:
    """A float as users type it: 15 significant digits, no exponent."""
    return np.format_float_positional(float(v), precision=15, unique=False, fractional=False, trim="-")


def _plane_text(n, p) -> str:
    return f"({_number(n[0])}*x + {_number(n[1])}*y + {_number(n[2])}*z + {_number(-np.dot(n, p))})".replace("+ -", "- ")


def _by_a_box_edge(kind: str, depth: float, angle: float, steep: float, bend: float = 0.0) -> str:
    """Two planes crossing along a line, or a plane and a sphere along a circle of radius 0.6, through
    (0.113, -1 + ``depth`` fine cells (of 64 on [-1, 1]), 1) on the face z = 1, ``depth`` cells from the
    box edge y = -1, z = 1; there the curve runs at ``angle`` degrees to the face y = -1 (towards it
    when negative: it leaves through y = -1) and crosses z = 1 at asin(cos(``steep``) cos(angle))
    (81, 64 and 39 degrees for steep 0.15, 0.45, 0.9).  The circle's centre is towards the box's
    centre turned by ``bend`` radians about the curve; the sheets cross at 30 degrees."""
    a = np.radians(angle)
    p0 = np.array([0.113, -1.0 + depth * 2.0 / 64, 1.0])
    t = np.array([np.sin(steep) * np.cos(a), np.sin(a), -np.cos(steep) * np.cos(a)])
    u = np.cross(t, [0.3, 0.5, 0.8])
    u /= np.linalg.norm(u)
    v = np.cross(t, u)
    if kind == "planes":
        return (_plane_text(np.cos(0.4) * u + np.sin(0.4) * v, p0) + "*"
                + _plane_text(np.cos(1.5) * u + np.sin(1.5) * v, p0))
    w = -p0 - np.dot(-p0, t) * t
    w /= np.linalg.norm(w)
    w = np.cos(bend) * w + np.sin(bend) * np.cross(t, w)
    m = np.cross(t, w)
    c = p0 + 0.6 * w + 0.35 * m
    k = float(c @ c) - 0.6 ** 2 - 0.35 ** 2
    sphere = (f"(x^2 + y^2 + z^2 + {_number(-2 * c[0])}*x + {_number(-2 * c[1])}*y + {_number(-2 * c[2])}*z"
              f" + {_number(k)})").replace("+ -", "- ")
    return _plane_text(m, p0) + "*" + sphere


#: (kind, depth in cells, angle in degrees, steep, bend) as in
#: :func:`_by_a_box_edge`: each fails on main (edges of six or three
#: triangles, or none of four).
BY_A_BOX_EDGE = [("planes", 1, -3, 0.9, 0.0), ("planes", 2, -6, 0.15, 0.0), ("sphere", 5, 0, 0.45, 1.2),
                 ("sphere", 1, -6, 0.15, -1.2), ("sphere", 2, -10, 0.15, -1.2), ("sphere", 2, 5, 0.9, -1.2)]
#: ... and of the same class, not fixed: a curve 2 cells from y = -1 at z = 1
#: (the sheets' traces on y = -1 cut within 8 cells of the curve's end on
#: z = 1; cutting them only near ends on their own face fixes these two but
#: breaks fuzz s3-978, whose end on x = -1 is 2.4 cells from y = 1).
BY_A_BOX_EDGE_OPEN = [("planes", 2, -8, 0.4, 0.0), ("sphere", 2, 0, 0.9, -1.2)]


@pytest.mark.parametrize("kind, depth, angle, steep, bend", BY_A_BOX_EDGE,
                         ids=[f"{k} d{d} a{a} s{s} b{b}" for k, d, a, s, b in BY_A_BOX_EDGE])
def test_double_curve_by_a_box_edge(kind, depth, angle, steep, bend):
    """A double curve crossing the face z = 1 at 39-81 degrees 1-5 cells
    from the box edge y = -1, running along or leaving through y = -1:
    edges of more than two triangles only on the curve (four), open edges
    only on the box's faces, the curve's points (Newton on the factors) on
    edges of four, no two vertices closer than 1e-9 of the box."""
    text = _by_a_box_edge(kind, depth, angle, steep, bend)
    case, V, four, cell = _crossing_sheets_meshed(f"{kind} {depth} {angle} {steep} {bend}", text)
    _four_on_the_curve(case, V, four, cell)


@pytest.mark.xfail(strict=True, reason="sheets' traces on a face cut near a curve end on the next face")
@pytest.mark.parametrize("kind, depth, angle, steep, bend", BY_A_BOX_EDGE_OPEN,
                         ids=[f"{k} d{d} a{a} s{s} b{b}" for k, d, a, s, b in BY_A_BOX_EDGE_OPEN])
def test_double_curve_by_a_box_edge_open(kind, depth, angle, steep, bend):
    test_double_curve_by_a_box_edge(kind, depth, angle, steep, bend)


#: Failures of ``benchmarks/fuzz.py`` not fixed yet (seed, index, what is
#: wrong): strict, so that a fixed one shows.
OPEN_CASES = [
    (1, 270, "the loop of f1 = f2 = 0 has a cusp at the cubic cone's apex, where the double curve through it "
             "crosses: the loop's half-sheets are also that curve's, and their rails snap to it (open edges)"),
    (3, 474, "a trace lost next to a crossing of curves: edges of six triangles"),
    (4, 33, "edges of four and six triangles along the z-axis at 0.09 < z < 0.35, where F is a cuspidal edge "
            "(F = 1.97 z^2 x^2 + 0.034 z y^3 + ...: 2 sign changes on circles of radius 0.001 to 0.03 round "
            "the axis at z = 0.2, 0.35, 0.5; the mesher reads A2 there too): a real defect (open12 triage)"),
    (4, 206, "a plane and a cubic: non-manifold edges"),
    (4, 850, "edges of four triangles on the z-axis, f2's own double line with a pinch point (the judge "
             "allows four only on f1 = f2 = 0 and misses f2's curve: its Newton ends at the pinch point); the "
             "edges of six triangles past the triple point (0, 0, 0.80) are gone (facets/tubes.py "
             "_no_excursions, tests/test_pinch_and_triple_point.py); F has 4 sign changes on circles of radius "
             "0.001 to 0.03 round the z-axis at z = 0.5, 0.98, 1.3 (a double line, four triangles right): "
             "the judge's limit (open12 triage)"),
    (3, 350, "traces of the double curve 2.9 cells apart at fine 64 share a tube one level finer too "
             "(5.7 cells): 25 edges of three triangles, 2 open edges; clean with two levels (open12, "
             "318f1c3), which broke s3-950 and the Seepferdchen"),
    (4, 410, "traces of the double curve 4.5 cells apart at fine 64 share a tube one level finer too "
             "(9.1 cells): 45 edges of six or eight triangles; clean with two levels (open12, "
             "318f1c3), which broke s3-950 and the Seepferdchen"),
    (4, 746, "a cuspidal edge (-5/7 z^3 - 9/4 x^2 y, its y-axis) times a plane: 2 lattice roots 6.5 cells "
             "off the mesh at (0.23, 0.5, -0.09), between the sheets beside two short pieces read as corank-2 "
             "edges.  Clean on main 965fd82 only where those pieces' wide tube went round every curve "
             "vertex (as s4-893; and only under some PYTHONHASHSEED values, before 530989b)"),
    (4, 893, "the x-axis is read as two A1 double curves and a short corank-2 edge between them, but across "
             "it F ~ 1.1 x^2 z^4 - 2.7 y^6 (sheets tangent, not crossing): 3 lattice roots 2.0 cells off the "
             "mesh 6 cells from the axis at x = -0.375.  Clean on main 965fd82 only because the corank-2 "
             "edge's wide tube went round every curve vertex (facets/tubes.py wide_vertices); a wide tube "
             "for such 'double curves' is not done"),
    (4, 16, "the y-axis is a curve of D6 points for y < 0 (x (z^2 + 3 x^4 / y): a plane and two sheets "
            "tangent along the axis), read as D4: sheets left out up to 9 cells from the axis (found by the "
            "judge's check of pieces left out)"),
    # Seeds 6 and 7 (fuzz.py --n 1000, coarse 8, fine 64; 9 and 7 failures
    # on main ba35d69, s6-688 and s6-666 fixed on this branch).
    (6, 344, "-3 z^5 - 3 y^5 + 3/2 x^3 z^2 has the x-axis as a curve of singular points (F, grad F vanish "
             "on y = z = 0): 27 vertices up to 3.8e-5 of the box off F = 0; not a product, not looked into"),
    (6, 414, "a plane times a cubic: 86 edges of six triangles, the first at (0.12, -0.16, -0.16)"),
    (6, 570, "traces of the double curve 3.4 cells apart at fine 64 share a tube one level finer too "
             "(6.9 cells): 23 edges of three triangles, 4 open edges; clean with two levels (open12, "
             "318f1c3), which broke s3-950 and the Seepferdchen"),
    (6, 601, "a smooth surface but for a corank-3 point at the origin (3-jet 0) on the y-axis, a lattice "
             "line in the surface: its star's cycles are joined at the axis's lattice points now "
             "(facets.cycles._corner_bridges; the point is a vertex), but 4 open edges at (0, 0.21, 0) remain: "
             "the sheet x ~ -c z^5 hugs the lattice plane x = 0 along the axis, and the events at the axis's "
             "lattice points lie in the cells x < 0, z > 0 only, while the sheet lies in x > 0, z < 0 too"),
    (6, 710, "traces of the double curve 4.2 cells apart at fine 64 share a tube one level finer too "
             "(8.5 cells): 19 edges of three or five triangles, 4 open edges; clean with two levels "
             "(open12, 318f1c3), which broke s3-950 and the Seepferdchen"),
    (7, 192, "a corank-3 point at the origin with the y- and z-axes, lattice lines, on the surface: its "
             "star is closed now (facets.cycles._corner_bridges), but one vertex 5.9e-5 from the point lies "
             "3e-6 off the plane z = 0 (on y = 0, F = x^5 z / 2; |grad F| 5e-22 there)"),
    (7, 422, "the cubic -8 y^3 + ... + 4 x^2 + 1 touches the face y = 0.5 at (0, 0.5, 0) (its double curve "
             "with the plane z = 0 ends there): two vertices 4.7e-6 and 1e-3 outside the box, polygon "
             "centres projected along grad F across the face (facets/triangulate.py), not held in it; projecting "
             "those again within the face they crossed makes it clean (tried, not kept: no case of the class "
             "that fails on main was found, the cubic alone and tilted copies are clean)"),
    (7, 458, "a quadric cone (apex at the origin) times a cubic: 15 edges of three triangles, the first "
             "at (0.93, -0.34, -1.99) by the face z = -2"),
    (7, 742, "a plane times a cubic whose x-axis is a curve of singular points of its own (y = z = 0): 20 "
             "edges of four triangles along the axis, which the judge allows only on the factors' common "
             "curve (maybe the judge's limit: it saw no curve of that factor; not checked)"),
]


@pytest.mark.xfail(strict=True, reason="fuzz cases not fixed yet (OPEN_CASES)")
@pytest.mark.parametrize("seed, index, what", OPEN_CASES, ids=[f"s{s}-{i}" for s, i, _ in OPEN_CASES])
def test_open_fuzz_case(seed, index, what):
    v = fc.judge(fc.make_case(seed, index), 8, 64)
    assert v.status in ("clean", "empty"), f"{what}: {v.detail}"
