"""Every tolerance exactff uses: named, relative, and with its reason."""

import numpy as np

__all__ = [
    "EPS",
    "PLANARITY_RTOL",
    "PLANARITY_ULPS",
    "DEGENERATE_AREA_RTOL",
    "PLANE_SIDE_ULPS",
    "ON_PLANE_ULPS",
    "BSP_COPLANAR_ULPS",
    "BSP_SPLIT_SNAP_EPS",
    "ZBUFFER_ROUNDING_ULPS",
    "COVERED_RTOL",
    "DEFAULT_RTOL",
    "CHART_MARGIN",
    "AREA_CONSERVATION_RTOL",
    "OVERLAY_SNAP_GRID",
    "OVERLAP_RTOL",
    "PLANE_HASH_NORMAL",
    "PLANE_HASH_PAD",
    "NEAR_COPLANAR_RTOL",
    "TILE_FRAGMENTS",
    "MAX_TILES",
    "CLIP_BATCH",
    "LONG_POLYGON",
    "BATCH_VALIDATION_MAX_VERTICES",
    "BATCH_VALIDATION_PAIRS",
    "BSP_SCORE_SAMPLE",
    "BSP_AXIS_CANDIDATE_MIN",
    "CHART_EDGE_ULPS",
    "CHART_EXACT_CLIP_RTOL",
    "MP_MAX_DPS",
    "MP_VALUE_FLOOR",
    "VALUE_FLOOR",
    "BSP_AXIS_IMBALANCE",
    "CHART_VERTEX_ERROR",
    "REFINE_MATCH",
    "REFINE_AMBIGUOUS",
    "REFINE_QUERY",
    "REFINE_CHART_REACH",
    "REFINE_PARALLEL",
    "REFINE_VERTEX_ULPS",
    "REFINE_MP_ZERO_DIGITS",
    "RASTER_NEAR_ORIGIN",
    "SPLIT_FLATNESS_TIE",
    "AREA_HULL_RTOL",
    "AREA_EVENT_PARALLEL",
    "AREA_EVENT_LINE_ULPS",
    "AREA_RAY_PARALLEL",
    "AREA_SLIVER_CELL",
    "AREA_SLIVER_SHARE",
    "AREA_UNEVALUATED_SHARE",
    "AREA_UNEVALUATED_LEAST",
    "AREA_ROUNDING_ULPS",
    "AREA_HIDDEN_PAD",
    "AREA_BOOLEAN_ULPS",
    "AREA_IMAGE_ULPS",
    "AREA_IMAGE_RTOL",
    "AREA_IMAGE_PRECISE_RTOL",
    "AREA_IMAGE_PRECISE_SHARE",
    "AREA_IMAGE_BUDGET_SHARE",
    "AREA_BOUND_COS_SLACK",
    "AREA_BOUND_SPREAD_ULPS",
    "AREA_SLIVER_ULPS",
    "AREA_MAX_PIECES",
    "AREA_POINTS_PER_CALL",
    "AREA_EDGE_ON_RTOL",
    "AREA_HULL_MAX_POINTS",
    "AREA_WHOLE_TOLERANCE_SHARE",
    "AREA_CLOSED_THIN",
    "DOUBLE_TINY",
    "AREA_STRICT_TURN",
    "AREA_EDGE_CUT",
    "CLIP_MEET_ULPS",
    "C1",
    "SVBSP_BAND",
    "COMPILED_FALLBACK_MAX_POLYGONS",
    "BSP_COMPILED_MIN_MAGNITUDE",
    "SHAFT_MARGIN",
    "SHAFT_COMPILED_MAX_POLYGONS",
    "OCCLUDED_ATOL",
    "BOUND_CAP_FROM",
    "FLOAT_DISTANCE_RTOL",
    "SVBSP_SPLIT_ULPS",
    "SVBSP_BOX_BUDGET",
    "SVBSP_FILTER_ROUNDOFFS",
    "EXACT_FILTER_ROUNDOFFS",
    "SVBSP_BOX_MARGIN",
    "SVBSP_BOX_FLOOR",
    "SVBSP_LEAK_BUDGET_SHARE",
    "BSP_QUAD_TRUST",
    "LONG_SHADOW_EDGES",
    "LONG_SHADOW_LEAF",
    "SVBSP_COVER_GRID",
    "SVBSP_COVER_MAX_CELLS",
    "SVBSP_COVER_BUDGET",
    "SVBSP_COVER_OFFSET",
    "CONVEX_TURN_ULPS",
    "EQ3_FACTOR_ULPS",
    "SVBSP_TILES",
    "SVBSP_TILES_MAX",
    "SVBSP_TILES_EAGER",
    "SVBSP_THIN_IMAGE",
    "SVBSP_POLYGONS_PER_CELL",
    "VIEW3D_REGION_RTOL",
    "VIEW3D_IN_PLANE_RTOL",
    "VIEW3D_FACING_COS",
    "VIEW3D_WITHIN_RTOL",
    "VIEW3D_EMISSIVITY_RANGE",
    "VIEW3D_ZERO_COORDINATE",
    "C2",
    "OFFSET_ROUNDING_ULPS",
    "LONGDOUBLE_EPS",
    "AREA_FAR",
    "TANH_SINH_LEVEL",
    "TANH_SINH_T_MAX",
    "AREA_CLOSED_ULPS",
    "AREA_CLOSED_NEAR_PARALLEL",
    "AREA_CLOSED_RTOL",
    "AREA_CLOSED_FLOOR",
    "AREA_CLOSED_MP_DPS",
    "AREA_CLOSED_MP_ULPS",
    "AREA_GAUSS_ORDER",
    "AREA_GAUSS_LOW_ORDER",
    "AREA_RULE_ORDERS",
    "AREA_RULE_ORDERS_MANY_CELLS",
    "AREA_MANY_CELLS",
    "AREA_LOW_RULES_TOLERANCE",
    "AREA_SYMMETRIC_DEGREES",
    "AREA_SMALL_SYMMETRIC_DEGREES",
    "AREA_NULL_RULE_FACTOR",
    "AREA_SMALL_TRIANGLE_SHARE",
    "AREA_SMALL_TRIANGLE_REACH",
    "AREA_BACK_FACE_RTOL",
    "AREA_CUT_EXTEND_RTOL",
    "AREA_CURVED_EVENT_SAMPLES",
    "AREA_CURVED_EVENT_BISECTIONS",
    "AREA_CURVED_MAX_TRIPLES",
    "AREA_CURVED_EVENT_RTOL",
    "AREA_CURVED_CHORD_SPLIT",
    "AREA_CURVED_CHORD_HALVINGS",
    "AREA_CELL_COVER_RTOL",
    "AREA_CELL_COVER_ATOL_SHARE",
    "AREA_UMBRA_MIN_LINES",
    "AREA_UMBRA_MARGIN",
    "AREA_UMBRA_SHRINK",
    "AREA_UMBRA_MIN_SHARE",
    "AREA_UMBRA_LIMIT",
    "AREA_UMBRA_CLOSED_SHARE",
    "AREA_UMBRA_SPLIT_DEPTH",
    "AREA_UMBRA_COVER_DEPTH",
    "AREA_UMBRA_SPLIT_LEFT",
    "AREA_UMBRA_ROW_MARGIN",
    "AREA_UMBRA_COVER_PAIRS",
    "AREA_UMBRA_MAX_LEFT",
    "AREA_UMBRA_MAX_SQUARES",
    "AREA_UMBRA_COVER_STALL",
    "AREA_UMBRA_PROBE",
    "AREA_UMBRA_SPLIT_MIN_BLOCKERS",
    "AREA_WALL_PLANES",
    "AREA_WALL_TRIES",
    "AREA_WALL_PIECES",
    "AREA_WALL_NODES",
    "AREA_WALL_MIN_BLOCKERS",
    "AREA_WALL_BAND",
    "AREA_WALL_SLIVER",
    "AREA_UMBRA_TAKE_SHARE",
    "AREA_UMBRA_SQUARE_SLACK",
    "AREA_MAX_EVENT_LINES",
    "AREA_EVENT_LINE_KEY",
    "AREA_MAX_DEPTH",
    "AREA_RULE_CHECK_SHARE",
    "AREA_CORNER_MIDDLE_ORDER",
    "AREA_EDGE_TERMS_PER_CALL",
    "AREA_EVENT_ROWS_PER_CALL",
    "REMAINDER_SPLIT_POLYGONS",
    "REMAINDER_SLACK",
    "MATRIX_ROUNDING_ULPS",
    "MATRIX_ROW_SUM_ATOL",
    "MATRIX_RECIPROCITY_RTOL",
    "CLOSED_RESIDUAL",
    "AUDIT_CONTACT_RTOL",
    "AUDIT_NEAR_SEPARATION",
    "AUDIT_GRAZING_RTOL",
    "AUDIT_AREA_RTOL",
]

#: Unit roundoff of IEEE double precision, 2**-53.
EPS = float(np.finfo(float).eps) / 2

#: The smallest normal double (a floor for logarithms of quantities that may be 0).
DOUBLE_TINY = float(np.finfo(float).tiny)

#: A polygon is planar when no vertex lies farther than this fraction of its diameter
#: from its Newell plane (the same figure as ``shared/scenes/check_scene.py``).
PLANARITY_RTOL = 1e-6

#: On top of PLANARITY_RTOL, a vertex may deviate by this many ulps of the largest
#: coordinate magnitude: a tiny polygon far from the origin is planar up to the rounding
#: of its own coordinates.
PLANARITY_ULPS = 64.0

#: A polygon whose area is below this fraction of its squared diameter is degenerate
#: (collinear up to rounding): its area vector is then pure rounding noise.
DEGENERATE_AREA_RTOL = 256 * EPS

#: Below this many ulps of the coordinates' magnitude, the float signed distance of the
#: receiving point from a polygon's plane cannot decide its side (the rounding band):
#: the side is decided exactly (rational arithmetic on the float input) and the
#: unoccluded value evaluated in high precision. In the visibility engine, also the
#: rounding of local coordinates (ulps of ``|c - p|``) in ON_PLANE_ULPS's test.
PLANE_SIDE_ULPS = 16.0

#: The visibility engine takes a point within this many units of rounding of its own
#: coordinates and of a polygon's centroid (``u (|n| . |p| + |n| . |c|)``) of the
#: polygon's plane to lie in it (seen edge-on): a centroid rounded to float lies off its
#: polygon's plane by up to one such unit, a coplanar neighbour's plane by about as
#: much again. Beyond it (still inside PLANE_SIDE_ULPS) the side is decided exactly.
ON_PLANE_ULPS = 2.0

#: The near-coplanar band of every method (``exactff.predicates.coplanar_band``): a
#: point within this many ulps of the magnitudes in ``n . x - d`` lies in the plane.
#: In the BSP tree a vertex in it lies on the splitting plane (coordinates rounded to
#: float cannot place it more precisely, and splitting there would only cut
#: rounding-thin slivers); in the discrete methods' z-buffers a polygon whose plane
#: passes within it of the nearest hit point ties with it in depth. Beyond it both
#: order faces by their geometry (a rafter 3.5e-13 below a slab's plane at
#: 15 m, where the band is 2.1e-13, is in front of it for every method).
BSP_COPLANAR_ULPS = 64.0
#: BSP tree: a split's crossing within this many machine epsilons (of an end point's
#: largest coordinate, in every coordinate) of one of its edge's end points is that end
#: point, in both parts (exactff.halfspace.split_polygon, Builder::split): an exact
#: split of a polygon that nearly lies in the plane would otherwise leave edges an ulp
#: long, whose planes through the point the compiled core cannot orient (such a piece
#: has no shadow, and what it covers is charged to the pieces behind it). The compiled
#: build charges the end point's distance from the crossing to its vertex bound.
BSP_SPLIT_SNAP_EPS = 16.0

#: The z-buffers' depth-tie test evaluates ``n . (X - c)`` for a hit point ``X = t d``
#: in the receiver's local frame, not the input coordinates: on top of the band, it
#: allows this many ulps of ``|c - p|`` (the centroid relative to the point) and of
#: ``|t d|`` (the hit point), the rounding of the frame, the depth and the dot
#: products (a few ulps each; far below the band's 64 ulps of the input magnitudes
#: where the point is near what it sees).
ZBUFFER_ROUNDING_ULPS = 8.0

#: A tile of the clipper's covered region whose uncovered area falls below this fraction
#: of the tile is tested for being full: it is full only when its region covers the
#: whole tile (an exact predicate), so that a tiny polygon seen through a tiny gap keeps
#: its value; the area test only decides when to ask.
COVERED_RTOL = 1e-13

#: Default relative accuracy requested of every unoccluded form factor: where the
#: rounding-error estimate of the double-precision value exceeds it, the value is
#: re-evaluated with mpmath (docs/explanation/robustness.md).
DEFAULT_RTOL = 1e-12

#: The sampling z-buffer clips polygons to chart frusta widened by this much (chart
#: units), so that a cell on a chart's edge falls strictly inside the images covering it.
CHART_MARGIN = 1e-6

#: Every clipping step must conserve area, area(covered | g) = area(covered) +
#: area(g - covered), to this fraction of the areas involved: more is a GEOS overlay
#: failure (seen without an exception on near-degenerate input), and the step is redone.
AREA_CONSERVATION_RTOL = 1e-12

#: Snap-rounding grid (chart units, |u|, |v| <= 1) of the overlay fallbacks: vertices move
#: by less than 1e-15, far below the 1e-11 accuracy target of occluded values.
OVERLAY_SNAP_GRID = 2.0 ** -50

#: Two coplanar polygons overlap (a tie in depth that the scene summary reports) when
#: they share more than this fraction of the smaller one's area: polygons that only
#: touch along an edge share zero area up to the rounding of their coordinates.
OVERLAP_RTOL = 1e-9

#: The scene summary groups polygons by plane without the BSP tree
#: (``exactff.visibility.coplanar``): unit normals closer than this (in each
#: coordinate) are never put in different groups. Not a tolerance on the result: pairs
#: are then kept by the BSP tree's band; it bounds what is missed, a coplanar polygon
#: whose float normal is off by more than this (a sliver whose height is below its band
#: over 1e-3: 1e-8 of the coordinates' magnitude), and larger values only cost time.
PLANE_HASH_NORMAL = 1e-3

#: Two overlapping polygons are near-coplanar (reported apart by the scene summary)
#: when one lies within this of the other's plane, relative to the magnitudes in
#: ``n . x - d``, but not within the BSP tree's band (BSP_COPLANAR_ULPS ulps): a face
#: flush with another to 1e-13, which the exact method orders by its geometry and the
#: discrete methods' z-buffers may call a tie.
NEAR_COPLANAR_RTOL = 1e-9

#: The plane hash finds candidate pairs with one STRtree over every group's 2-D
#: bounding boxes, each group moved to its own place: boxes are widened by this share
#: of the widest group, far more than the rounding of the move (a few ulps of the
#: moved coordinates), so that no pair of meeting boxes is lost.
PLANE_HASH_PAD = 1e-6

#: The clipper's covered region is kept per tile of a grid over each chart, with about
#: this many fragment images per tile (not a tolerance: a cost trade-off, measured in
#: benchmarks/bench_engine.py; results do not depend on it beyond rounding).
TILE_FRAGMENTS = 1024

#: At most this many tiles per side of a chart.
MAX_TILES = 64

#: Fragments decided together (vectorised) by the tiled clipper: a cost trade-off
#: (larger batches have more parts that wait for an earlier part of the batch).
CLIP_BATCH = 256

#: The discrete methods' z-buffer tests cells against polygon images with a vectorised
#: crossing-number loop over the edges; images with more vertices than this use a
#: prepared point-in-polygon test instead (not a tolerance: a cost threshold). The
#: refinement likewise finds the candidate edges of fragments and scene polygons longer
#: than this by proximity (STRtree) instead of trying all of them.
LONG_POLYGON = 64

#: Scene validation checks polygons with the same vertex count together, with O(k^2)
#: pairwise distances; longer polygons are checked one by one (not a tolerance: a cost
#: threshold).
BATCH_VALIDATION_MAX_VERTICES = 128

#: Scene validation checks at most this many vertex pairs (polygons times k^2) in one
#: batch: bounds its temporaries (about 1 KiB per triangle) without costing time (not a
#: tolerance: a memory threshold, measured in benchmarks/bench_real_files.py).
BATCH_VALIDATION_PAIRS = 2 ** 19

#: BSP nodes with more fragments than this score their candidate planes on a random
#: sample of this many fragments (its own random stream: the same candidates; not a
#: tolerance but a cost threshold; the chosen plane then classifies every fragment).
#: Cloister (80,461 polygons): BSP build 1.6 -> 0.67 s (process time) with the same
#: tree (1,115 nodes, 1,700 splits); a sample of 1,024 gave 0.56 s and a tree of 1,153
#: nodes and 1,749 splits.
BSP_SCORE_SAMPLE = 4096
#: The compiled BSP build's exact tests are expansions of doubles, exact while no product
#: of up to six coordinate differences underflows (each difference at least the smaller
#: coordinate's ulp): a scene with a nonzero coordinate below this in magnitude is built
#: by the Python build instead (integers: exact at any magnitude).
BSP_COMPILED_MIN_MAGNITUDE = 1e-30

#: BSP nodes with more fragments than this also try a plane through the median of the
#: fragments' vertex means along their widest axis (not a tolerance: a cost threshold).
BSP_AXIS_CANDIDATE_MIN = 512

#: Chart coordinates within this many ulps of a chart's edge (u = +-1, v = +-1) are put on
#: it: they are points clipped onto the edge, off it only by the rounding of the clip and
#: the projection; left there, two images meeting on the edge had vertices 1e-15 apart,
#: which GEOS's overlays and predicates got wrong.
CHART_EDGE_ULPS = 8

#: A polygon whose plane passes within this much of its size of the point is clipped to
#: the charts' frustums in rational arithmetic (exactff.visibility.charts.
#: exact_chart_clip): in floating point, the crossings near the point carry rounding of
#: the polygon's size, which there is a large share of the image.
CHART_EXACT_CLIP_RTOL = 2.0 ** -30


#: mpmath's precision limit (decimal digits) in the last escalation tier: a value that
#: two evaluations 20 digits apart still disagree on here raises (or is returned with
#: its error estimate on request).
MP_MAX_DPS = 400

#: Two mpmath evaluations closer than this (absolutely) agree: a value that is 0 up to
#: the working precision has no relative accuracy to reach.
MP_VALUE_FLOOR = 1e-300

#: A form factor meets a relative ``tolerance`` when its bound is at most ``tolerance``
#: times the larger of its magnitude and this share of the hemisphere
#: (:func:`exactff.errors.misses_tolerance`): a value of 1e-30 cannot carry 12 digits
#: relative to the 1e-17 rounding of its neighbours (a sliver left between touching
#: polygons by moved coordinates, a polygon all but edge-on; hypothesis found a 0 with
#: a bound of 1.6e-16 from a rigid motion of an occluded row), while 100 such values
#: keep a row's sum within ``tolerance``; the accuracy targets are absolute plus relative
#: too (1e-13 + 1e-12 F, ten times looser than this floor's 1e-14 at the default;
#: docs/explanation/robustness.md, "Accuracy targets").
VALUE_FLOOR = 1e-2

#: The axis-plane candidate is tried at a BSP node when the best of the polygons' own
#: planes leaves more than this fraction of the node's fragments' count as the
#: difference between its two sides (a chain in the making; a cost heuristic).
BSP_AXIS_IMBALANCE = 0.75

#: Bound on how far the clipper moves a piece's vertex, in chart units: the local frame
#: and the chart's division (a few ulps), GEOS's intersections and the snap-rounding grid
#: OVERLAY_SNAP_GRID of its fallbacks (2**-50). A piece's value is off by at most its
#: perimeter times this over pi (the image's area density is at most 1 per unit of chart
#: area); measured against refined values in tests/test_refinement.py.
CHART_VERTEX_ERROR = 2.0 ** -47

#: A piece's edge is on a candidate plane when both its end points (unit directions) are
#: within this of it; the least residual wins.
REFINE_MATCH = 1e-10

#: A candidate plane within this residual of both end points of a piece's edge may be
#: the one the edge stands for: the clipper's vertices are within CHART_VERTEX_ERROR of
#: their places, and a unit direction or a double plane's normal rounds by a few ulps
#: more (twice the vertex error). Where another plane than the label is that close, the
#: region between the two arcs is charged to the refined value (Refiner._ambiguity).
REFINE_AMBIGUOUS = 2.0 * CHART_VERTEX_ERROR

#: Chart distance of the search for images whose boundary passes through an edge.
REFINE_QUERY = 1e-11

#: The refinement projects a long fragment's edges into a chart as far as this many
#: chart units from its centre (the chart spans [-1, 1]; not a tolerance: a margin, so
#: that an edge's image stays finite and every edge reaching the chart is kept).
REFINE_CHART_REACH = 2.0

#: Two planes closer to parallel than this (sine of their angle) do not give a vertex:
#: the clipper's is kept, with its error counted.
REFINE_PARALLEL = 1e-9

#: Rounding of a refined edge's plane and of its end points' residuals, in units of the
#: working precision per unit of the plane's condition (measured: at most 73 % of the
#: long-double estimate used against mpmath on 3,503 cloister pieces; 16 was not enough).
REFINE_VERTEX_ULPS = 32.0

#: In the mpmath tier, two planes whose cross product is below 10**(this - dps) of their
#: magnitudes are one great circle (collinear input edges), at the working precision.
REFINE_MP_ZERO_DIGITS = 10

#: The native disk rasteriser treats an edge passing closer to the point than this,
#: relative to its end points' distance, as passing through it (the polygon is cast ray
#: by ray instead).
RASTER_NEAR_ORIGIN = 1e-9

#: Fans of a non-planar face whose flatness scores differ by less than this are equal
#: (the first apex is kept), so that the split does not depend on rounding.
SPLIT_FLATNESS_TIE = 1e-12

#: Area form factors: a polygon within this of a face of the convex hull of an emitter
#: and a receiver (relative to the scene's size) lies on it and hides nothing.
AREA_HULL_RTOL = 1e-12

#: Area form factors: an event plane whose line with the emitter's plane has a direction
#: below this (relative to the plane's normal) is parallel to it (no event line).
AREA_EVENT_PARALLEL = 1e-12

#: Area form factors: a vertex within this many units of rounding (of the largest
#: coordinate of it and an edge's ends, times the edge's length and the shorter of its
#: ends' distances from the vertex) of the edge's line makes no event: the plane
#: through them is rounding's (exactff.area.events; _core/pair.cpp).
AREA_EVENT_LINE_ULPS = 64.0

#: Area form factors: a ray from a vertex through an edge's end point rising less than
#: this (relative to its length) towards the emitter's plane never meets it.
AREA_RAY_PARALLEL = 1e-14

#: Area form factors: cells of the cut emitter below this share of its area are slivers
#: of rounding and are dropped (their area counts in the estimate).
AREA_SLIVER_CELL = 1e-14

#: Area form factors: a triangle whose area (over the emitter's) is below this share of
#: the tolerance is integrated once, not cut, and carries its area as its estimate.
AREA_SLIVER_SHARE = 1e-3

#: Area form factors: the share of a pair's absolute tolerance that its triangles (cells)
#: of least bound times area may take unevaluated, each at half its bound on the
#: unoccluded point values times its area, within as much (exactff.area.points.unevaluated,
#: exactff.area.points.unoccluded_bounds): where many events cut an emitter far from a
#: small receiver, most cells matter less than the tolerance (View3D's gunter2, wall 7
#: of 380 to a gable triangle of 0.28 some 100 away: 52,067 triangles, the bound 8.3e-6
#: near the gable and 4.8e-7 at the wall's far end).
AREA_UNEVALUATED_SHARE = 0.25
#: ... and only where they are at least this share of the pair's triangles (elsewhere
#: the tolerance's share buys little time: on gunter1 at 1e-6, 103 triangles of 168,941
#: points, their values up to 0.97 of their estimates from values at 1e-11; with this, 6
#: triangles, 0.17 as with none; the 106-surface box none).
AREA_UNEVALUATED_LEAST = 0.2

#: Area form factors: the rounding of a contour sum or an area rule, in units of
#: rounding of its absolute terms.
AREA_ROUNDING_ULPS = 64.0

#: Area form factors: the rectangle over which a blocker's image is kept, around the
#: receiver in its plane, is wider than the receiver's bounding box by this share of it
#: (the rectangle's edges then never meet the receiver's); likewise the disk within
#: which event lines are kept, around the emitter.
AREA_HIDDEN_PAD = 0.01

#: Area form factors: the boundary of the hidden region built by half-plane splits moves
#: by at most this many units of rounding of its largest coordinate per splitting line.
AREA_BOOLEAN_ULPS = 16.0

#: Area form factors, hidden parts: the rounding of a blocker's offset from the point,
#: and of each crossing of the pyramid's planes, in units of the working precision's
#: roundoff (doubles, or long double) of its length (a crossing's: of its edge's longer
#: end; added to its ends' own); and the share of the receiver's size beyond which what
#: that rounding can move a point's images (magnified by the projection near the point)
#: sends the point to the engine.
AREA_IMAGE_ULPS = 8.0
AREA_IMAGE_RTOL = 1e-9

#: Area form factors, hidden parts: the 3-D clipping and projection run in doubles, and
#: again in long double at a point whose images their rounding can move by more than
#: this share of the receiver's size (2.4 times faster in doubles on View3D's facet).
AREA_IMAGE_PRECISE_RTOL = 1e-13

#: Area form factors, hidden parts: again in long double (AREA_IMAGE_PRECISE_RTOL) only
#: where what the doubles' rounding moves of the point's value (the estimate's term for
#: it, which then holds the doubles' figure) is more than this share of the caller's
#: budget for it (``atol`` of ``hidden_values``, AREA_IMAGE_BUDGET_SHARE of the pair's):
#: the rules integrate the estimates, so at most this share of that budget a rule, a
#: quarter of 1 % of the tolerance. On gunter1 at 1e-6, 58 % of the points went to long
#: double by AREA_IMAGE_PRECISE_RTOL alone, each costing both passes. 0.25 rather than
#: 0.01: at 1e-9, gunter1's matrix 21 % and test4's 22 % faster, the same points and
#: values within 3e-17, the sum of the estimates 0.05 % larger (docs/benchmarks.md).
AREA_IMAGE_PRECISE_SHARE = 0.25

#: Area form factors: what the bound on the unoccluded point value
#: (``exactff.area.points.unoccluded_bound``) adds to each cosine's bound for the
#: polygon's normal against the one the kernel takes (the scene's, from the whole
#: polygon): a polygon planar within PLANARITY_RTOL of its diameter turns its parts'
#: normals by a few 1e-6; with room.
AREA_BOUND_COS_SLACK = 1e-4
#: Area form factors: the rounding that bound adds to the spread h of ``n . v`` over the
#: two polygons' vertices, in units of EPS times the coordinates' largest 1-norm: each
#: ``n . v`` is a sum of three products of a unit normal's component (itself rounded,
#: its norm's division included) and a coordinate, within a few roundoffs of that norm,
#: and h is a difference of two of them; with room.
AREA_BOUND_SPREAD_ULPS = 64.0

#: Area form factors, occluded pairs: the share of the tolerance that a point value's
#: estimate may hold for its images' rounding before the point goes to the engine (the
#: adaptive rules integrate the estimates, so at most this share of the value's); and
#: what the bound 0 <= hidden <= unoccluded of a call's untrusted points may cost, their
#: weights in the rules applied, for it to stand in for the engine.
AREA_IMAGE_BUDGET_SHARE = 0.01

#: Area form factors, hidden parts: a piece of the hidden region whose doubled area is
#: within this many units of rounding of the squared extent of its point's images is a
#: sliver left by splits along nearly coincident lines: dropped, its area in the
#: estimate; and the pieces one point may hold before it goes to the engine.
AREA_SLIVER_ULPS = 64.0
AREA_MAX_PIECES = 20_000

#: Area form factors, hidden parts: points per call of the compiled hidden regions and
#: their sector sums (bounds the temporaries: a closed Cornell box's floor, one call for
#: a level's 300,000 points, needed 43 million edges' worth, over 8 GiB).
AREA_POINTS_PER_CALL = 20_000

#: Area form factors: a blocker whose plane passes within this of a point (relative to
#: the sub-scene's size) is seen edge-on from it and hides nothing.
AREA_EDGE_ON_RTOL = 8 * EPS
#: ... and a convex solid's member whose plane passes more than this (relative to the
#: same size) behind a point is seen from behind: skipped where the point is this far in
#: front of another member's plane (outside the hull). Within it the member is kept,
#: which is always right (a skipped one only saves work).
AREA_BACK_FACE_RTOL = 1e-12

#: Area rows: a receiver is strictly convex (blockers are clipped to the pyramid over it)
#: where it turns by more than this (radians, as the sine) at every vertex.
AREA_STRICT_TURN = 1e-6

#: The closed form's skew edge pairs: a triangle of the parallelogram thinner than this
#: share of its size (``exactff/_core/closed_form.cpp``) is of no area (its
#: terms would only underflow).
AREA_CLOSED_THIN = 1e-100

#: Area form factors: the share of a pair's tolerance the unoccluded value of an
#: occluded pair may take (its closed form falls back to the far rule or mpmath only
#: beyond it); the hidden part's adaptive rules have the rest.
AREA_WHOLE_TOLERANCE_SHARE = 0.1

#: Area form factors: the hull test of a pair's blockers (``exactff/_core/row_culling.cpp``)
#: takes the hull's faces as the planes through three of the pair's vertices that have
#: them all on one side, O(v^4) in its v vertices: beyond this many, no hull test (every
#: polygon the shaft leaves is a blocker, hiding nothing where it is outside the hull).
AREA_HULL_MAX_POINTS = 48

#: Area form factors: cuts of an emitter's edge (for the contour integral's outer rule)
#: closer than this (as a share of the edge) to each other or to its ends are dropped.
AREA_EDGE_CUT = 1e-9

#: The half-space clipper computes a crossing as the meet of the edge's plane through
#: the origin with the clipping plane (``exactff.halfspace``) where that plane's normal
#: ``A x e`` is above this many ulps of ``|A|_1 |e|_1`` (below it the edge's line runs
#: through the origin to rounding and the interpolated crossing is kept), and where it
#: agrees with the interpolated crossing within this many ulps of ``(|A|_1 + |e|_1)``
#: times the crossing's condition ``1 + |h|_1 |e|_1 / |h . e|``.
CLIP_MEET_ULPS = 8.0

#: Constants of the sector sums' rounding-error estimate (docs/explanation/robustness.md):
#: per edge term,
#: the relative error of its angle and sum (C1 ulps), and of its plane's direction (C2
#: ulps per unit of the cross product's condition number).
C1 = 10.0
C2 = 10.0
#: Roundoffs bounding the error of the midpoint factor ``v_x u_y + u_x v_y`` of Eq. 3's
#: stable form (``exactff.kernel.eq3_ring_sums``; the compiled core's is the same),
#: times ``2 sin(theta / 2)``: its normalisations, cross product and dot products, each
#: a few roundoffs of unit vectors, and ``1 / cos(theta / 2)`` from the midpoint's
#: length, which ``sin(theta)`` turns into ``2 sin(theta / 2)``.
EQ3_FACTOR_ULPS = 64.0

#: The offsets' rounding in that estimate (``kernel.sector._offset_rounding``): a
#: vertex's position from the point is off by at most this many ulps of
#: ``|A0| + |E_i|`` (the differences rounded once per coordinate, then rotated: about
#: 6.2, the frame's own rounding folded in); the cosines along an edge are good to as
#: many ulps.
OFFSET_ROUNDING_ULPS = 8.0

#: Unit roundoff of the platform's long double (2**-64 for x87 80-bit extended; equal to
#: EPS where long double is double, and the second tier of the ladder is then skipped).
LONGDOUBLE_EPS = float(np.finfo(np.longdouble).eps) / 2

#: Area form factors: beyond this distance between centroids (in diameters of the larger
#: polygon) the area integral of exact point values replaces the contour integral, whose
#: terms cancel as (distance / size)^2 (measured: 4e-12 relative for squares 100
#: diameters apart).
AREA_FAR = 3.0

#: Area form factors: the tanh-sinh rule of the contour integral's outer integral (step
#: 2**-level, nodes up to |t| = t_max).
TANH_SINH_LEVEL = 6
TANH_SINH_T_MAX = 3.6

#: Area form factors: Gauss-Legendre orders of the far-field rule on the emitter's
#: triangles, and of the coarser rule its estimate compares with.
AREA_GAUSS_ORDER = 12
AREA_GAUSS_LOW_ORDER = 8

#: Area form factors, occluded pairs: the two collapsed Gauss rules per triangle (points
#: a side), and how many times a triangle may be cut in four.
AREA_RULE_ORDERS = (6, 10)
AREA_MAX_DEPTH = 7
#: ... and the lower pair that each triangle of a pair tries first where the events cut
#: its emitter into more than AREA_MANY_CELLS triangles (small ones, which rarely need
#: more points; a triangle the lower pair misses takes the pair above). Measured on
#: View3D's examples and the closed Cornell box (docs/benchmarks.md): 20 and 100 were
#: no better than 50.
AREA_RULE_ORDERS_MANY_CELLS = (3, 5)
AREA_MANY_CELLS = 50
#: ... and where a blocker touches a triangle's first vertex (a corner), a third
#: collapsed rule between that pair's two, of this many points a side: the high rule's
#: estimate is its difference from either. Without it, a corner of gunter1 (row 17,
#: column 11 without shortcuts, at 1e-9) came out 1.02 times its estimate: the errors
#: of 3, 4, 5 and 6 points a side were 3.2e-10, 1.9e-9, 2.5e-10 and -3.2e-11.
AREA_CORNER_MIDDLE_ORDER = 4
#: ... that pair's degrees (4 and 8) in symmetric rules of 6 and 16 points
#: (exactff.area.rules.SYMMETRIC_RULES), on every triangle but those whose first vertex
#: a blocker touches (they keep the collapsed rule, whose collapsed vertex it is).
AREA_SYMMETRIC_DEGREES = (4, 8)
#: ... and a small triangle (at most AREA_SMALL_TRIANGLE_SHARE of the emitter's area, its
#: box's diagonal at most AREA_SMALL_TRIANGLE_REACH times the distance from its box to
#: every box of the receiver's part and the blockers' pieces) off a corner, at those
#: targets, the symmetric rules of degrees 2 and 4 (3 and 6 points) instead, and where
#: refined those of degrees 4 and 8 (exactff.area.rules.rule_pair): 9 points where 22
#: were, 22 where 136 were. At 1e-6: gunter1 179,396 points, now 163,797; the 106-surface
#: box 1.50 million, now 1.20 million; gunter2's rows 100, 200, 300 and 50 573,202, now
#: 489,013; no value's error against values 100 to 100,000 times tighter grew (gunter1
#: 0.31 of its estimate at most, the box 0.22). The distance: without it, two triangles
#: of gunter2's pair (285, 20), 0.05 from a gable that meets the emitter along an edge,
#: had rules agreeing to 8.4e-9 while 4.1e-7 off (a value at 1.6 times its estimate);
#: at a share of 3e-2, gunter1's worst rose to 0.52; on every triangle, a value of the
#: box came out at 22 times its estimate (docs/benchmarks.md).
AREA_SMALL_SYMMETRIC_DEGREES = (2, 4)
AREA_SMALL_TRIANGLE_SHARE = 1e-2
AREA_SMALL_TRIANGLE_REACH = 1.0
#: ... and every pair's triangles start with the lower pair where the target (absolute)
#: is at least this: at 1e-6 the lower pair converges on most cells, large or not
#: (gunter1: 266,288 points instead of 450,466, 2.74 -> 2.24 s; the closed Cornell box
#: 5 % fewer points; test4 and facet 6 to 10 % faster); at 1e-9 the large cells of
#: test4 and facet take the higher pair in the end, and starting low cost them 15 %.
AREA_LOW_RULES_TOLERANCE = 1e-7
#: Area form factors: where the symmetric pair of degrees 4 and 8 is taken, its high
#: rule's error is estimated by at least this many times the spread of its null rules
#: of degree 5 (exactff.area.rules.symmetric_null_spread), not by the rules' difference
#: alone: a needle cell of gunter2 (pair (186, 8)) had rules agreeing 24 times closer
#: than the degree-8 rule's error. Of 101 triangles of random gunter2 pairs whose error
#: was at least 2 % of their pair's estimate, 28 were beyond their difference, and with
#: the spread times 1, 2 and 3, 3, 1 and 0. At 1e-6: 4 to 14 % more points on View3D's
#: examples (test4 15,968 -> 16,784, facet 29,424 -> 33,640, gunter1 163,797 ->
#: 170,599), 2.8 % on the 106-surface box (1,204,703 -> 1,237,949); (186, 8) and (187,
#: 8), 1.54 and 1.16 times their estimates of their values at 1e-9 before, now within,
#: as are 298 random gunter2 pairs (benchmarks/bench_area_pairs.py, docs/benchmarks.md).
AREA_NULL_RULE_FACTOR = 3.0
#: Area form factors: a triangle whose rules' difference the closed form of the
#: unoccluded part shows to be too small (``exactff.area.rule_check``) is refined,
#: where what it shows exceeds this share of the triangle's share of the tolerance.
AREA_RULE_CHECK_SHARE = 0.1
#: Area form factors: an end of an event line cut to the emitter this close to its
#: boundary (relative to its size, the square root of its area) is moved out by as much
#: before the lines are noded, so that it crosses the boundary (as GEOS rounds it, a
#: line through a corner ended 3e-15 inside: a dangle, dropped, and a cell left uncut).
AREA_CUT_EXTEND_RTOL = 1e-9
#: Area form factors: a curved visibility event (three skew edges: the images of two
#: blockers' edges crossing on the receiver's edge, exactff.area.curved.curved_event_lines)
#: is looked for between the points of the receiver's edge where it may start or stop
#: and this many steps along it (where it leaves the disk around the emitter) ...
AREA_CURVED_EVENT_SAMPLES = 16
#: ... (where it leaves that disk, by at most this many bisections, fewer once every end
#: lies beyond twice the radius: only that it lies outside the emitter matters) ...
AREA_CURVED_EVENT_BISECTIONS = 20
#: ... for a pair with at most this many triples of edges that may trace one (after the
#: cheap culls): a cost limit. At 1e-6 the 106-surface box's pairs have at most 230,
#: gunter1's 938; gunter2's rows 0 and 95 have 15 pairs beyond it (up to 31,788), and its
#: pair (38, 3) behind 151 blockers 700,000 before the culls, whose 31,000 curves took 22 s
#: and 127,000 chords; row 38 took 154 s with a limit of 20,000, 53 s with this one (52 s
#: without curved events). Traced compiled, row 38's pairs would trace 401,734 curves as
#: 4.7 million chords in 18 s without the limit: the chords' cells are what it bounds.
AREA_CURVED_MAX_TRIPLES = 2_000
#: ... and cut along as a polyline whose chords lie within this of the curve (relative to
#: the emitter's size), or within the square root of the tolerance where that is less:
#: the kink of the hidden part (a jump of its second derivative) then lies in a strip of
#: that width along a cut, where it moves the rules' values by that width squared.
AREA_CURVED_EVENT_RTOL = 1e-3
#: ... the steps of a piece of curve first even (from the deviation at the piece's
#: midpoint: up to 2.03 times too far where its curvature is uneven), then each step
#: whose own midpoint lies farther from its chord than this share of that deviation
#: halved (the curve's farthest point from a chord is not at the step's midpoint where
#: its parametrisation is uneven: 1.0004 times the midpoint's on a step of
#: scratch chords_check's trial 22, seed 0) ...
AREA_CURVED_CHORD_SPLIT = 0.9
#: ... at most this many times (each halving cuts the deviation about four times).
AREA_CURVED_CHORD_HALVINGS = 10
#: ... and the emitter's cells must cover it to this share of its area, else it is cut
#: again another way (as cut, then on a grid: the cells that cover most are kept) ...
AREA_CELL_COVER_RTOL = 1e-12
#: ... or miss no more area than the estimate's charge for it (1 per unit of the
#: emitter's area) keeps within this share of the pair's absolute target: the cut along
#: the lengthened lines is the one whose cells follow every event; the cut as cut leaves
#: a line that ends short of P's boundary by rounding dangling in a cell, whose kink the
#: rules then miss (test4 turned and moved by 890: GEOS dropped 1e-11 of the area from
#: the lengthened cut, and the fallback's cells put the value 3.8e-6 off, 8 times its
#: estimate).
AREA_CELL_COVER_ATOL_SHARE = 1e-3

#: Area form factors: the umbras (exactff.area.umbra) of an occluded pair whose events
#: give more than AREA_UMBRA_MIN_LINES segments (their set-up, 1-30 ms a pair, costs
#: more than it saves below that: gunter2's rows 95 and 300, pairs of 64 to 1,000
#: segments 2.03 s without and 2.62 s with, of 1,000 to 3,000 6.34 and 5.65 s): the regions of the emitter from which one
#: blocker hides the whole receiver, where the event lines are cut away and the cells
#: integrated in closed form (on View3D's gunter2, row 38, column 23: 472,008 cells and
#: 10.2 million points before). A point passes the test where every segment to the
#: receiver's vertices meets the blocker AREA_UMBRA_MARGIN of the coordinates' size
#: inside (some 1e5 units of rounding of each term; the grazing factor on top); each
#: region is shrunk by AREA_UMBRA_SHRINK of the emitter's size and proven on the region
#: within that much of it, so that a cell noded within rounding of it is in; regions
#: below AREA_UMBRA_MIN_SHARE of the emitter are not used, nor more than AREA_UMBRA_LIMIT.
AREA_UMBRA_MIN_LINES = 1000
AREA_UMBRA_MARGIN = 1e-11
AREA_UMBRA_SHRINK = 1e-9
AREA_UMBRA_MIN_SHARE = 1e-3
AREA_UMBRA_LIMIT = 8
#: ... and their cells take the closed form where its estimate (summed over them) is
#: within this share of the pair's tolerance, else the rules as before.
AREA_UMBRA_CLOSED_SHARE = 0.1
#: ... and first, the umbras of several blockers (exactff.area.joint_umbra): the
#: emitter cut into squares, each cut in four down to AREA_UMBRA_SPLIT_DEPTH levels where
#: the receiver's part left uncovered is at most AREA_UMBRA_SPLIT_LEFT of it; the
#: receiver cut into triangles down to AREA_UMBRA_COVER_DEPTH levels (while at most
#: AREA_UMBRA_COVER_PAIRS pairs of a triangle and a blocker are candidates, and while
#: the area left falls below AREA_UMBRA_COVER_STALL of the last level's) to cover it by
#: the parts each blocker hides from all of a square. A pair none of whose first
#: AREA_UMBRA_PROBE squares (spread over the emitter) has its bound within its share, with
#: more than AREA_UMBRA_MAX_LEFT squares left (each would be a pair of its own: 0, as on
#: gunter2 the squares left, where the receiver is seen past the seams, cost more than
#: the pair whole, row 38 98.5 s instead of 47.2 s at 64), or more than
#: AREA_UMBRA_MAX_SQUARES squares to test on a level, is integrated whole instead.
AREA_UMBRA_SPLIT_DEPTH = 3
AREA_UMBRA_COVER_DEPTH = 8
AREA_UMBRA_SPLIT_LEFT = 0.5
AREA_UMBRA_COVER_PAIRS = 4096
AREA_UMBRA_MAX_LEFT = 0
AREA_UMBRA_MAX_SQUARES = 1024
AREA_UMBRA_COVER_STALL = 0.75
AREA_UMBRA_PROBE = 4
#: ... tried only on pairs of at least this many blockers: on gunter2's row 38 the pairs
#: of about 40 blockers (over AREA_UMBRA_MIN_LINES segments, but a few thousand points)
#: cost 0.3-2.5 s of squares each, more than they saved (the row 71.2 s instead of 42.7
#: s); pair (3, 27), of 135, 300 s without them.
AREA_UMBRA_SPLIT_MIN_BLOCKERS = 100
#: Area form factors: walls between a pair (exactff.area.walls), proven in rationals to
#: hide all of the receiver from all of the emitter, across up to AREA_WALL_PLANES
#: planes one behind the other (the pieces of a plane's slice its blockers leave
#: uncovered tried against the next); at each step the AREA_WALL_TRIES planes whose
#: slices GEOS finds least uncovered are tried, a plane that leaves more than
#: AREA_WALL_PIECES pieces goes no further, and a pair stops after AREA_WALL_NODES exact
#: tests (each a few ms: a pair not hidden costs no more than that). At 3 planes, 8
#: pieces and 24 tests, gunter2's end wall 22 and the roof strips behind a ceiling of 51
#: pieces and the planes beyond it (four in all) were integrated instead: 1.0 million
#: points each for a value of 0, row 22 46.6 s; now 11.5 s, the same values (the
#: strips proven in 0.15 s each; a pair the proof fails on costs up to 0.07 s instead
#: of 0.03). The proof for (22, 165): the wall x = -109.5, the annex's ceiling (15
#: pieces left), the roof lights' slopes and the wall y = 207.3; 33 exact tests.
AREA_WALL_PLANES = 4
AREA_WALL_TRIES = 3
AREA_WALL_PIECES = 20
AREA_WALL_NODES = 100
#: ... tried before the integral on pairs of at least this many blockers; on fewer only
#: where the integral's estimate misses the tolerance. On gunter2's rows 0, 1, 8, 13,
#: 18, 42, 150 and 300 the proofs of the pairs of 1-15 blockers cost 3.4 s against 1.3
#: s for integrating those they take, those of 16 or more 2.6 s against 7.3 s.
AREA_WALL_MIN_BLOCKERS = 16
#: ... what doubles choose there (the proof is exact whatever they are): within this of
#: the coordinates' size a vertex counts as in a plane, and the blockers' planes are
#: grouped (normals and offsets rounded to it); a slice with this share of its area left
#: counts as covered in the plan, one with all but this share as not covered at all;
#: the plan drops uncovered parts below AREA_WALL_SLIVER of the slice's area.
AREA_WALL_BAND = 1e-9
AREA_WALL_SLIVER = 1e-12
#: ... a square is taken (half its bound, within as much) without being cut further
#: where that bound is within this share of its share of the tolerance, and the receiver
#: is cut no finer than the area whose bound is this share of it.
AREA_UMBRA_TAKE_SHARE = 1e-2
#: ... the emitter's first squares: its extent over its shorter side rounded up, less
#: this (an extent of 1 with a rounding above it is one square, not two).
AREA_UMBRA_SQUARE_SLACK = 1e-9
#: ... each proven with the blocker's plane AREA_UMBRA_MARGIN of the coordinates' size
#: away, and inside each plane through a corner of the square and an edge of the
#: blocker by AREA_UMBRA_ROW_MARGIN of its terms' size (some 450 units of rounding; the
#: computed value is within some ten of them), on the square less a strip of
#: AREA_UMBRA_SHRINK of the emitter's size along its boundary (bounded instead).
AREA_UMBRA_ROW_MARGIN = 1e-13
#: Area form factors: an occluded pair whose events lie on more distinct lines than this
#: (after the umbras; exactff.area.events.distinct_lines, angle and offset rounded to
#: AREA_EVENT_LINE_KEY) raises NumericalError instead of noding them: the arrangement's
#: time and its cells grow with the square of its lines (up to 50 million crossings
#: here, some gigabytes of cells and rule nodes). The most on View3D's gunter2: 3,804
#: meeting the emitter (row 38, column 23: 22,549 segments, 472,008 cells).
AREA_MAX_EVENT_LINES = 10_000
AREA_EVENT_LINE_KEY = 1e-9

#: Area form factors: receivers per call of the vectorised point values (bounds the
#: temporaries: about 2e5 edge terms per call).
AREA_EDGE_TERMS_PER_CALL = 200_000
#: ... and vertex-edge rows per batch of a pair's visibility events (its blockers' every
#: vertex against every other's edges: bounds the temporaries, a few hundred bytes a row).
AREA_EVENT_ROWS_PER_CALL = 200_000

#: Compiled core (exactff.visibility.compiled): a vertex lies on a plane through the
#: point when its distance is within this band (radians, with the plane's and vertex's
#: own error bounds added); 16 units of long double's roundoff (the sign's rounding is
#: 3 to 5 of them).
SVBSP_BAND = 16 * LONGDOUBLE_EPS
#: The accuracy target of an occluded value (absolute; docs/explanation/robustness.md,
#: "Accuracy targets"). The compiled core's bound
#: for the rounding of the BSP's crossings is held to it (beyond, the row goes to the
#: Python engine): no precision tier narrows that part, and the Python engine's crossings
#: are rounded as well.
OCCLUDED_ATOL = 1e-11

#: A compiled row's bound above its value and above this is capped by what the value
#: could be off by at all (between 0 and the unoccluded value:
#: ``exactff.visibility.compiled._capped_by_unoccluded``); below it, none is computed.
BOUND_CAP_FROM = 1e-6

#: A distance computed in float and used as a lower bound (the node-first order's
#: charge, ``exactff.visibility.bsp.node_first_charges``, and
#: ``exactff.geometry.point_polygon_distance``) is shrunk by this share of the
#: magnitudes involved, far above its rounding.
FLOAT_DISTANCE_RTOL = 1e-12
#: Compiled core: the largest scene whose compiled values that miss the tolerance are
#: recomputed by the Python engine (per polygon: its row, of which only those values
#: are kept; ``stats["python_polygons"]``). Its rows cost 5 to 20 times the compiled
#: core's and grow with the scene, so on a larger scene each such value is recomputed
#: on its shaft instead (the polygons that may hide part of it,
#: ``stats["shaft_polygons"]``): by the compiled core first, then by the Python engine
#: where the shafts of the values still missing hold at most this many polygons in all
#: (about 30 s); a value still unsettled raises at once (or is returned with its bound,
#: ``error=True``).
COMPILED_FALLBACK_MAX_POLYGONS = 5_000
#: Compiled core, a value settled on its shaft: polygons within this much (relative to
#: the scene's largest coordinate, plus 1) of the convex hull of the point and the
#: polygon are kept in the shaft, so that the hull's own rounding drops none that
#: reaches into it.
SHAFT_MARGIN = 1e-9
#: Compiled core, values settled on their shafts: the compiled core recomputes them
#: there first (its own BSP tree of the shaft's polygons), where the row's shafts hold
#: at most this many polygons in all (a compiled build and row each: 0.07 s for a shaft
#: of 301 polygons, 0.11 s for 634, SampleHouse4 row 18196; ``stats["shaft_compiled"]``);
#: the Python engine then takes those
#: still missing, within ``COMPILED_FALLBACK_MAX_POLYGONS``.
SHAFT_COMPILED_MAX_POLYGONS = 50_000
#: Compiled core: the rounding of a vertex split off an edge, in long double roundoffs
#: per unit of the edge's ends' distance from the point over the new vertex's (the
#: parameter's quotient and the three-term interpolation, with a margin).
SVBSP_SPLIT_ULPS = 8.0
#: Compiled core: most shadow-tree nodes one bounding-box test may visit before it
#: gives up (the subtree is then entered, which is always correct).
SVBSP_BOX_BUDGET = 256
#: Compiled core (exactff/_core/constants.h, generated by tools/gen_core_constants.py):
#: the classification's double filter. A distance computed in double from the long
#: double vectors rounded to double is within this many units of DBL_EPSILON (2 double
#: roundoffs each) of |m| |v| of its long double value (6 roundoffs needed, 8 kept).
SVBSP_FILTER_ROUNDOFFS = 4.0
#: Compiled core (constants.h): the exact predicates' long double filter. A 3 x 3
#: determinant of differences of doubles, or a dot product with one, computed in long
#: double is within this many long double unit roundoffs (LDBL_EPSILON each) of its
#: permanent of its exact value; beyond, its sign is taken from it, else computed exactly.
EXACT_FILTER_ROUNDOFFS = 32.0
#: Compiled core (constants.h): what a row's shadows leave uncovered (the part of a
#: non-convex image outside its kernel, a sliver with no shadow: Core::leave_out) is
#: charged to every receiving value while the row's total stays within this share of
#: the relative tolerance: a hundredth of the tolerance at VALUE_FLOOR (1e-16 at the
#: default 1e-12), so that it never decides whether a value meets the tolerance; larger
#: parts are charged only to the later visible pieces whose cones meet theirs.
SVBSP_LEAK_BUDGET_SHARE = 1e-4
#: Compiled core (constants.h): the point must lie outside a subtree's bounding box by
#: this share of the box's and the point's coordinates' magnitudes (plus SVBSP_BOX_FLOOR)
#: for the box's conic hull from it to be a pointed cone (the culling test).
SVBSP_BOX_MARGIN = 1e-9
SVBSP_BOX_FLOOR = 1e-300
#: Compiled BSP build (constants.h): a crossing computed in quadruple precision is kept
#: where its bound is within this share of a double roundoff of its coordinates (the
#: rounding to double then dominates); beyond, it is computed exactly.
BSP_QUAD_TRUST = 1e-3
#: Compiled core (constants.h): a visible piece whose shadow takes more than this many of
#: its edges' planes gets them as a balanced tree of chords (Core::long_shadow), parts of
#: at most ``LONG_SHADOW_LEAF`` edges each, instead of one chain: a piece behind it then
#: visits about log2(edges / leaf) + leaf planes instead of every edge's, and the pieces
#: around it are cut across its edges instead of along their nearly parallel planes (the
#: office with a 5,000-vertex table top, ``benchmarks/bench_long_polygon.py``).
LONG_SHADOW_EDGES = 32
LONG_SHADOW_LEAF = 16
#: Compiled core (constants.h): the cube map of directions about the point whose cells
#: are proven covered (``Core::cell_covered``), so that a fragment or a BSP subtree's box
#: in covered cells is skipped without being cut along every shadow over it
#: (``stats["fragments_covered"]``). Cells per face side (a power of two), the largest
#: footprint (in cells) of a hidden fragment whose cells are then tried, the shadow-tree
#: visits one proof may take, and how far the inner grid lines are moved off the even
#: values (off the planes of an axis-aligned scene and of the tiles). Measured on eight
#: SampleHouse4 rows (core, process time): 32 cells 5-15 % faster than none, 64 about
#: the same or better, 128 slower (more proofs).
SVBSP_COVER_GRID = 64
SVBSP_COVER_MAX_CELLS = 16
SVBSP_COVER_BUDGET = 2048
SVBSP_COVER_OFFSET = 0.0123456789
#: A ring is convex where every corner turns the normal's way or is collinear within
#: this many ulps of its edges' cross product (``exactff.visibility.compiled.convex_rings``).
CONVEX_TURN_ULPS = 8.0
#: Compiled core: planes per axis of the grid the upper hemisphere is cut into
#: (``(tiles + 1)^2`` cells, each growing its own shadows; at once only in coarse
#: blocks, SVBSP_TILES_EAGER), at least this many and at most SVBSP_TILES_MAX (63: the
#: core's blocks hold 6 bits per axis), about SVBSP_POLYGONS_PER_CELL polygons of the
#: scene per cell (``exactff.visibility.compiled._shadow_tiles``). Measured with the
#: whole grid cut at once, on six cloister rows (80,461 polygons, core alone, process
#: time): 7 tiles 4.2-4.5 s, 15 4.1 s, 31 3.6-3.8 s, 63 4.0 s, 127 5.1 s; on six office
#: rows (4,424): 7 or 15 tiles 0.15 s, 31 0.21 s (the bigger tree built each row).
SVBSP_TILES = 7
SVBSP_TILES_MAX = 63
SVBSP_POLYGONS_PER_CELL = 64
#: Compiled core (constants.h): the tiles' grid is cut at once only into blocks of fewer
#: than this many planes along each axis (a coarse balanced tree: 2 x 2 blocks for 19
#: tiles, 4 x 4 for 34); a block is cut further where a visible piece arriving in it lies
#: clearly on one side of its middle plane (``Core::grow_tile``), so that a finer plane
#: never cuts the piece it is placed for. Measured (issue 48, one run each, alternating, medians of 8
#: seeded and README rows, in hemicube-256 rows; docs/benchmarks.md, bench_real_rows):
#: tested_sample_project 7.47 -> 6.82, SampleHouse4 5.11 -> 4.89, Duplex 0.83 -> 0.81,
#: every row 0.54 to 1.01 but one of 6 polygons seen (1.36); the cloister's and the
#: office's 8 rows each 0.97 to 1.01, their totals the same.
SVBSP_TILES_EAGER = 10
#: Compiled core (constants.h): a visible piece reaching a block of the tiles' grid not
#: yet cut is cut along its middle planes as the whole grid would cut it, not kept
#: whole, where the plane through three of its vertices passes within this sine of the
#: point (relative to its farthest vertex): its image is thin, and for a polygon planar
#: only within the validation tolerance may not be convex, its shadow then the image's
#: kernel, charged by its perimeter (a bent quad seen from 1e-8 above its plane, a
#: zigzag disc seen from 1e-6 above: ``tests/test_near_planar.py``,
#: ``tests/test_long_polygons.py``).
SVBSP_THIN_IMAGE = 1e-3
#: Open scenes (exactff.remainder): the horizontal splits of one scene kept in its
#: cache, the latest used, up to this many polygons in all (rows at one height, a floor
#: grid, share one; the office's 42 heights all fit, the cloister's 80,000-polygon
#: splits six at a time: a split and its BSP tree cost about what the scene does).
REMAINDER_SPLIT_POLYGONS = 500_000
#: Open scenes, the exact method without error=True: how far below 0 a sky or ground
#: may come out and still be rounding (then set to 0): ten times the row-sum accuracy
#: target (1e-11), since a remainder is a share minus a row's sum.
REMAINDER_SLACK = 1e-10
#: check_matrix: the rounding allowed on top of the error estimates, in units of the
#: roundoff per value summed (a row's sum of N values is within N roundoffs of exact;
#: this many times that, for the values' own last roundings).
MATRIX_ROUNDING_ULPS = 4.0
#: check_matrix without error estimates: how far a row may sum from 1, and a value
#: exceed its unobstructed one (the exact method's accuracy targets: row sums and
#: occluded values within 1e-11).
MATRIX_ROW_SUM_ATOL = 1e-11
#: check_matrix without error estimates: the reciprocity defect allowed, relative to the
#: larger of A_i F_ij and A_j F_ji (testing.assert_reciprocity's default; the area
#: form factors' default tolerance).
MATRIX_RECIPROCITY_RTOL = 1e-9
#: check_matrix: a scene is closed when its vector area |sum A n| is within this share
#: of its total area (and every edge is paired): the figure `exactff info` uses.
CLOSED_RESIDUAL = 1e-12
#: audit: two polygons share an edge when an edge of each lies within this share of the
#: pair's larger diameter of the other's line and they overlap by more than it (files
#: round shared vertices alike, or within a few digits of the coordinates: far below).
AUDIT_CONTACT_RTOL = 1e-9
#: audit: a pair is near when its centroids are less than this many of the larger
#: circumradius apart: there 1/r^2 varies over the polygons by a factor of about
#: ((s + 1) / (s - 1))^2 = 4 or more, where point samples and low-order rules go wrong.
AUDIT_NEAR_SEPARATION = 3.0
#: audit: a pair is grazing when one polygon comes within this share of its diameter of
#: the other's plane (or crosses it) from its front: the horizon of every point of the
#: other, where rays and hemicube cells graze it.
AUDIT_GRAZING_RTOL = 0.05
#: reading another tool's matrix: a surface's area from its file matches its polygon's
#: within this share (View3D prints areas with %g, six digits: 5e-6 of rounding; its
#: binary files hold float32, 6e-8).
AUDIT_AREA_RTOL = 1e-5

#: View3D surfaces (exactff.combine): cuts of a polygon around its subsurfaces closer
#: than this share of its size are one cut, and pieces smaller than this share of its
#: area are left out: slivers of the booleans' rounding (a few ulps of the coordinates),
#: far below any surface a View3D file describes.
VIEW3D_REGION_RTOL = 1e-10
#: View3D's own tests of a subsurface, mask or null surface on its base (getdat.c,
#: TestSubSrf): its vertices within this share of its radius of the base's plane...
VIEW3D_IN_PLANE_RTOL = 1e-5
#: ... facing as the base (or against it, for masks and null surfaces) to this cosine...
VIEW3D_FACING_COS = 0.999
#: ... and within the base: at most this share of its area outside (View3D's overlap
#: test takes 1e-6 of the square root of the area as its tolerance).
VIEW3D_WITHIN_RTOL = 1e-6
#: View3D clamps emissivities to this range (getdat.c, with a warning): its script-F
#: factors divide by 1 - emissivity.
VIEW3D_EMISSIVITY_RANGE = (0.001, 0.999)
#: View3D sets F 3a vertex coordinates below this magnitude to 0 (getdat.c, SetPlane):
#: the rounding of cos(90 degrees) and its kin; exactff does the same, to read the same
#: vertices.
VIEW3D_ZERO_COORDINATE = 1e-14

#: Area form factors, the closed form of the contour integral: its rounding, in units of
#: EPS of the magnitudes of its terms (each edge pair's triangle terms over |e x f|, or
#: the parallel form's four corner terms, times |e . f|, summed; a logarithm counted by
#: its factor, its rounding being absolute). Measured against mpmath: at most 0.9 units
#: on 700 random edge pairs of every kind (skew, crossing, sharing a vertex, collinear,
#: parallel, 1e-8 from parallel), 0.2 on Howell's catalogue cases; 4 leaves a margin of 4.
AREA_CLOSED_ULPS = 4.0

#: Area form factors, the closed form: edges within this sine of parallel are also taken
#: by the parallel form, the shorter edge turned onto the longer's direction, with the
#: bound of that turn, 4 q (1 + ln(1 + 1 / 2 q)) for q = |e x f| / max(|e|, |f|)^2
#: (``exactff/_core/closed_form.cpp``), and the form of the smaller estimate kept: the
#: skew form's terms grow as 1 / sin (edges parallel but for their vertices' rounding,
#: a sine of 3e-17: terms of 1e18), the bound as sin ln(1 / sin); for edges of about
#: unit length and distance they cross near a sine of 3e-8 (estimates of 5e-7 there),
#: well inside this.
AREA_CLOSED_NEAR_PARALLEL = 1e-6

#: Area form factors, the closed form: the relative target of its estimate, and the
#: floor of the values it is relative to (a share of the emitter's hemisphere); where the
#: estimate misses it, the far-field rule (far pairs) or mpmath takes over.
AREA_CLOSED_RTOL = 1e-13
AREA_CLOSED_FLOOR = 1e-3

#: Area form factors, the closed form's mpmath escalation: its first working precision
#: (decimal digits; doubled while the estimate misses), and its rounding in units of
#: that precision of the terms' magnitudes (as AREA_CLOSED_ULPS for the floats, with
#: the margin of mpmath's functions' last digits).
AREA_CLOSED_MP_DPS = 30
AREA_CLOSED_MP_ULPS = 64.0

