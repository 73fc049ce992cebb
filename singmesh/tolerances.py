"""Every numerical tolerance and limit of singmesh, in one place.

Each value says what it protects against.  Change them here only.
"""

#: Largest total degree accepted.  Bernstein conversion on a box loses
#: roughly ``degree`` bits; beyond this the 1e-10 vertex accuracy is not
#: guaranteed any more.
MAX_DEGREE = 18

#: Deepest nesting of brackets, signs and exponents the parser reads (a
#: recursive descent: each level costs a few Python frames, and sympy
#: recurses over the tree again; Python's limit is 1000 frames).
MAX_NESTING = 150

#: Largest integer power of an expression in x, y, z the parser builds:
#: sympy expands it exactly ((x+y+z)^1000 has half a million terms and
#: takes minutes) before the degree is checked against ``MAX_DEGREE``.
#: Above ``MAX_DEGREE`` so that a power which cancels ((x+1)^20 - (x+1)^20
#: + x) still reads.
MAX_POWER = 4 * MAX_DEGREE

#: Largest decimal exponent of a power of numbers the parser computes
#: (sympy computes them exactly: 9^9^9 has 370 million digits).  Doubles
#: end at 10^308; a product of such numbers may come back in range.
MAX_NUMBER_EXPONENT = 1000

#: Largest |coordinate| of a box.  Several tolerances (Newton residuals,
#: the singular point search) are partly absolute: Cayley's cubic scaled by
#: 1e9 loses its nodes and a unit sphere centred at x = 1e9 comes out
#: empty, both silently; at 1e8 they are still right.  Refused above this
#: (with a factor 100 of room) rather than meshed wrong.
BOX_MAX_COORD = 1e6

#: Smallest side of a box.  A degree-18 polynomial scaled to a box of side
#: s has coefficients of about s^18: under 1e-16 they leave the range of
#: doubles (1e-308); a sextic scaled by 1e-60 comes out empty.
BOX_MIN_SIDE = 1e-12

#: Smallest side of a box relative to its largest |coordinate|: the fine
#: lattice (up to 2^14 cells) must stay far above the doubles' spacing
#: there (a unit box at 1e6 is at the limit).
BOX_MIN_RELATIVE_SIDE = 1e-6

#: Characters of the offending line quoted in a syntax error (the rest is
#: "..."): one readable line for a 100 kB input.
SOURCE_QUOTE = 60

#: Deepest subdivision: boxes per axis at the finest level is at most
#: ``2**MAX_LEVEL``.  Keeps integer lattice keys well inside int64.
MAX_LEVEL = 14

#: A box is empty when all its Bernstein coefficients exceed this fraction of
#: the largest one in one sign: below it, a coefficient may be a rounded zero.
PRUNE_SLACK = 1e-10

#: A value computed in floating point is taken for exactly zero when its
#: magnitude is below this many ulps of the magnitude of the terms summed
#: to get it (the rounding-error bound of the evaluation).
ZERO_ULPS = 64.0

#: What rounding the input's coefficients can do to a value computed from
#: them: a coefficient typed to relative precision rho (``Surface.rounding``,
#: e.g. 5e-15 for 15 significant digits) moves F(p) by up to rho times the
#: sum of its terms' magnitudes at p, and expanding a product of rounded
#: factors multiplies that by up to the degree.  A value below
#: ``INPUT_ROUNDING * degree * rho`` times its magnitude is zero to the
#: precision of the input.
INPUT_ROUNDING = 8.0

#: A root of F on a lattice line closer than this (in fine-lattice cell
#: units) to a lattice point at which F is zero *is* that lattice point.
SNAP_LATTICE = 1e-6

#: A root of F on a lattice line closer than this (relative to the box) to a
#: lattice point shares its vertex with the roots of the other lines through
#: that point (placed on the surface).  Apart, they would be vertices a hair
#: apart with triangles of no area between them (a thin cusp, a sheet
#: grazing a lattice point).  Roots this far from the point on three lines
#: through it span a triangle of about 0.9e-12 of the box squared, well
#: above the 1e-14 that counts as no area; at 1e-7 (ROOT_CLUSTER's size) a
#: sheet grazing a corner of a float-rotated A4 form left one of 3e-14.
SNAP_DISTANCE = 1e-6

#: Roots of the restriction of F to a lattice line: eigenvalues whose
#: imaginary part is below this (relative to the line's length scale) are
#: candidates for real roots; they are then confirmed by sign tests.
ROOT_IMAG = 1e-5

#: A lattice line's polynomial is skipped (no eigenvalues) only where |p| on
#: the segment exceeds what a root kept by ROOT_IMAG allows: its Bernstein
#: hulls on ROOT_FREE_PIECES pieces of the segment (one hull over a line's
#: whole extent is too loose) stay above 2 ROOT_IMAG sum k |c_k| (twice the
#: bound of |b| max |p'|), plus ROOT_FREE_BACKWARD (sum |c|)^2 / |c_d| (the
#: eigenvalues' backward error, ~ n^3 eps of it, with a 1e5-fold margin)
#: plus ROOT_FREE_ROUNDING 2^n sum |c| (the rounding of the hull).
ROOT_FREE_PIECES = 8
ROOT_FREE_BACKWARD = 1e-8
ROOT_FREE_ROUNDING = 1e-12

#: Newton polishing of roots on lattice lines: iterations and the relative
#: step at which it stops.
NEWTON_ITERATIONS = 8
NEWTON_STEP = 1e-15

#: Surface.project: a Newton step that leaves F's domain (sqrt(x) + y - 0.5
#: near x = 0, where the surface is tangent to the domain's edge and a full
#: step lands at x < 0, F = NaN) is halved at most this many times before
#: the point stays where it was: 2^-30 of a step is below any lattice cell.
PROJECT_HALVINGS = 30

#: A sign sample between two roots of a lattice line with a pole or an end
#: of F's domain between them (boxes.edges._side_signs) is moved half-way
#: towards its root until F is continuous between, at most this many
#: times: 2^-40 of half a cell is at rounding level of the coordinates.
SIGN_SAMPLE_HALVINGS = 40

#: Sign samples between roots of a lattice line are asked whether F is
#: zero to rounding there (Surface.is_zero) only where |F| is below this
#: fraction of the largest sample: rounding noise is far below it.
SIGN_ZERO_PREFILTER = 1e-9

#: Roots on one line closer than this (relative to the line's length) are
#: one cluster: a multiple root such as an edge tangency.
ROOT_CLUSTER = 1e-7

#: A triangle whose doubled area is below this times its longest edge squared
#: is flat (its vertices are collinear to rounding): a collapsed feature.
ZERO_AREA = 1e-12

#: Triangles with doubled area below this times their longest edge squared
#: are slivers: their longest edge is flipped where that helps.
SLIVER_AREA = 1e-6

#: A skeleton curve crossing a star's link cycle within this fraction of
#: a link's length from one of its ends passes through that vertex.
NODE_ON_VERTEX = 0.05
#: ... and a node within this fraction of the link's length of another
#: vertex of the cycle is that vertex's place (the same point on two
#: squares of different sizes), not a node of its own: far below any
#: distance between two vertices of one cycle (a vertex 1e-31 beside an
#: event made a pair of vertices closer than 1e-9 of the box).
NODE_ON_OTHER = 1e-9

#: Largest half-side of a star cube, as a fraction of the domain.  A star
#: holds the leaves near its point that failed the simplicity test (along a
#: sharp cusp: 14 fine cells for an E8 at 256); on surfaces with long thin
#: regions those join up far beyond the point, and a cube that large may be
#: no cone over its boundary (caught by STAR_RETRIES).
STAR_REACH = 1 / 8

#: Inset (fine cells) of a leaf's box when it is given as a region to split
#: (a leaf holding a lens with a cycle of two events): the region then
#: meets that leaf and its children, not the neighbours sharing its faces.
LENS_INSET = 0.25

#: Times a star with fewer link cycles than its point's branches is halved
#: and meshed again (its cube was larger than the cone it must hold).
STAR_RETRIES = 2

#: Isolated singular points closer than this many fine cells (max norm)
#: make the fine lattice finer: star cubes reach a cell beyond their
#: point, rounded outwards, so points two or three cells apart get
#: overlapping cubes and lose their stars (Labs' septic in [-6, 6]^3 at
#: fine = 256: pairs 2.3 cells apart, 6 of 92 nodes not vertices).
STAR_MIN_GAP = 3.0

#: ... at most this many levels finer (16 times): nodes 0.002 apart in
#: [-1, 1]^3 are meshed at 4096; at 16384 the lattice is finer than the
#: classifier and the stars were made for (open edges seen), so closer
#: points keep the lattice and are reported.
STAR_MAX_RAISE = 4

#: Two creases (or two stretches of one) closer than this many fine cells
#: (max norm) share one tube (radius CURVE_TUBE_RADIUS + CURVE_TUBE_GROW
#: = 5.5 cells around each): the piece of surface between them then has
#: no rail and is lost (a cube with a cylindrical hole near its edges:
#: open edges at 6.4, 7.4, 8.4 and 9.4 cells, none at 10.2, 11.0, 12.8).
#: The fine level is doubled until they are this far apart ...
CREASE_MIN_GAP = 12.0

#: Singular curves closer than CREASE_MIN_GAP cells share a tube too (the
#: hyperbola's two branches 10.3 cells apart, fuzz s2-126: the sheets
#: between them lost where the tubes merge); the fine level is doubled
#: for them CURVE_GAP_MAX_RAISE times at most, and only where that parts
#: them (a gap of at least CURVE_GAP_LEAST cells): branches meeting
#: tangentially come arbitrarily close (s1-270's loop at a cone's apex,
#: 0.0008 cells), and the lattice would only grow.  One level is enough
#: well below CREASE_MIN_GAP / 2 (the least it was): stretches of a double
#: curve 2.4 to 5.9 cells apart share a tube at fine 64 and are meshed
#: right at 128 (fuzz s3-2, s3-950, s3-534, s4-542, s4-530: edges of three
#: triangles and open edges between them); at 1.1 to 1.4 cells (s3-474,
#: s4-530 turned) they are not, and two traces 4.5 cells apart (s4-410,
#: clean at 64 by luck) are 9 apart at 128 and still share a tube there
#: (edges of six): one level does not part everything (at 256 s4-410 is
#: clean, s4-530 is not).  Two levels
#: where one leaves them under 10 cells (gaps of 2.5 to 5 cells at fine 64)
#: were tried (open12, 318f1c3): s3-350, s4-410, s6-570, s6-710 and a plane
#: through a two-sheeted hyperboloid's axis came out clean, but s3-950 (3.2
#: cells: an edge of six triangles at 256) and the Seepferdchen's cuspidal
#: edge (open edges) broke: not kept (test_branches_a_few_cells_apart_get_tubes_of_their_own).
CURVE_GAP_MAX_RAISE = 1
CURVE_GAP_LEAST = 2.0

#: ... at most this many levels (8 times finer); closer creases keep the
#: lattice and the gap is reported in Mesh.stats.
CREASE_MAX_RAISE = 3

#: A mesh whose crease strips failed (a face between creases a few cells
#: across, all tube) is made again at twice the fine level this many times
#: at most: once was enough for every such face seen (a truncated cube's
#: corners at fine 64 and 128, an octahedron at 32), and where input is
#: degenerate (two boxes touching along a face, F = 0 on a patch inside
#: the solid) each try costs four times the last for nothing.
CREASE_RETRIES = 1

#: An empty mesh of a surface with singular curves, where F has both signs
#: at the leaves' corners above SIGN_RESOLVED of its largest value there,
#: is meshed again with the fine level doubled, at most this many times
#: (a lens 0.04 wide round a cuspidal edge, fuzz s3-925: fine 64 -> 512).
THIN_RETRIES = 3
#: ... (a sign seen only below this fraction is rounding: x^2 - 1e-20).
SIGN_RESOLVED = 1e-10

#: Points of the creases count as apart (for CREASE_MIN_GAP) when the way
#: between them along the creases is longer than this times their
#: distance: two creases meeting at a corner at more than ~40 degrees are
#: not close there.
CREASE_GAP_DETOUR = 3.0

#: ... and along a way that passes no corner (no vertex where the creases
#: turn by more than CREASE_LOOP_TURN degrees, or meet), more than this
#: times their distance: the two sides of a small closed crease (pi/2
#: across a circle) are apart, the points along a gently bent crease
#: (about 1) are not.
CREASE_LOOP_DETOUR = 1.4
CREASE_LOOP_TURN = 30.0

#: Largest polygon triangulated by exhaustive search over all its
#: triangulations (Catalan(n-2) of them); larger ones get a centre vertex.
MAX_TEMPLATE_POLYGON = 8

# ---------------------------------------------------------------------------
# Classification of singular points (singmesh.skeleton.classify).
#
# All four are relative to S, the largest |Taylor coefficient| of degree >= 2
# of F at the point, in the user's length unit: a coefficient c of any degree
# is "zero" when |c| <= tol * S.  Comparing coefficients of different degrees
# needs a length scale; the user's unit is the one the mesher works in (boxes
# of size ~1), so a feature that only shows below ~1e-7 of it is invisible to
# the mesh anyway.  The point is assumed known to ~1e-12: that perturbs the
# Taylor coefficients by ~ d^3 * S * 1e-12 (d the degree), and the splitting
# lemma amplifies this by at most a few orders of magnitude for well-scaled
# input, so 1e-7 leaves a margin of >= 1e3 over the noise while staying far
# below any coefficient a user writes down on purpose.
# ---------------------------------------------------------------------------

#: A point is singular when |F| and |grad F| there are at most this times S
#: (plus the rounding error of evaluating them).  A point off a true singular
#: point by delta has |grad F| ~ 6 S delta, so this accepts delta up to ~1e-9.
CLASSIFY_SINGULAR_RTOL = 1e-8

#: A Hessian eigenvalue with |lambda| <= this times S counts as zero (sets
#: the corank).  Noise in the Hessian is ~ |D^3 F| * 1e-12 + rounding.
CLASSIFY_RANK_RTOL = 1e-7

#: A coefficient of the residual function after the splitting lemma (and of
#: its cubic form, discriminant and later series) is zero when at most this
#: times S.  Kept equal to the rank tolerance so that an eigenvalue deemed
#: zero (|lambda| / 2 as a t^2 coefficient) is also a zero coefficient.
CLASSIFY_JET_RTOL = 1e-7

#: Truncation orders of the power series tried in turn: A_k is found for
#: k <= order - 1 and D_k for k <= order + 1; when the residual vanishes to
#: the last order the point is reported as non-simple (most likely on a
#: curve of singular points).  Small orders first because they are cheap.
CLASSIFY_ORDERS = (8, 14, 20)

# ---------------------------------------------------------------- singular points
#: A box may hold a singular point while F, Fx, Fy and Fz each have Bernstein
#: coefficients of both signs, counting as zero those below this fraction of
#: the largest (exact zeros at corners come out of the conversion as 1e-17).
CANDIDATE_SLACK = 1e-12

#: ... and those below this fraction of the largest coefficient on the whole
#: domain: de Casteljau splits from the domain down leave rounding dust of
#: that size (64 ulps), which deep boxes can no longer tell from their own
#: small coefficients.
CANDIDATE_DUST = 64 * 2.0 ** -52

#: Newton results with a relative residual max(|F|, |grad F|) / size of F's
#: terms below this are kept for classification and centring (degenerate
#: points are only fixed to about eps**(1/k) in double precision).
SINGULAR_LOOSE = 1e-6

#: Starts that Gauss-Newton took away from their box are tried again with
#: Jacobian singular values below this fraction of the largest cut: the
#: directions along which F is very flat (y^7) are left alone.
SINGULAR_FLAT_RCOND = 1e-6

#: A Gauss-Newton start whose step is below this times each of its
#: coordinates (a few ulps) has converged: further steps only change the
#: last bits, so it stops and the slow starts go on alone.
NEWTON_STILL = 4 * 2.0 ** -52

#: A Gauss-Newton coordinate below this fraction of the point's largest is
#: a root at 0 seen through rounding (far below the point's ulp): it is set
#: to 0, where the steps take it (by eps per step, then underflow) anyway.
NEWTON_ZERO = 1e-30

#: A singular point is accepted with a relative residual below this (or
#: below what the input's rounding allows, whichever is larger).
SINGULAR_RESIDUAL = 1e-12

#: The candidate boxes a search ends with are kept (tensors and all), for
#: a deeper search of the same surface to go on from, up to this size: the
#: curve search's level-6 boxes of a surface with hundreds of nodes are
#: tens of MB, and the point search at level 8 then skips six levels.
CANDIDATE_KEEP_BYTES = 64 * 2**20

#: Candidate boxes of the singular-point search are split at most this
#: many at a time (memory: four Bernstein tensors each, 8 children; a
#: few MB of children at a time stay in cache, ten times that do not).
CANDIDATE_CHUNK = 256

#: Boxes of the subdivision are split this many at a time, and their empty
#: children dropped at once (a whole level's children can be gigabytes).
SPLIT_CHUNK = 256

#: Candidate boxes of the singular-point search in a connected clump this
#: many boxes long may lie on a curve of singular points; CURVE_SAMPLES
#: boxes spread along it decide (see singular._curve_chains).
CURVE_SPAN = 8
CURVE_SAMPLES = 9

#: A clump of candidate boxes CURVE_SPAN or more across in two directions
#: that fills at least this part of the rectangle of its two largest
#: extents may be a sheet of singular points (F touching 0 along a
#: surface); a curve's clump, a few boxes thick, fills about thickness /
#: extent of it, under this once CURVE_SPAN long (see singular._sheets).
SHEET_FILL = 0.25

#: A sample of such a clump is on the curve when Newton (across the clump,
#: which converges only linearly on a curve of cusps) gets the relative
#: residual below this next to its box.  An isolated A5 four boxes away
#: is at ~1e-7.
CURVE_RESIDUAL = 1e-8
#: A vertex of a traced curve must get its relative residual below this
#: (or what the input's rounding allows): off a curve of singular points F
#: and grad F can both be as small as CURVE_RESIDUAL along a valley (near
#: the swallowtail point, where they vanish to high order), which a trace
#: would follow off the curve (there 3.6 x^5 / 291 at x from it on the
#: swallowtail of the sweep: above this from 3 cells out; 1e-9 let the
#: traces in 5 cells and join wrongly).  Newton across the curve (held in
#: the normal plane, multiplicity steps tried) gets below it on the curve;
#: on a cuspidal edge of rounded input (linear convergence) it may take a
#: second round of CURVE_NEWTON steps.
CURVE_VERTEX_RESIDUAL = 1e-10

#: More candidate boxes than this for skeleton nodes (F and two partial
#: derivatives zero) are a curve of them (a surface of revolution), not points.
SKELETON_NODE_MAX = 4096

#: Singular points closer than this (relative to the box) are one point.
SINGULAR_MERGE = 1e-7

#: Depth of the singular-point candidate search (boxes per axis 2**level),
#: at most the fine level.
SINGULAR_LEVEL = 8

#: Singular points closer than this many search boxes (at the search's
#: level) are crowded: Newton from a box between two may end at either,
#: and a third point there is lost (Labs' septic: 5 of its 99 nodes at
#: level 8, 1.2 to 2.3 boxes from their neighbours).  The search goes a
#: level deeper within this distance of them, at most SINGULAR_CROWD_LEVELS
#: times.  Nodes of Barth's sextic and decic, Endrass' octic and Chmutov's
#: surfaces are 10 boxes apart or more: no deeper search there.
SINGULAR_CROWD = 3.0
SINGULAR_CROWD_LEVELS = 2

#: A sheet of singular points of a polynomial is a near-double component
#: (F = G^2 - e, refused) where F's Hessian has rank one: its second
#: singular value under this fraction of the first.  There it is ~sqrt(e)
#: |Hess G| / |grad G|^2 against 2: under 1e-4 over the band of e the sheet
#: test sees (e up to CURVE_RESIDUAL); where two sheets cross (two curves
#: of singular points side by side, a clump as wide as a sheet) the two
#: are comparable.
NEAR_DOUBLE_RANK = 1e-3

#: Non-simple points closer than this many boxes of the point search are
#: one point.  Such a point is fixed only to where F and grad F are below
#: rounding, which a line of the surface through it with |grad F| ~ t^5
#: along it stretches to ~5e-3 (fuzz s6-688: -x^5 y / 2 + ... has the
#: x-axis; centring ended at x = +-5e-6, four "points" 1e-5 apart, each
#: with a star, and the stars clashed).  Distinct ones a box apart would
#: share a star cube anyway.
NON_SIMPLE_MERGE = 1.0

#: Gauss-Newton steps on a tip system's equations (skeleton/tips.py): they
#: are smooth at the tip, so a start in its candidate box converges in a
#: few; the rest are cheap at these few starts.
TIP_NEWTON_STEPS = 30
#: A tip's equations vanish to this much of (their Jacobian's size x the box).
TIP_RESIDUAL = 1e-12
#: A tip's kink is seen from TIP_PROBE of the box away (and twice that):
#: F - F0 at least this much of the box above rounding, well inside the
#: region where the root's own term dominates.
TIP_PROBE = 1e-3
#: ... where it grows by less than this factor from t to 2t (2 for a
#: square root, 2^(2/3) for a cube root of squares; 4 for a smooth F).
TIP_ORDER = 3.0

#: Depth of the search for skeleton nodes (F and two derivatives zero).
SKELETON_NODE_LEVEL = 6



# ---------------------------------------------------------------- centring
#: Most steps towards the centre of one degenerate point.  A step for the
#: true type lands on the centre; seen from afar a point looks like a
#: smaller type, whose step only covers a fixed fraction (1/2 to 1/4) of
#: the way: from the 5e-4 of a rotated A5 down to rounding takes ~40.
CENTRE_STEPS = 80

#: Hessian eigenvalues below this (relative to the Taylor coefficients)
#: count as zero when reading the type that sets a centring step: off the
#: centre the kernel eigenvalues are about the offset times the third
#: derivatives (up to ~1e-3 for the 5e-4 of an A5).  A node whose small
#: eigenvalue passes is tried and left where it is: the step leaves the
#: singular set.
CENTRE_RANK_RTOL = 1e-2

#: Taylor coefficients below this (relative) count as zero when reading
#: the type that sets a centring step.  Near an E7 the unfolding has D5
#: points; read strictly, a point 3e-7 from the E7 is a D5 whose step is
#: zero, while read at 1e-4 it is the E7 whose step reaches the centre.
CENTRE_JET_RTOL = 1e-4

#: Newton iterations on the truncated series within one centring step.
CENTRE_NEWTON = 8

#: Centring stops when a step moves the point less than this (relative).
CENTRE_STOP = 4e-16

#: A corank-2 non-simple point whose centring conditions have a Jacobian
#: of smallest singular value below this fraction of the largest leaves a
#: direction free (y in x^2 + y^6 + z^4), fixed then by g's order along it.
CENTRE_FLAT = 1e-6

#: ... the order k + 1 along it: the first derivative d^(k+1) g / de^(k+1)
#: above this fraction of the jet's scale times (k + 1)! (a coefficient of
#: t^(k+1) of 1e-3 the largest of g's).
CENTRE_FLAT_SLOPE = 1e-3

# ---------------------------------------------------------------- singular curves
#: Gauss-Newton iterations that put a vertex on a curve of singular points
#: (across a cuspidal edge convergence is linear: ~2/3 per step).
CURVE_NEWTON = 40

#: The trace steps this many mesh cells; each step is then divided into
#: as many vertices by Newton on all of them at once.
CURVE_TRACE_STEP = 4

#: The fractions of a trace step tried in turn where the full step loses
#: the curve.  Down to a sixteenth (a quarter of a mesh cell): a curve
#: turning within a cell of the mesh (the bottom of a U, y (1 - 8 z^2) = 1
#: in a box 4 across at fine 64: fuzz s1-278) is followed round, not lost
#: with its other arm never traced.
CURVE_TRACE_SCALES = (1.0, 0.5, 0.25, 0.125, 0.0625)
#: ... the steps shorter than a quarter only where two sheets cross
#: transversally: the Hessian's second singular value at least this
#: fraction of its first (0.9 on that U; 0.05-0.1 where two branches of
#: fuzz s1-638's double curve pass within a step, which the shorter steps
#: followed past each other instead of meeting).
CURVE_TURN_RANK = 0.2
#: A trace step is taken only where the curve it lands on runs within
#: 60 degrees of the step (|cos| at least this), where that can be read
#: (two sheets crossing): a step that lands on another curve passing
#: near the predicted point runs across it (fuzz s1-270, the double curve
#: through a cone's apex).  A turn of 60 degrees within one step is taken
#: with a shorter one.
CURVE_TRACE_ALONG = 0.5
#: Where the step along the last chord loses the curve, a step along the
#: Hessian's kernel (the curve's tangent) is tried where that kernel is
#: one direction: the second singular value at least this fraction of the
#: first (two sheets crossing at 5 degrees give 0.002, fuzz s3-474's
#: loop tip; along a cuspidal edge it is at rounding level).
CURVE_KERNEL_RANK = 1e-3
#: ... with steps down to a 64th (a 16th of a cell): the tip of such a
#: loop can be a cell across or less (fuzz s3-2: followed at 1/64 only).
CURVE_KERNEL_SCALES = CURVE_TRACE_SCALES + (0.03125, 0.015625)
#: A trace sets out along the samples' principal direction unless that is
#: more than ~25 degrees off the curve's tangent (|cos| below this), as at
#: the tip of such a loop, where the samples lie on both arms.
CURVE_START_ALONG = 0.9
#: A trace step stands only where Newton from its chord's midpoint lands
#: within this fraction of the chord (an arc turning up to ~45 degrees
#: within the step; one turning more is taken in shorter steps): a step
#: of 4 cells from one arm of a loop to the other 2 cells away lands a
#: quarter of the chord off.
CURVE_STEP_SAGITTA = 0.1

#: A trace closes back at its start only after this many steps' length
#: (four full steps, as before the shorter steps of CURVE_TRACE_SCALES,
#: are 4 or more).
CURVE_CLOSE_STEPS = 3.0

#: A trace shorter than this many steps is not a curve (an isolated point).
CURVE_MIN_STEPS = 2

#: Golden-section / bisection steps placing crossings and changes of type.
CURVE_CROSSING_STEPS = 40

#: Transversal type: samples on, and radius (in mesh cells) of, the circle
#: in the normal plane on which the arcs of F = 0 are counted.
CURVE_CIRCLE_SAMPLES = 720
CURVE_CIRCLE_RADIUS = 3.0

#: An eigenvalue of the Hessian in the normal plane is zero when below
#: this times the largest (relative to the polynomial's coefficients for
#: the largest).
CURVE_RANK_RTOL = 1e-6
#: ... and a small eigenvalue below this times the largest reads rank two
#: only if the circle agrees (no arc for an isolated line, four for two
#: sheets): on a cuspidal edge of rounded input a vertex a little off the
#: curve has a small eigenvalue of up to ~2e-5 of the largest, and the
#: circle sees the cusp's two arcs.
CURVE_RANK_MARGIN = 1e-4

#: The tube of fine leaves meshed along a curve: leaves within this many
#: cells of it, and the non-simple leaves next to them up to CURVE_TUBE_GROW
#: cells away.
CURVE_TUBE_RADIUS = 1.5
CURVE_TUBE_GROW = 4.0

#: A group of leaves outside the tube that it encloses (no link to the box's
#: boundary) at most this many fine cells across is a hole of the tube and
#: joins it (its own polygon and the strip over it would cover it twice).
TUBE_HOLE_CELLS = 3

#: Changes of type along a curve are placed to this fraction of a cell.
CURVE_PLACE = 1e-12

#: Singular values of the Jacobian of (F, grad F) below this times its
#: largest count as zero in Newton onto a curve of singular points (no
#: absolute floor: across a curve of type beyond A_k they are genuinely
#: small; the one along the curve is left out by the step's plane).
CURVE_SVD_RTOL = 1e-12

#: ... in the plane normal to the curve (the direction along it left out
#: by the plane): across an edge of type A_k the small singular value
#: falls as the distance to the curve to the power k - 1, and a cut at
#: CURVE_SVD_RTOL stopped Newton 5e-7 off an A3 isolated line (x^2 + y^4,
#: fuzz s1-73).  Here the cut is far below: an A3 line is reached to 1e-10,
#: a step that noise blows up is not kept (the iterate with the least
#: residual is the answer).  Not zero: without any cut, steps divided by
#: rounding-sized singular values left the vertices of a corank-2 curve
#: (y z^3 + x y^4 along the x-axis, fuzz s1-745) 1e-6 off it.
CURVE_SVD_PLANE_RTOL = 1e-20

#: A point Newton left with a residual above rounding level is on the
#: curve only if a Newton step there would remove at least this fraction
#: of it (about 1 near the curve, whatever its type; 0 at a minimum of
#: |F| + |grad F| beside it, in a valley by a degenerate point of the
#: locus, where the residual stays ~1e-11 a hundredth of the box away).
CURVE_EXPLAINED = 0.5

#: Newton onto a curve stops when no step is longer than this fraction of
#: the distance it may move (the points are then at rounding level).
CURVE_STOP = 1e-13

#: Rounds of Newton onto a curve and a slide onto the box's face that
#: place a curve's end on the box (each shrinks the slide by about the
#: curvature times the step; they stop once the slide is below CURVE_STOP
#: of the step).
CURVE_CLIP_ROUNDS = 30

#: Halvings of the chord that bracket a curve's exit from the box when the
#: rounds above leave the end off the curve (skeleton.singular_curves.
#: _bisect_exit): 2^-50 of a step is rounding level for the end.
CURVE_CLIP_BISECT = 50

#: A point the classifier reads as a simple type of at least this Milnor
#: number is checked for a curve through it (skeleton.singular._continues):
#: along a short arc of a double curve that turns within a few boxes, F is
#: flat to rounding and reads A12 to A15 (the rotated parabola of
#: test_fuzz's SHORT_ARCS).  The largest simple type meshed as a point in
#: the tests and the judge is A5.
CURVE_CHECK_MILNOR = 6
#: ... by tracing the locus from it both ways (half-box steps, at most
#: CURVE_CHECK_STEPS): a curve when both ways leave the cube of
#: CURVE_CHECK_REACH boxes around it or take all the steps (a curve winding
#: inside it), or one way comes back to it.
CURVE_CHECK_REACH = 10.0
CURVE_CHECK_STEPS = 80

#: A curve's end on the box within this many trace steps of a second face
#: is tried on the box edge between the two (skeleton.singular_curves.
#: _onto_box_edge): a cuspidal edge through a box edge is located across
#: itself to ~1e-8 only, far below this; a curve passing beside the edge
#: is told apart by the residual, not by this distance.
CURVE_EDGE_SNAP = 1e-4
#: Gauss-Newton steps along the box edge (quadratic convergence from
#: 1e-4 steps away: a few suffice; rounding level stops them earlier).
CURVE_EDGE_NEWTON = 8

#: Other changes of type (read from the arcs on a circle, which blur
#: within its radius) are placed to this fraction of a cell.
CURVE_TYPE_PLACE = 1e-3

#: A point where the sheets through an A1 curve touch (the normal
#: Hessian's eigenvalue ratio r has a double zero, no change of sign): a
#: vertex where |r| is least, and the parabola through it and its two
#: neighbours falls to this fraction of theirs or below.  At a double zero
#: the parabola reaches 0 up to the cubic terms (a few 1e-3 of the
#: neighbours' at a cell's spacing); a generic minimum of |r| over a step
#: stays within a few per cent of its neighbours'.
CURVE_TANGENCY_RTOL = 0.02

#: The point search leaves alone candidate boxes this many cells from a
#: traced curve (its pinch and triple points are the curve's).
CURVE_AVOID = 3.0

#: A Newton end this many fine cells from a traced curve's samples (a
#: quarter cell apart: a point of the curve is within an eighth) is a
#: point of that curve; one further off is an isolated point beside it.
CURVE_ON = 0.25
#: Newton steps from the boxes round a traced curve: a few take most of
#: them onto it (those are dropped), then enough for the rest to reach a
#: point beside it (a node in 5, an A2 to the loose residual in 10).
CURVE_NEAR_STEPS = (4, 12)

#: Traces that lose the curve within this many trace steps of each other
#: are joined at one point of the singular locus between their ends.
CURVE_JOIN = 3.0

#: Two paths of the curve graph between the same two crossings, each
#: within this many steps of the other, are one curve at the mesh's
#: resolution (curves tangent where they meet): the longer goes.  One
#: step, as for the vertices merged into a crossing (the Tuelle surface's
#: parabola runs 0.8 steps beside its line there); paths of up to
#: ``CURVE_DOUBLE_PATH_EDGES`` edges in all, a few steps each way.
CURVE_DOUBLE_PATH = 1.0
CURVE_DOUBLE_PATH_EDGES = 24

#: A curve vertex closer than this (in steps) to a special point placed
#: beside it is merged into the special point.
CURVE_MERGE = 0.3

#: Lattice specks (facets.bubbles): closed pieces of at most BUBBLE_FACES
#: triangles and BUBBLE_THICKNESS cells across, with no critical point of
#: F in them (an extremum: Newton on grad F = 0, BUBBLE_NEWTON steps from the centre, to
#: |grad F| <= BUBBLE_CRITICAL of its scale there), are two sheets closer
#: than a cell seen at one lattice point, not pieces of the surface.
BUBBLE_FACES = 200
BUBBLE_THICKNESS = 2.0
BUBBLE_NEWTON = 12
BUBBLE_CRITICAL = 1e-6

#: Around pinch and triple points the non-simple leaves join the tube up
#: to this many cells away at a fine lattice of CURVE_BALL_FINE cells per
#: box or coarser.  The sheets meet tangentially there and part only as
#: the square of the distance, so the reach in cells where they are a
#: cell apart grows as the square root of the cells per box: at 256 it is
#: twice this (a rotated cross-cap's sheets were a cell apart 13.5 cells
#: from a pinch point, two cylinders' 14 cells from where their double
#: curves cross; a non-simple leaf left outside paired one sheet's events
#: with the other's: a closed bubble of 8 triangles, an edge of 4).
#: Growing further at 64 (where every leaf of the Roman surface is
#: non-simple) took the whole box into the tube.
CURVE_BALL_GROW = 10.0
CURVE_BALL_FINE = 64

#: Around a point where two cuspidal edges cross (Crixxi's (0, +-1, 0))
#: every leaf within this many cells is tube: the two half-sheets between
#: the edges form a lens whose thickness falls as the cube of the
#: distance, closer than the octree can part (Crixxi at 256 cells: 1.6
#: cells apart at 0.27, 2 at 24 cells).
CURVE_MEET_BALL = 24.0

#: A rail's step back along the curve followed within this many rail
#: steps (events, about a cell apart) by a step forward past where it
#: turned is a zigzag, not a turn (facets.tubes._no_zigzags).  The
#: excursions round the non-simple leaves joined to the balls reach about
#: ``ball_grow`` cells (20 at 256 cells per box); a rail that turns round
#: the end of a curve comes back along all of it.  (Rotated Roman surface:
#: 12 rail steps left an edge of 8 triangles, 24 none.)  Also the longest
#: run of a rail's snaps onto another piece of the curve graph that is
#: taken for an excursion (facets.tubes._one_piece: 1 to 3 events in fuzz
#: s1-614 and s1-302), not for a rail that goes on along the other piece.
CURVE_ZIGZAG_STEPS = 24

#: The square-free part is computed (sympy, exact) for polynomials with at
#: most this many terms; beyond, sympy's factoring takes seconds.
SQUAREFREE_MAX_TERMS = 400

#: A pinch point is bracketed on the chord between two curve vertices down
#: to this fraction of a cell, then on the curve itself.
CURVE_CHORD_PLACE = 1e-3

#: Radius (cells) of the tube along a curve whose sheets are tangent (a
#: tacnode edge): they part as the square of the distance, and must be
#: more than a cell apart where they leave the tube.
CURVE_TANGENT_RADIUS = 10.0

#: The tube's links on the box's faces continue its rails (a half-sheet
#: that leaves the tube through the box), except where a curve meets the
#: box: its half-sheets' traces on the face meet there, and their rails
#: end on the box, joined to the curve's end.  "There" is the tube's reach
#: (radius and growth) and this many cells more.
CURVE_FACE_RAIL = CURVE_TUBE_RADIUS + 1.0
#: A run of the tube's face links from within this many cells of one
#: curve end on the box to within it of another is the trace of a
#: half-sheet between the curve and the face, its rail (fuzz s1-374: an
#: arc 8.6 cells deep from a face back to it; the end's own square, where
#: the two sheets' traces cross, holds no link: its events are within a
#: cell and a half).
CURVE_FACE_GAP = 2.0

#: Across a curve whose branches are tangent (A_k, k >= 3) the tube
#: reaches where they are this many cells apart (the tacnode's
#: CURVE_TANGENT_RADIUS is that for x^2 = y^4 at the default cell): one
#: and a half cells, so that no boundary square holds both.  The distances
#: tried (cells), the Newton steps onto the polar curve at each, and the
#: widest tube (cells).
CURVE_BRANCH_GAP = 1.5
#: Two sheets crossing at a small angle (A1) get the wide tube where,
#: as a whole piece, they are closer than CURVE_BRANCH_GAP cells out to
#: more than this many cells: the usual tube's reach (CURVE_TUBE_RADIUS +
#: CURVE_TUBE_GROW).  Sheets at 10 degrees are 1.5 cells apart 8.6 cells out.
CURVE_CROSSING_RADIUS = 5.5
#: ... measured on the piece's vertices more than CURVE_BALL_GROW cells
#: from its special points (other than ends on the box), when it has at
#: least this many.
CURVE_CROSSING_MIN_VERTICES = 4
#: ... and only on a piece at least this many times that reach long (a
#: shorter one is all ends on the box).
CURVE_CROSSING_MIN_LENGTH = 4.0
#: ... and only on a piece all of whose vertices are farther than that
#: reach and this many cells from every other curve (not joined to it):
#: the wide tube reaches its
#: radius and CURVE_TUBE_GROW - CURVE_TUBE_RADIUS more into non-simple
#: leaves, the other curve's tube CURVE_TUBE_RADIUS + CURVE_TUBE_GROW, and
#: where they meet both curves are in one tube and the sheet between them
#: has no rail (fuzz s4-838: a plane along a cubic's line at 3.6 degrees,
#: wide 10 cells, the other branch of their curve 12 cells away; triangles
#: from a rail on the box's face 13 cells out to both curves).
CURVE_WIDE_APART = 2 * CURVE_TUBE_GROW + 1.0
#: A piece whose wide tube has no room (its far stretches closer than two
#: such tubes: a small loop where a plane nearly tangent to a sphere cuts
#: it) raises the fine level by up to this many levels: a loop 12 cells
#: across at 8 degrees needs two.
CURVE_CRAMPED_MAX_RAISE = 2

#: A rail with both ends on one face of the box at most this many cells
#: apart is a stub of a half-sheet's trace that ran along the face
#: (facets.tubes._join_stubs); it is joined to the nearest rail end there,
#: at most as far.
CURVE_RAIL_STUB = 3.0
CURVE_BRANCH_RADII = (2, 3, 4, 5, 6, 8, 10, 12, 14, 16, 20, 24)
CURVE_POLAR_NEWTON = 4
CURVE_TANGENT_MAX = 24.0

#: Candidate boxes of the curve search (at its level) in a clump spanning
#: fewer boxes than this hold isolated points, not a curve.
CURVE_MIN_CLUMP = 4

# ---------------------------------------------------------------- non-polynomial F
# (singmesh.elementary: interval bounds and Taylor jets instead of Bernstein forms)

#: Interval bounds (boxes/intervals.py) are widened by this many relative
#: ulps after numpy's transcendental functions and powers, which are not
#: correctly rounded (glibc's and numpy's SIMD versions are within 4 ulps);
#: after + - * / and sqrt (correctly rounded) one ulp (nextafter) suffices.
INTERVAL_FUNCTION_ULPS = 8.0

#: Order of the Taylor jets of a non-polynomial F (its ``degree``): what
#: classification reads at a singular point (A_k up to k = 7, as the first
#: of CLASSIFY_ORDERS does for polynomials).
TAYLOR_ORDER = 8

#: Lattice-line roots of a non-polynomial F: pieces of a segment on which
#: F' may vanish are halved down to this fraction of the segment (far
#: below ROOT_CLUSTER, so two roots left in one piece are one cluster
#: anyway); a root is then kept where |F| is at rounding level.
ELEMENTARY_ROOT_PIECE = 1e-9

#: A removable singularity of a non-polynomial F (sin(x) / x at x = 0:
#: ElementarySurface.removable_singularity) is read at points of the
#: divisor's zeros found by this many Newton steps from a grid, with F
#: evaluated this fraction of the box to either side: values within
#: REMOVABLE_JUMP of F's scale of each other there are a limit (a pole's
#: are ~1 / REMOVABLE_STEP apart).
REMOVABLE_NEWTON_STEPS = 30
REMOVABLE_STEP = 1e-6
REMOVABLE_JUMP = 1e-3

#: An open edge of a non-polynomial mesh inside the box is next to where
#: the surface runs into a pole or out of F's domain (said in a note) when
#: F is undefined or unbounded within this many fine cells of its middle:
#: the mesh stops up to a cell short of such places, and the bounds of a
#: cube of 2 cells round it see them.
DOMAIN_EDGE_REACH = 2.0

#: An open edge next to an end of F's domain gets a strip up to it
#: (facets.domain_edges) when both its ends reach that end by Newton
#: within this many fine cells (the mesh stops up to a cell short of it).
DOMAIN_STRIP_REACH = 2.0

#: Points put on an end of F's domain where its argument is a rounding
#: error outside are moved back towards their vertex by 1e-15, 4e-15, ...
#: of their size, at most this many times, until F is defined there.
DOMAIN_STRIP_NUDGES = 12

#: A point put on an end of F's domain this close (of the box) to a vertex
#: is that vertex: the lattice's own vertices on it, snapped there, and
#: no two vertices closer than the mesh promises (1e-9 of the box).
DOMAIN_STRIP_SAME = 1e-10

#: Consecutive points of a strip on an end of F's domain closer than this
#: many fine cells are one (the ends of a lattice edge across that end
#: land next to each other: a sliver between them).
DOMAIN_STRIP_MERGE = 0.25

#: A vertex is on an end of F's domain (the mesh's note) when it is this
#: close (of the box, to first order) to both surfaces whose meeting is it:
#: the strips' vertices are there to rounding, the lattice's a cell away.
DOMAIN_STRIP_ON = 1e-9

#: line_roots of a non-polynomial F gives up a piece with F undefined at
#: an end (0 / 0) and unbounded on it once it is narrower than this part
#: of its segment: a root closer than that to where F is 0 / 0 is lost (the
#: mesh stops a cell short of such points anyway), and the 30 halvings to
#: ELEMENTARY_ROOT_PIECE on every lattice line crossing them are not made.
ELEMENTARY_UNDEFINED_PIECE = 2.0 ** -8

#: A root polished by Newton is kept when |F| there is below this times
#: the size of F's terms (a sign change across a pole, 1/x at 0, has
#: |F| about its size and is no root).  A true root has |F| at rounding
#: level (~1e-16 of it).
ELEMENTARY_ROOT_RESIDUAL = 1e-8

#: Safeguarded Newton (bisection when a step leaves the bracket) on
#: sign-change brackets of lattice lines: at most this many steps.
ELEMENTARY_ROOT_STEPS = 100

#: may_vanish of a non-polynomial F tries every combination of the pieces
#: of the kinks (Abs, Min, Max) straddling a box, up to this many; a box
#: with more passes untested (never dropped).
KINK_COMBINATIONS = 64

#: Creases (kinks of F on its zero set, skeleton/creases.py).  Depth of
#: the search for boxes where both functions of a kink may vanish (as the
#: singular curves' samples: level 6 boxes are a few fine cells wide).
CREASE_LEVEL = 6

#: A point is on a crease when |G1| and |G2| are below this times the
#: size of their gradients times the point's scale (Newton reaches
#: ~1e-16; a start in a valley that stalls is far above).
CREASE_RESIDUAL = 1e-11

#: F's gradient jumps across an active kink: the two pieces' gradients
#: differ by more than this fraction of their size (where an enclosing
#: Max picks another argument, both pieces give the same gradient).
CREASE_JUMP = 1e-6

#: A kink is active where grad F differs this far (relative to the point's
#: scale) to either side of its tie: far above rounding (ties of an
#: enclosing Min at 1e-17 pick a piece at random), far below any feature.
CREASE_SIDE_STEP = 1e-7

#: Points on the circle of radius CREASE_SIDE_STEP round a crease on which
#: the crossings of F = 0 are found (elementary._Kink._around_differ):
#: two half-sheets at an angle down to 360 / CREASE_AROUND degrees apart
#: are two crossings (a box's edge is 90).
CREASE_AROUND = 12

#: A tie of a Max/Min is on top when no third argument exceeds it by more
#: than this times the arguments' size (a corner where three tie is
#: still active, to rounding).
CREASE_TIE = 1e-12

#: Creases are traced with this many fine cells per step, then each step
#: is divided by Newton (as CURVE_TRACE_STEP for singular curves).
CREASE_TRACE_STEP = 4

#: A crease trace takes up to this many steps at once (predicted along
#: its tangent, Newton on all in one call, then checked in order as single
#: steps): from CREASE_AHEAD_MIN after a single step, doubling while all
#: are kept.  Each call of F's graph costs as much for one point as for
#: dozens; along a straight crease every step is kept, along a curved one
#: those within a step of the tangent's prediction.
CREASE_AHEAD_MIN = 4
CREASE_AHEAD_MAX = 32

#: Newton iterations onto a crease (min-norm steps on two equations, or
#: Gauss-Newton on the stacked equations at a corner).
CREASE_NEWTON = 30

#: Ends of crease traces (where a kink stops being active) closer than
#: this many trace steps are one corner, placed by Gauss-Newton on the
#: equations of all the creases meeting there.
CREASE_CORNER = 1.5

#: A crease trace that comes within this many trace steps of a point of the
#: same crease traced before stops there ("meet"): it went on through a
#: corner of its own crease (the rim of Max(|u| + |v|, |w|) turns where the
#: Abs kink's side edge meets it) and would trace a stretch twice.  Half a
#: step: a trace's own next vertex is a whole step on.
CREASE_ONTO = 0.5

#: A sample of a kink's crease this close (trace steps) to the line of an
#: earlier kink lies on it: the two kinks hold one crease (the coincident
#: edges of two boxes with coplanar faces joined by Min), traced once.  A
#: chord's sagitta on a curved crease is far below it (0.01 step at a
#: radius of 12 steps); distinct creases a step apart are far above.
CREASE_SAME = 0.05

#: A corner of creases is pinned by the kinks through it when the
#: smallest singular value of their stacked gradients is above this
#: fraction of the largest (coincident box edges alone leave a line).
CREASE_PIN_RANK = 1e-6

#: A tube's rail lies on a patch of F = 0 without sign change (two solids
#: of a Min touching along a face) where F has one sign this many fine
#: cells to either side of it: the rails are a few cells from the crease,
#: where the two half-sheets of a crease are cells apart, and a sheet's
#: own zeros are a cell or more from the next sheet.
SIGN_KEPT_STEP = 0.25

#: Two crease traces passing closer than this many trace steps, away from
#: their ends, cross: they are cut there and the crossing is a corner
#: (two equal cylinders joined by Min cross along a crease with a double
#: point).  A chord's sagitta is far below it; traces of two creases side
#: by side are a step or more apart.
CREASE_CROSS = 0.25

#: A double point of a crease (grad G1 x grad G2 = 0 there) is looked for
#: only from points where |grad G1 x grad G2| is below this times
#: (|grad G1| + |grad G2|)^2: a step (4 cells at fine 256) from the double
#: point of two cylinders of radius 0.45 joined by Min it is 0.1; where
#: another kink meets this crease, 0.14 (a prism's corner) or more.
CREASE_DOUBLE_CROSS = 0.12

#: Central-difference step (relative to the point's scale) for the Jacobian
#: of grad G1 x grad G2 in the search for a crease's double point: G1 and G2
#: come with exact gradients but not their second derivatives.
CREASE_DIFF_STEP = 1e-7

#: Vertices of the crease graph joined by an edge shorter than this many
#: trace steps are one vertex: a corner placed by Gauss-Newton beside the
#: trace's own vertex at the same point (1e-14 cells apart), as
#: ``_no_repeats`` within one trace.  Far below any step or sagitta.
CREASE_WELD = 1e-6

#: Ends on the box of two creases closer than this many fine cells are
#: joined along the surface's trace on the box face (twice the tubes'
#: reach, CURVE_TUBE_RADIUS + CURVE_TUBE_GROW, and some).
CREASE_BOX_JOIN = 12.0

#: Coarsening of crease meshes (facets/coarsen.py): vertices within this
#: many coarse cells of a crease vertex can go (the fine triangles of a
#: tube and the finer leaves round it reach ~20 fine cells from the crease
#: at coarse 32, fine 256: 2.5 coarse cells); ...
COARSEN_REACH = 3.0
#: ... and the vertices whose neighbours are all within this fraction of
#: the box's size of the plane of one of their triangles (a flat face,
#: float-rotated: rounding is ~1e-16; far from the tubes, such a face can
#: be meshed on the fine lattice where bounds of F are loose), ...
COARSEN_FLAT = 1e-10
#: ... a new triangle turns at most this many degrees from the surface's
#: normal at the fine triangle it descends from (the normals at a
#: triangle's corners differ by its size over the radius of curvature: 12
#: degrees for a coarse cell's diagonal on a sphere of 7 coarse cells'
#: radius, where the coarse lattice's own triangles do), and a new chord along a
#: crease is as close to it as one of ``max_edge`` whose ends turn this
#: much (on a flat face and a straight crease nothing turns), ...
COARSEN_BEND = 12.0
#: ... and no new triangle has an angle below this many degrees (or below
#: the smallest of the triangles it replaces; 14, not the quality judge's
#: 10: a margin for triangles left beside a short chord; the cube's
#: smallest was 13.7 before), ...
COARSEN_ANGLE = 14.0
#: ... (the smallest of those it replaces times this: rounding, and slivers
#: in clusters made a hair thinner by the collapse of a neighbour), ...
COARSEN_ANGLE_SLACK = 0.99
#: ... or as a needle: its shortest edge at most this fraction of the next
#: (collapsed next: three vertices much closer than a cell go in two
#: collapses, the first of which leaves a needle), with no angle below
#: COARSEN_NEEDLE degrees, ...
COARSEN_NEEDLE_EDGE = 0.25
COARSEN_NEEDLE = 1.0
#: ... or with an edge shorter than this fraction of ``max_edge`` (of any
#: shape: crossings of the surface with the lattice clustered at a
#: lattice point, 1e-5 of a cell apart, go one by one), ...
COARSEN_TINY = 1e-3
#: ... nor an edge longer than this many coarse cells (the largest
#: triangles of the coarse lattice elsewhere: a cell's face diagonal).
COARSEN_EDGE = 1.4142135623730951
#: ... (this many times longer where a triangle thinner than COARSEN_ANGLE
#: goes, or an edge a quarter of the longest: a sliver between triangles of
#: the full size on a cube's face, the last short chord of a crease).
COARSEN_EDGE_SLIVER = 1.25
#: Flips after the collapses of a round: of the edges of triangles with an
#: angle below this many degrees (flips of better ones gain little).
COARSEN_FLIP_BELOW = 35.0
#: Rounds after the others for the triangles still thinner than
#: COARSEN_ANGLE (a needle whose collapse was not valid).
COARSEN_CLEANUP = 6
#: Passes of choosing collapses that conflict with none chosen, in a round.
COARSEN_PASSES = 6

#: Curvature (singmesh.curvature): grad F is zero at a point, and the
#: curvature undefined (NaN), when |grad F| is below this fraction of the
#: size of the terms summed for its components: ZERO_ULPS ulps, the
#: rounding error of that sum (a singular vertex's computed gradient).
CURVATURE_GRADIENT_ZERO = ZERO_ULPS * 2.0 ** -52

#: Curvature sizing (singmesh.boxes.sizing): Newton steps from a box's
#: centre and corners onto F = 0, to sample the curvature in the box
#: (started within a box of the surface, a few steps converge; a start
#: that does not is no sample).
SIZING_NEWTON = 6

#: A sample counts for its box when it lies within the box widened by this
#: fraction of its side (the surface near the box's faces bends the same).
SIZING_BOX_SLACK = 0.1

#: A Newton end point is on the surface when |F| is below this fraction of
#: the size of F's terms there (far above rounding, far below a stalled
#: start's residual).
SIZING_RESIDUAL = 1e-8

#: Defaults of mesh(size="curvature"), fractions of the box's longest side:
#: the longest edge (8 boxes per axis: the coarsest lattice on which the
#: simplicity test still settles typical surfaces quickly) and the chord
#: tolerance (a tenth of a percent: the deviation of the uniform mesh at
#: coarse = 32 on a unit sphere in a box of side 3 is of that order).
SIZING_MAX_EDGE = 1 / 8
SIZING_CHORD = 1e-3

#: The longest edge of the triangles in a leaf box, in units of its side,
#: for the curvature sizing: measured so that the maximal deviation of the
#: mesh is about the chord tolerance (the unit sphere in [-1.5, 1.5]^3 at
#: 32 boxes per axis deviates 2.79 times k side^2 / 8 from the surface: the
#: edges that count are about sqrt(2.79) = 1.67 sides long, face
#: diagonals).  A little less, so that a chord tolerance equal to a
#: uniform mesh's deviation does not ask for the next level by rounding
#: (the deviation can then exceed the tolerance by up to (1.67/1.6)^2 = 9%).
SIZING_EDGE_PER_SIDE = 1.6
# ---------------------------------------------------------------------------
# Triangle shape (singmesh.facets.improve, issue #12).
# ---------------------------------------------------------------------------

#: Rounds of (flips, relaxation) and the flip passes in each (a pass
#: flips an independent set; the next looks only at the triangles it
#: changed or left).  Three rounds bring the crossings' slivers to
#: well-shaped triangles, two leave some (Clebsch: min angle 8 away from
#: the box); more passes change little (sphere 6.4 -> 27 degrees).  The
#: rounds stop as soon as no angle is below IMPROVE_ACTIVE_ANGLE, so only
#: meshes with slivers left take more, and each only at the vertices near
#: them: Barth's sextic kept a 0.8 degree sliver 0.2 from its nodes after
#: three (22 after eight), Kummer rotated 11.9 -> 20.7, Clebsch rotated
#: 18.7 -> 22 (benchmarks/bench_angles.py); the shaping's time on Barth
#: 0.20 -> 0.26 s.
IMPROVE_ROUNDS = 8
IMPROVE_FLIP_PASSES = 2

#: Relaxation moves the vertices of triangles with an angle below this
#: (degrees) and their neighbours; the others are well placed already.
#: At 22 the 16 surfaces of the quality judge keep 19.4 degrees or more
#: away from singular points (25: 19.96, 20: 16.9 and 0.14% below 20),
#: with a quarter fewer Newton projections than at 25 (sphere 1080
#: instead of 1913 moves), and no relaxation round is left once no angle
#: is below it.
IMPROVE_ACTIVE_ANGLE = 22.0

#: ... and the vertices this many edges from those.  0: with two flip
#: passes a round the corners of the small triangles alone suffice (with
#: one pass, 0 left 5-8 degree angles in rotated D4 near its apex); 1
#: moved nearly every vertex of Barth's sextic in the first round (its
#: 10,403 triangles below 22 degrees of 31,372) for a tenth of the pass.
IMPROVE_ACTIVE_RINGS = 0

#: A vertex moves at most this fraction of its local edge length per
#: relaxation step: Newton then starts close to the surface (the tangent
#: plane is off it by ~ curvature x step^2) and cannot reach another sheet.
IMPROVE_STEP = 0.5

#: A vertex whose move was undone tries half the step in the next round,
#: down to this fraction of it (then it keeps trying that: a sixteenth of
#: half an edge still moves a vertex off a sliver's short edge over the
#: rounds left).
IMPROVE_MIN_SCALE = 1 / 16

#: Newton steps after a move (quadratic convergence from a start within
#: a fraction of an edge length of the surface: three reach rounding).
#: The last is taken only where the residual below is not met after the
#: others (sphere: none of 1080 points; tanglecube: 1043 of 4441).
IMPROVE_NEWTON = 3

#: After IMPROVE_NEWTON - 1 steps, the points whose residual is above this
#: fraction of IMPROVE_RESIDUAL take the last step (at 1 the vertices next
#: to a domain edge, where grad F is large, kept |F| of 3e-12).
IMPROVE_NEWTON_DONE = 1e-3

#: A moved vertex stays only if |F| / |grad F| there is below this
#: fraction of the box (the mesh promises 1e-10: a 100-fold margin) ...
IMPROVE_RESIDUAL = 1e-12

#: ... if Newton moved it at most this fraction of its tangent step (more
#: is not the curvature of its own sheet: a jump towards another one) ...
IMPROVE_PROJECTION = 0.5

#: ... and if its unit normal keeps a cosine above this with the old one
#: (45 degrees: a step of half an edge turns it by far less on a sheet
#: the mesh resolves; near a double curve the other sheet's is far off).
IMPROVE_NORMAL_TURN = 0.7

#: A triangle leans from the surface by the angle between its normal and
#: the mean of its vertices' unit normals: a flip or a move may not make it
#: lean more than the triangles it replaces or this (cosine, 25 degrees),
#: whichever is larger.  Keeps the mesh as close to F = 0 as it was.
IMPROVE_LEAN = 0.906

#: Vertices this many edges or fewer from a singular curve or crease stay
#: where the tubes put them, and no edge at them is flipped: sheets meeting
#: tangentially along a curve (x^2 = y^4) are closer than a Newton step
#: there, and the judge's sample cannot see them apart.
IMPROVE_CURVE_RINGS = 2

#: Vertices at most this far (fraction of the box) from a face of the box
#: lie on it (the crossings there are computed in that plane).
IMPROVE_ON_BOX = 1e-12

#: Integers and fractions with more digits than this are shown as floats
#: in reports and messages (1e300 is read exactly: 301 digits); the mesh
#: uses the exact number.
DISPLAY_DIGITS = 30

#: An empty mesh of an F of one sign on a grid: a local search from this
#: many samples looks for where F touches 0 (-|z - 0.3| between samples),
#: and a value below this fraction of the largest |F| sampled is a zero
#: (Nelder-Mead reaches rounding level at a kink or a double root).
EMPTY_TOUCH_STARTS = 4
EMPTY_TOUCH = 1e-12
#: Steps (fractions of the box) from such a zero along the axes that tell
#: a crossing from a touching: sheets 0.002 apart on a box of 4 ((x -
#: 0.013)^2 - 1e-6) have the other sign 1e-5 of the box from either; a
#: touching (-|z|, a double root) shows no other sign at any of them.
EMPTY_CROSS_STEPS = tuple(10.0 ** -k for k in range(2, 10))

#: Steps per side of a square in which the face curve is followed to pair
#: the events of an ambiguous square on the box's boundary (two sheets'
#: traces less than a cell apart, :func:`singmesh.boxes.faces.traced_pairs`):
#: a step well under the traces' distance (half a cell and more where they
#: are paired at all; closer, the curve's end on the face, where the tube's
#: rails do not read them), so that the corrector stays on its own trace.
FACE_TRACE_STEPS = 16
#: Steps (accepted or halved) after which a trace that has not left its
#: square is given up (the square keeps its pairing along the boundary).
FACE_TRACE_MAX = 256
#: A step is halved when its corrector moves the point more than this
#: fraction of the step off the predicted one, or the curve's direction
#: turns by more than 60 degrees (cosine 0.5) over it: another trace may be near.
FACE_TRACE_DRIFT = 0.5

#: Gauss-Newton steps towards a point of the singular locus where the
#: Hessian vanishes too (skeleton/singular_curves.py _flat_point): linear
#: (halving the distance) where F vanishes to fourth order, from a few
#: cells to rounding level.
CURVE_FLAT_NEWTON = 80
#: Such a point is taken when its Hessian is at most this fraction of the
#: Hessian where the search started (a fraction of a cell away): along a
#: curve of rank-2 points the Hessian keeps its size, at a cone's apex on
#: it (fourth order) it falls as the square of the distance.
CURVE_FLAT = 1e-6

#: A singular point at most this far (fraction of the box) from a face of
#: the box lies on it: only the branches inside the box meet it there, so
#: the classifier's branch count is no target for its star (singmesh.api).
#: The centred points of float input sit within rounding of the face, and a
#: point a hair inside it is meshed as on it (the links on the face cannot
#: tell the cone's two nappes apart that close to the apex); its edges to
#: the box's face stay within the judges' 1e-9 of it.
STAR_ON_BOX = 1e-10

#: A two-branch point (a node, A_k with two sheets) further inside the box
#: than STAR_ON_BOX but at most this many fine cells from a face of it: the
#: links on that face pass its branches' traces less than a square apart
#: and may join them into one star cycle (facets.stars.part_branches parts
#: it again).  The star cube reaches a cell beyond its point, rounded
#: outwards, so it meets the face up to two cells in.
BRANCHES_NEAR_FACE = 2.0

#: A cycle of the star of a point on the box's boundary lying within this
#: many fine cells of one face of the box through the point ...
SLIVER_FLAT = 0.5
#: ... and nowhere nearer the point than this many fine cells may be a
#: small disc of surface grazing that face, not a piece through the point
#: (facets.stars.face_slivers).  The traces on the face of the pieces
#: through the point come to it, joined at most a cell or two from it
#: (a node, A_k) or where the two arcs of a cusp of the trace are a cell
#: apart (D4: 2 to 10 cells); the slivers seen on D4 stars lay 7 to 16
#: cells from their point, within 0.25 of a cell of the face.
SLIVER_FAR = 4.0
#: Such a cycle is a piece through the point after all when F = 0 on the
#: face, sampled at 1/SLIVER_SAMPLES of a fine cell, joins its events on
#: the face to the trace within SLIVER_NEAR cells of the point (nearer,
#: the arcs of a D4's cusp of the trace are closer than the sampling).
SLIVER_SAMPLES = 8
SLIVER_NEAR = 2.0
#: Flat cycles of one star with events this many fine cells apart or less
#: are pieces of one sheet along the face (facets.stars.face_slivers): the
#: pieces of a sheet less than a cell off the face, cut by it, lie a cell
#: or so apart in a row.
SLIVER_CHAIN = 1.5
