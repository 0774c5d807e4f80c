// The shadow-volume BSP tree of the visibility core (Chin & Feiner 1989): a BSP tree of
// planes through the point p whose leaves are covered (IN) or free (OUT, or a block of
// the tiles' grid not yet cut, <= LAZY: free too); its root is
// the horizon plane. Its nodes (Plane), the vertices of the convex pieces filtered down
// it (Vertex, Piece), each with its error bound, and the core's rounding constants
// (Constants). The tree's operations are Core's (shadow_tree.cpp: side, the tiles,
// insert_shadow and the exact tests of a vertex against a plane).

#ifndef EXACTFF_CORE_SHADOW_TREE_H
#define EXACTFF_CORE_SHADOW_TREE_H

#include <cfloat>
#include <cmath>
#include <cstdint>
#include <vector>

#include "constants.h"
#include "precision.h"
#include "vec.h"

namespace exactff {

constexpr int OUT = -1;  // a free leaf of the shadow tree
constexpr int IN = -2;   // a covered leaf
// a free leaf that is a block of the tiles' grid not yet cut (Core::grow_tile): LAZY
// less its code, the grid's planes still to place along each axis, [x0, x1) and
// [y0, y1) (TILE_BITS each: at most 63 tiles), and whether it is below the horizon
constexpr int LAZY = -3;
constexpr int TILE_BITS = 6;
struct TileBlock {
    int x0, x1, y0, y1, below;
};
inline int tile_leaf(const TileBlock& b) {
    if (b.x0 >= b.x1 && b.y0 >= b.y1) return OUT;  // one cell: nothing left to cut
    return LAZY - (b.x0 | b.x1 << TILE_BITS | b.y0 << 2 * TILE_BITS | b.y1 << 3 * TILE_BITS |
                   b.below << 4 * TILE_BITS);
}
inline TileBlock tile_block(int leaf) {
    const int c = LAZY - leaf, mask = (1 << TILE_BITS) - 1;
    return {c & mask, (c >> TILE_BITS) & mask, (c >> 2 * TILE_BITS) & mask,
            (c >> 3 * TILE_BITS) & mask, (c >> 4 * TILE_BITS) & 1};
}
// a free leaf, cut or not
inline bool is_free(int node) { return node == OUT || node <= LAZY; }

struct Vertex {
    V3 v;       // its direction from p (not normalised): an input vertex's position less
                // p (a computed vertex's differences come from its anchor or its
                // direction, see Core::between)
    R length;   // |v|
    R err;      // bound on the error of its direction, radians
    int64_t id; // index of an input vertex (its coordinates exact), or -1: computed
    int64_t on_edge, on_plane;  // a computed vertex where input edge on_edge (the
                                // input vertex it starts from) crosses exact plane
                                // on_plane, or -1
    int64_t edge;  // the edge to the next vertex: on input edge id (>= 0: the input
                   // vertex it starts from) or on exact plane -1 - k
    R t = 0;       // with on_edge: its parameter along that input edge
    R err_line = 0;  // with on_edge: bound on its direction's error off that edge's
                     // plane through p (its error along the edge moves no boundary)
    double vd[3] = {0, 0, 0};  // v, length and err rounded to double: the
    double lengthd = 0;        // classification's filter (see Core::process)
    double errd = 0;
    R gerr = 0;  // bound on the angle off the planes of its two edges that the input's
                 // own errors add (a BSP crossing is rounded): the geometry's, not the
                 // computation's, so it moves values (Core::charge_edges), not decisions
};

inline void set_double(Vertex& u) {
    u.vd[0] = static_cast<double>(u.v.x);
    u.vd[1] = static_cast<double>(u.v.y);
    u.vd[2] = static_cast<double>(u.v.z);
    u.lengthd = static_cast<double>(u.length);
    u.errd = static_cast<double>(u.err);
}
using Piece = std::vector<Vertex>;

struct Plane {  // m . x = 0 through p; positive side first
    V3 m;
    R mnorm;
    R err;      // bound on its tilt, radians
    int pos, neg;
    int exact;  // the exact plane it is (ExactPlane index)
    int orient; // +1 or -1: m's orientation against the exact plane's
    R slack = 0;  // the widest sliver decided against it so far: the covered region
                  // next to it is uncertain by that much for every later piece
    double md[3] = {0, 0, 0};  // m and mnorm rounded to double, for the filter
    double mnormd = 0;
    int parent = -1;  // the node whose child this one is (-1: the root)
};

inline void set_double(Plane& P) {
    P.md[0] = static_cast<double>(P.m.x);
    P.md[1] = static_cast<double>(P.m.y);
    P.md[2] = static_cast<double>(P.m.z);
    P.mnormd = static_cast<double>(P.mnorm);
}

// the double filter of a direction against a plane: P.m . u.v in double is off its long
// double value by at most SVBSP_FILTER_ROUNDOFFS double roundoffs of |m| |v| (the
// roundings to double, the products and sums), so a direction beyond `width` (radians,
// the plane's band and errors) plus its own error by more than that is on the side of
// its sign: +1 or -1, else 0 (its long double distance decides)
inline int filtered_side(const Plane& P, const Vertex& u, double width) {
    const double dd = P.md[0] * u.vd[0] + P.md[1] * u.vd[1] + P.md[2] * u.vd[2];
    if (std::fabs(dd) > (width + u.errd + SVBSP_FILTER_ROUNDOFFS * DBL_EPSILON) *
                            (P.mnormd * u.lengthd) * (1 + 8 * DBL_EPSILON))
        return dd > 0 ? 1 : -1;
    return 0;
}

struct Constants {
    R eps;      // unit roundoff of R
    R band;     // relative band of "on the plane" (radians)
    R c1;       // rounding constants of a sector sum (the Python kernel's C1, C2)
    R c2;
    R split;    // rounding of a split vertex, in units of eps
};

}  // namespace exactff

#endif
