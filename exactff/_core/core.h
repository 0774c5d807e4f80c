// The visibility core: one row of exact occluded form factors from a point p.
//
// A BSP tree of convex fragments (built by exactff.visibility.bsp, convexified by
// exactff.visibility.compiled) gives the fragments front to back from p. The covered
// region is a shadow-volume BSP tree (shadow_tree.h): each fragment is filtered down the
// tree; the parts reaching free leaves are visible: they are integrated with the sector
// form (Lambert), or with the paper's Eq. 3 in its stable form (a row's choice), and the
// leaf is replaced by the planes through p and their edges (their shadow volume).
// Splitting convex pieces by planes needs no polygon booleans, and the topology follows
// from one sign per vertex and plane.
//
// Before a BSP subtree is entered, the conic hull of its bounding box's corners is
// filtered down the shadow tree: a subtree whose box is wholly covered is skipped
// without touching its fragments (hierarchical occlusion culling), so that the cost of a
// row follows what it sees.
//
// Arithmetic is in long double (x87 80-bit where the platform has it). Every vertex
// carries a bound on the error of its direction (radians); every plane a bound on its
// tilt. A piece's value is bounded by the rounding of its sector sum plus, for each edge,
// its arc length times the larger of its end points' bounds over pi. The Python wrapper
// checks those bounds against the tolerance and falls back to the Python engine where
// they miss it.
//
// Where each part lives: core.cpp (the constructor and the row's set-up and results),
// culling.cpp (the subtrees' boxes, the hierarchical culling and the cube map of cells
// proven covered), shadow_tree.cpp (the
// shadow tree's operations and exact tests), pieces.cpp (the piece loop: the front-to-back
// walk and each fragment's filtering), integrate.cpp (a visible piece's sector sum, long
// double and quadruple precision), bounds.cpp (the vertices' error charges and the
// quadruple-precision refinement).

#ifndef EXACTFF_CORE_CORE_H
#define EXACTFF_CORE_CORE_H

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstring>
#include <memory>
#include <type_traits>
#include <utility>
#include <vector>

#include "precision.h"
#include "predicates.h"
#include "shadow_tree.h"
#include "vec.h"

namespace exactff {

using TileNormals = std::vector<std::array<double, 3>>;

struct EdgeKey {
    R c[6];
    bool operator==(const EdgeKey& o) const {
        for (int i = 0; i < 6; ++i)
            if (c[i] != o.c[i]) return false;
        return true;
    }
};
struct EdgeKeyHash {
    size_t operator()(const EdgeKey& k) const {
        size_t h = 1469598103934665603ull;
        for (int i = 0; i < 6; ++i) {
            double d = static_cast<double>(k.c[i]);
            uint64_t bits;
            std::memcpy(&bits, &d, sizeof bits);
            h = (h ^ bits) * 1099511628211ull;
        }
        h ^= h >> 29;  // the low bits index the tables: every bit mixed into them
        h *= 0xBF58476D1CE4E5B9ull;
        return h ^ (h >> 32);
    }
};
// a table by EdgeKey (the row's edge charges, Core::charge_edges; the held pieces'
// edges, Core::settle): open addressing on the keys' hashes (linear probing, a
// power-of-two capacity at most half full), the entries in one vector in the order
// they came, so that a lookup allocates nothing and the row's sums over them follow
// one fixed order
template <class T>
class KeyTable {
  public:
    struct Entry {
        EdgeKey key;
        T value;
    };
    // the value under k, or nullptr
    T* find(const EdgeKey& k) {
        if (slots_.empty()) return nullptr;
        const uint64_t h = EdgeKeyHash()(k);
        for (size_t i = h & (slots_.size() - 1);; i = (i + 1) & (slots_.size() - 1)) {
            const Slot& s = slots_[i];
            if (s.generation != generation_) return nullptr;
            if (s.hash == h && entries_[s.index].key == k) return &entries_[s.index].value;
        }
    }
    // empty, its capacity kept (the slots of earlier generations read as empty)
    void clear() {
        entries_.clear();
        if (++generation_ == 0) {  // wrapped: the old marks could read as current
            std::fill(slots_.begin(), slots_.end(), Slot{0, 0, 0});
            generation_ = 1;
        }
    }
    // the value under k, inserted as `fresh` if absent
    T& emplace(const EdgeKey& k, const T& fresh) {
        if (T* v = find(k)) return *v;
        if (2 * (entries_.size() + 1) > slots_.size()) grow();
        place(EdgeKeyHash()(k), static_cast<uint32_t>(entries_.size()));
        entries_.push_back({k, fresh});
        return entries_.back().value;
    }
    const std::vector<Entry>& entries() const { return entries_; }
    // what its entries take, with their slots (at most half full)
    size_t bytes() const { return entries_.size() * (sizeof(Entry) + 2 * sizeof(Slot)); }

  private:
    struct Slot {
        uint64_t hash;
        uint32_t index;
        uint32_t generation;  // the slot is taken in the current generation only
    };
    void place(uint64_t h, uint32_t index) {
        size_t i = h & (slots_.size() - 1);
        while (slots_[i].generation == generation_) i = (i + 1) & (slots_.size() - 1);
        slots_[i] = {h, index, generation_};
    }
    void grow() {
        slots_.assign(slots_.empty() ? 1 << 10 : 2 * slots_.size(), Slot{0, 0, 0});
        for (size_t j = 0; j < entries_.size(); ++j)
            place(EdgeKeyHash()(entries_[j].key), static_cast<uint32_t>(j));
    }
    std::vector<Slot> slots_;
    std::vector<Entry> entries_;
    uint32_t generation_ = 1;
};

struct EdgeCharge {
    int64_t src;
    R charge;
    int count;
    bool refined;  // its ends' directions from Core::refine (quadruple precision)
    R geo = 0;     // the part the input's own errors make (Vertex::gerr), held apart
};

// the row's cache of exact tests of an input point against an exact plane, by ids:
// open addressing (linear probing, power-of-two capacity, at most half full), one probe
// run and no allocation per test in the usual case
class PointCache {
  public:
    // -1: not decided yet; else whether the point is on the plane
    int find(int64_t a, int64_t b, int64_t x) const {
        if (keys_.empty()) return -1;
        for (size_t i = slot(a, b, x);; i = (i + 1) & (keys_.size() - 1)) {
            const Key& k = keys_[i];
            if (k.generation != generation_) return -1;
            if (k.a == a && k.b == b && k.x == x) return k.on;
        }
    }
    // what its tests take (the slots at most half full)
    size_t bytes() const { return 2 * used_ * sizeof(Key); }
    void insert(int64_t a, int64_t b, int64_t x, bool on) {
        if (2 * (used_ + 1) > keys_.size()) grow();
        size_t i = slot(a, b, x);
        while (keys_[i].generation == generation_) i = (i + 1) & (keys_.size() - 1);
        keys_[i] = {a, b, x, on ? 1 : 0, generation_};
        ++used_;
    }
    // empty, its capacity kept (the keys of earlier generations read as empty)
    void clear() {
        used_ = 0;
        if (++generation_ == 0) {
            std::fill(keys_.begin(), keys_.end(), Key{0, 0, 0, 0, 0});
            generation_ = 1;
        }
    }

  private:
    struct Key {
        int64_t a, b, x;
        int32_t on;
        uint32_t generation;  // taken in the current generation only
    };
    size_t slot(int64_t a, int64_t b, int64_t x) const {
        uint64_t h = static_cast<uint64_t>(a) * 0x9E3779B97F4A7C15ull;
        h ^= static_cast<uint64_t>(b) + 0x632BE59BD9B4E019ull + (h << 6) + (h >> 2);
        h ^= static_cast<uint64_t>(x) * 0xC2B2AE3D27D4EB4Full;
        h ^= h >> 29;
        h *= 0xBF58476D1CE4E5B9ull;
        h ^= h >> 32;
        return static_cast<size_t>(h) & (keys_.size() - 1);
    }
    void grow() {
        std::vector<Key> old = std::move(keys_);
        keys_.assign(old.empty() ? 1 << 12 : 2 * old.size(), Key{0, 0, 0, 0, 0});
        used_ = 0;
        for (const Key& k : old)
            if (k.generation == generation_) insert(k.a, k.b, k.x, k.on != 0);
    }
    std::vector<Key> keys_;
    size_t used_ = 0;
    uint32_t generation_ = 1;
};

// a part of the hemisphere a shadow leaves uncovered: within `radius` of direction c,
// worth at most `charge` of any piece behind it
struct Leak {
    V3 c;
    R radius, charge;
};

struct RowStats {
    // exact tests of input points against planes through p already decided this row
    // (the same mesh vertex and edge recur in every fragment that shares them)
    PointCache on_plane;
    // exact tests of a crossing (an input edge's with an exact plane) against another
    // exact plane already decided this row, by the three's identities (Core::exactly_on)
    PointCache on_crossing;
    // the vertex-error charges of visible pieces' edges with a computed end, by edge:
    // an edge two visible pieces of one polygon share cancels (the two pieces' sums
    // carry it with opposite signs); the rest is charged at the end of the row
    KeyTable<EdgeCharge> edges;
    // what the shadows leave uncovered (Core::leave_out) and their omitted sides may
    // hide, charged to every receiving polygon
    R unattributed = 0;
    // shadows left out: < 3 vertices, a side the piece straddles, a kernel worth more
    // than the piece, < 3 sides
    int64_t slivers[4] = {0, 0, 0, 0};
    // the cube map of directions about p (Core::footprint): per cell, whether it is
    // proven covered (Core::cell_covered), and the shadow tree's size when a proof last
    // failed (it is tried again only once the tree has grown)
    std::vector<uint8_t> cover;
    std::vector<int32_t> cover_tried;
    int64_t cover_proofs = 0, cover_cells = 0, cover_visits = 0, fragments_covered = 0,
            subtrees_covered = 0;
    int64_t fragments_behind = 0;  // fragments skipped clearly behind the tangent plane
                                   // (Core::behind_horizon)
    // the normals of the tiles' planes, tiles[below][axis] (above the horizon or below
    // it; along u or v: Core::tile_normals), and the grid's planes placed where pieces
    // needed them (Core::grow_tile)
    TileNormals tiles[2][2];
    int64_t tiles_cut = 0;
    int64_t collapsed = 0;      // shadow-tree nodes whose two sides were both covered
    int64_t repeated_sides = 0;  // shadows' sides along a plane on their leaf's path
                                 // (Core::drop_repeated_sides)
    bool covered = false;       // every direction the row sees covered: the walk stops
    bool cull = true;           // the shortcuts (Exact(shortcuts=...)); here, whether the
                                // repeated sides are left out (Core::drop_repeated_sides)
    int64_t kernels = 0;        // non-convex images whose kernel is their shadow
    int64_t omitted_sides = 0;  // shadows with a short side left out
    // uncovered parts worth more than the row's budget for unattributed charges
    // (Core::leave_out), and that budget
    std::vector<Leak> leaks;
    R leak_budget = 0;
    R rtol = 0;          // pieces whose bound exceeds this times their value are
                         // integrated again in quadruple precision (0: never), unless
                         // their polygon's bound is within half rtol times floor
    R floor = 0;         // the value below which a bound is held to rtol times it, not
                         // to rtol times the value (Core::settle; 0: relative throughout)
    const double* normal = nullptr;  // the receiver normal as given
    const double* point = nullptr;   // the point as given
    const std::vector<ExactPlane>* xp = nullptr;  // the row's exact planes (Core::run)
    // integrate with Eq. 3's stable form instead of the sector form, in the frame
    // (e1, e2, n) (Core::integrate)
    bool eq3 = false;
    V3 e1{0, 0, 0}, e2{0, 0, 0};
    // the whole sphere of directions (both sides of the horizon free, no culling behind
    // it), each visible piece measured by its solid angle over pi (Core::integrate_solid)
    bool sphere = false;
    int64_t quad_pieces = 0;
    // with rtol > 0, the pieces whose own bound exceeds rtol times their value, held
    // until the row's end, where the second tier is decided per polygon (Core::settle)
    struct Held {
        Piece q;
        int64_t f;
        R val, bnd;
        std::vector<R> arcs;  // its edges' arc lengths (Core::charge_edges)
    };
    std::vector<Held> held_pieces;
    int64_t pieces_held = 0, held_bytes = 0;  // pieces so held, and their memory
    int64_t fragments = 0, visible = 0, hidden = 0, splits = 0, subtrees_culled = 0,
            fragments_culled = 0, box_tests = 0, shadow_planes = 0,
            node_visits = 0,   // shadow-tree nodes a piece was classified at
            near_tests = 0,    // vertices within the band of such a plane
            exact_tests = 0;   // exact tests of an input point decided (not cached)
    int64_t held = 0, held_peak = 0;  // vertices in the filter's work list, now and at most
    int64_t working_bytes = 0;  // the row's own containers at their largest (Core::run)
    // per polygon, the charges of its visible pieces' edges that the input's own errors
    // make (BSP crossings, Vertex::gerr): reported apart from the computation's bound
    std::vector<R> crossing;
};

// the row's results: values, bounds (the computation's, the near-coplanar band's, the
// input's rounded crossings'), one per polygon, and the row's counters
struct RowResult {
    std::vector<double> F, E, B, G;
    RowStats stats;
};

// a visible piece's value plus its bound (Core::piece_worth), once known
struct PieceWorth {
    R value;
    bool known;
};

// a corner of a piece in the filter's work list: a vertex (an index into the
// fragment's vertices and crossings) and the edge to the next corner (Vertex::edge)
struct Corner {
    int32_t v;
    int64_t edge;
};

// an allocator whose emplace_back() with no arguments default-initialises (a vertex
// made in place, Core::crossing, writes every field: its value-initialisation would
// first clear its 200 bytes)
template <class T>
struct DefaultInit : std::allocator<T> {
    template <class U>
    struct rebind {
        using other = DefaultInit<U>;
    };
    DefaultInit() = default;
    template <class U>
    DefaultInit(const DefaultInit<U>&) noexcept {}
    template <class U>
    void construct(U* p) noexcept(std::is_nothrow_default_constructible<U>::value) {
        ::new (static_cast<void*>(p)) U;
    }
    template <class U, class... A>
    void construct(U* p, A&&... a) {
        ::new (static_cast<void*>(p)) U(std::forward<A>(a)...);
    }
};

// the filter's work list (Core::process): the fragment's vertices and the crossings
// made so far, the pieces waiting (each a run of corners on one stack, with the link,
// plane and branch, it arrived by) and each step's scratch, reused by every fragment
struct Filter {
    struct Item {
        size_t begin;  // its corners run from here to the next item's (or the end)
        int plane;
        bool positive;
    };
    std::vector<Vertex, DefaultInit<Vertex>> pool;
    Piece piece;  // a visible piece, its corners' vertices with their edges
    std::vector<Corner> corners, cur;
    std::vector<Item> items;
    std::vector<int> sg;
    std::vector<R> d, arcs;
    std::vector<int32_t> cut;
    size_t pool_peak = 0;  // the most vertices one fragment's pieces took this row
};

// the containers of a row that grow with it (Core::run): its shadow tree, exact planes,
// the filter's work list and its tables, kept per thread from row to row. One per
// thread, so a row is not re-entrant: Core::run must not be called again on the same
// thread while a row runs (nothing in a row calls back into Python or into another row;
// rows on different threads, as jobs= runs them, each have their own)
struct RowScratch {
    std::vector<Plane> sv;
    std::vector<ExactPlane> xp;
    Filter work;
    KeyTable<EdgeCharge> edges;
    PointCache on_plane, on_crossing;
};

class Core {
  public:
    // the fragments' vertices (3 V doubles) and their errors (V), each fragment's start,
    // count and source polygon, the BSP nodes' children, fragments (here_start into
    // here_front) and fragments behind (here_behind), the number of polygons, the band,
    // the sector sums' C1 and C2 and the split vertices' rounding (exactff._tolerances)
    Core(std::vector<double> vertices, std::vector<int64_t> start, std::vector<int64_t> count,
         std::vector<int64_t> source, std::vector<int64_t> front, std::vector<int64_t> back,
         std::vector<int64_t> here_start, std::vector<int64_t> here_front,
         std::vector<int64_t> here_behind, int64_t n_sources, double band, double c1, double c2,
         double split, std::vector<double> vertex_errors);

    // one row from point (3,) with normal (3,), given each BSP node's side of the point
    // (+1 front, -1 back; even, 0 or +-2, where the node's own fragments come first:
    // exactff.visibility.bsp.node_sides)
    // and each polygon's (+1 front, -1 back, 0 on)
    RowResult row(const double* point, const double* normal, const int8_t* node_side,
                  const int8_t* source_side, bool two_sided, bool cull, int64_t box_budget,
                  int64_t tiles, double rtol, double floor, bool eq3,
                  bool sphere = false) const;
    int64_t n_sources() const { return n_sources_; }
    int64_t nodes() const { return static_cast<int64_t>(front_.size()); }
    int64_t pieces() const { return static_cast<int64_t>(start_.size()); }
    double unit_roundoff() const { return static_cast<double>(K_.eps); }

  private:
    int64_t n_sources_;
    std::vector<double> V_;
    std::vector<double> VE_;  // per input point, a bound on its distance from the exact one
    std::vector<int64_t> uid_;  // distinct input point of each vertex
    std::vector<int64_t> start_, count_, source_, front_, back_, here_start_, here_front_,
        here_behind_;
    std::vector<double> lo_, hi_;
    std::vector<int64_t> size_;
    Constants K_;
    // culling.cpp
    struct Footprint {
        int face, i0, i1, j0, j1;  // cells [i0, i1] x [j0, j1] of one face
    };
    static bool footprint(const double (*dirs)[3], const double* margin, size_t n,
                          Footprint* out);
    bool fragment_footprint(int64_t f, const double* pp, Footprint* out) const;
    struct BoxCorners {
        double c[8][3];  // the corners (input doubles)
        R v[8][3];       // their differences from p
        R length[8];     // and those differences' lengths
    };
    void box_corners(int64_t k, const double* pp, BoxCorners* out) const;
    bool box_footprint(const BoxCorners& b, const double* pp, Footprint* out) const;
    static bool all_covered(const Footprint& fp, const RowStats& st);
    bool cell_covered(const std::vector<Plane>& sv, const std::vector<ExactPlane>& xp,
                      int face, int i, int j, RowStats& st) const;
    void prove_cells(const Footprint& fp, const std::vector<Plane>& sv,
                     const std::vector<ExactPlane>& xp, RowStats& st) const;
    void build_boxes();
    bool box_behind(const BoxCorners& b, const double* pp, const double* pn) const;
    bool box_hidden(const std::vector<Plane>& sv, int64_t k, const BoxCorners& b, const V3& p,
                    int64_t budget) const;
    // shadow_tree.cpp
    static int side(const Plane& P, const Vertex& x, const Constants& K, R* d_out);
    static void tile_normals(const double* pn, int64_t tiles, TileNormals& xs, TileNormals& ys);
    Plane tile_plane(const TileBlock& b, bool along_x, const RowStats& st) const;
    int place_tile(Plane P, std::vector<Plane>& sv, std::vector<ExactPlane>& xp) const;
    int cut_tiles(int leaf, std::vector<Plane>& sv, std::vector<ExactPlane>& xp,
                  const RowStats& st) const;
    static bool thin_image(const Filter& work);
    int grow_tile(int leaf, int plane, bool positive, const Filter& work, std::vector<Plane>& sv,
                  std::vector<ExactPlane>& xp, RowStats& st) const;
    static Expansion exact_value(const ExactPlane& X, const double* p, const double* x);
    static bool same_plane(const ExactPlane& P, const ExactPlane& Q);
    bool point_on_plane(const ExactPlane& Q, const double* p, const double* x, int64_t ux,
                        RowStats& st) const;
    bool exactly_on(std::vector<ExactPlane>& xp, int k, const double* p, int64_t f,
                    const Vertex& u, RowStats& st) const;
    bool exactly_on_input(const ExactPlane& Q, const double* p, const double* x) const;
    bool crossing_on(const ExactPlane& P, const ExactPlane& Q, const double* p, int64_t ia,
                     int64_t ib) const;
    static V3 input_plane(const double* p, const double* a, const double* b);
    // (`worth`: the piece's value and bound, computed where a shadow left out needs
    // them if not known, Core::piece_worth; `n` the receiver normal, for that)
    bool insert_shadow(const Piece& q, int64_t f, const double* pp, int plane, bool positive,
                       std::vector<Plane>& sv, std::vector<ExactPlane>& xp, RowStats& st,
                       PieceWorth& worth, const V3& n) const;
    static void drop_repeated_sides(int plane, bool positive, const std::vector<Plane>& sv,
                                    const std::vector<ExactPlane>& xp, std::vector<Plane>& chain,
                                    std::vector<size_t>& chain_edge, RowStats& st);
    static void adopt(std::vector<Plane>& sv, size_t first);
    static void attach(std::vector<Plane>& sv, int plane, bool positive, int child,
                       size_t first, RowStats& st);
    void leave_out(const Piece& q, R charge, int why, RowStats& st) const;
    static V3 direction_sum(const Piece& q);
    Leak cone(const Piece& q) const;
    R leaked(const Piece& q, R worth, const RowStats& st) const;
    int long_shadow(const Piece& q, const double* pp, const std::vector<Plane>& chain,
                    const std::vector<size_t>& chain_edge, std::vector<Plane>& sv,
                    std::vector<ExactPlane>& xp, RowStats& st) const;
    // pieces.cpp
    V3 between(const Vertex& a, const Vertex& b, int64_t f, R* scale) const;
    void crossing(const Plane& P, const Vertex& x, const Vertex& y, R dx, R dy, R* t,
                  Vertex& c) const;
    static bool lex_less(const V3& x, const V3& y);
    static R arc(const Vertex& a, const Vertex& b);
    static R arc_bound(const Vertex& a, const Vertex& b);
    void run(const double* pp, const double* pn, const int8_t* node_side,
             const int8_t* source_side, bool two_sided, bool cull, int64_t budget,
             int64_t tiles, std::vector<R>& F, std::vector<R>& E, std::vector<R>& B,
             RowStats& st) const;
    void process(int64_t f, const double* pp, const V3& p, const V3& n,
                 const int8_t* source_side, bool two_sided, std::vector<Plane>& sv,
                 std::vector<ExactPlane>& xp, Filter& work, std::vector<R>& F,
                 std::vector<R>& E, std::vector<R>& B, RowStats& st) const;
    // bounds.cpp
    static R turn_bound(R ratio);
    R input_error(int64_t i, R length) const;
    R input_tilt(int64_t ia, int64_t ib, const double* pp) const;
    static R measured_off(const Quad m[3], Quad ml, Quad cond, const std::array<Quad, 3>& x);
    static R rough_length(const Quad x[3]);
    // (without `record`, `keyed` receives the edges it would key, with their charges;
    // `arcs`, the edges' arc lengths: computed into it where it is short, else read;
    // `f`, the piece's fragment, where its edges' planes' input tilts may be asked for)
    R charge_edges(const Piece& q, int64_t src, std::vector<R>& E, RowStats& st,
                   const std::vector<R>* refined = nullptr, bool record = true,
                   std::vector<std::pair<EdgeKey, R>>* keyed = nullptr,
                   std::vector<R>* arcs = nullptr, int64_t f = -1) const;
    R edge_tilt(int64_t code, int64_t f, const RowStats& st) const;
    void quad_plane(int64_t code, int64_t f, const double* pp, const std::vector<ExactPlane>& xp,
                    Quad m[3], Quad* cond) const;
    void refine(const Piece& q, int64_t f, const double* pp, const std::vector<ExactPlane>& xp,
                std::vector<std::array<Quad, 3>>& v, std::vector<R>& err) const;
    bool behind_horizon(int64_t f, const V3& p, const Plane& H) const;
    void piece_value(const Piece& q, int64_t f, const V3& n, const RowStats& st, R* val,
                     R* bnd) const;
    R piece_worth(const Piece& q, int64_t f, const V3& n, const RowStats& st,
                  PieceWorth& w) const;
    // integrate.cpp
    void integrate(const Piece& q, int64_t f, const V3& n, R* value, R* bound,
                   const RowStats* eq3 = nullptr) const;
    void integrate_quad(const std::vector<std::array<Quad, 3>>& v, const double* pn, R* value,
                        R* bound, bool eq3 = false) const;
    void integrate_solid(const Piece& q, int64_t f, R* value, R* bound) const;
    void settle(const double* pp, const std::vector<ExactPlane>& xp, std::vector<R>& F,
                std::vector<R>& E, RowStats& st) const;
};

}  // namespace exactff

#endif
