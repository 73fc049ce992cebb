"""Every numerical tolerance and limit of singmesh, in one place.

Each value says what it protects against.  Change them here only.
"""

#: Largest total degree accepted.  Bernstein conversion on a box loses
#: roughly ``degree`` bits; beyond this the 1e-10 vertex accuracy is not
#: guaranteed any more.
MAX_DEGREE = 18

#: Deepest subdivision: boxes per axis at the finest level is at most
#: ``2**MAX_LEVEL``.  Keeps integer lattice keys well inside int64.
MAX_LEVEL = 14

#: A value computed in floating point is taken for exactly zero when its
#: magnitude is below this many ulps of the magnitude of the terms summed
#: to get it (the rounding-error bound of the evaluation).
ZERO_ULPS = 64.0

#: A root of F on a lattice line closer than this (in fine-lattice cell
#: units) to a lattice point at which F is zero *is* that lattice point.
SNAP_LATTICE = 1e-6

#: Roots of the restriction of F to a lattice line: eigenvalues whose
#: imaginary part is below this (relative to the line's length scale) are
#: candidates for real roots; they are then confirmed by sign tests.
ROOT_IMAG = 1e-5

#: Newton polishing of roots on lattice lines: iterations and the relative
#: step at which it stops.
NEWTON_ITERATIONS = 8
NEWTON_STEP = 1e-15

#: Roots on one line closer than this (relative to the line's length) are
#: one cluster: a multiple root such as an edge tangency.
ROOT_CLUSTER = 1e-7

#: Largest polygon triangulated by exhaustive search over all its
#: triangulations (Catalan(n-2) of them); larger ones get a centre vertex.
MAX_TEMPLATE_POLYGON = 8
