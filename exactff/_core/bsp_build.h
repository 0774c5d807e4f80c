// The BSP tree of a scene (the autopartition of exactff.visibility.bsp.build_bsp, with
// its crossings in quadruple precision or exactly): bsp_build.cpp.

#ifndef EXACTFF_CORE_BSP_BUILD_H
#define EXACTFF_CORE_BSP_BUILD_H

#include <cstddef>
#include <cstdint>
#include <vector>

namespace exactff {

// The tree as arrays: node normals (3 M) and offsets (M), front and back children (-1 for
// none), each node's fragments (here_start (M + 1) into here), and the fragments the
// nodes hold, renumbered in node order: vertices (3 N), starts (F + 1), source polygons
// (F), whether each is its source polygon uncut (F), the number of splits, and per
// vertex a bound on its distance from the exact point it stands for (N): 0 for the
// input's, else a crossing's (Builder::crossing).
struct BspArrays {
    std::vector<double> node_n, node_d;
    std::vector<int64_t> front, back, here_start, here;
    std::vector<double> live_verts;
    std::vector<int64_t> live_start, live_source;
    std::vector<uint8_t> whole;
    int64_t splits = 0;
    std::vector<double> live_err;
};

// The tree of the n polygons V (vertices, polygon i at start[i] .. start[i + 1]) with
// their planes (normals (3 n), offsets (n)): up to `candidates` planes scored at a node,
// on a sample of `sample` fragments; a node of at least axis_min fragments left more
// unbalanced than axis_imbalance also tries its median plane; band_ulps the
// near-coplanar band; a crossing within `snap` machine epsilons of an edge's end is that
// end; seed the random streams'.
BspArrays build_bsp(const double* V, const int64_t* start, int64_t n, const double* normals,
                    const double* offsets, size_t candidates, size_t sample, size_t axis_min,
                    double axis_imbalance, double band_ulps, double snap, uint64_t seed);

}  // namespace exactff

#endif
