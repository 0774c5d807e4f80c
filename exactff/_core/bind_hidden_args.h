// What the two bindings that call the hidden parts share (bind_hidden.cpp's
// hidden_pieces and bind_pair.cpp's adaptive_levels): the receiver's frame, the
// blockers and Q's convex parts of a HiddenArgs (hidden.h) taken from their arrays, with
// their shapes checked. No math.

#ifndef EXACTFF_CORE_BIND_HIDDEN_ARGS_H
#define EXACTFF_CORE_BIND_HIDDEN_ARGS_H

#include <stdexcept>
#include <string>

#include "bind_arrays.h"
#include "hidden.h"

namespace exactff {
namespace bind {

// h's geometry from the arrays (which must outlive h): the pyramid's base (corners
// (c, 3)), Q's plane (q0, nQ (3,), RQ: its first two rows, (2, 3) or (3, 3)), the
// blockers (b, k, 3) with their vertex counts, unit normals (b, 3) and solids (b,), Q's
// convex parts (q, k, 2) with their counts, the receiving frame (3, 3) and Q's extent;
// `who` names the caller in the error
inline void set_hidden_geometry(HiddenArgs& h, const char* who, const Array<double>& corners,
                                const Array<double>& q0, const Array<double>& nQ,
                                const Array<double>& RQ, const Array<double>& blockers,
                                const Array<long long>& counts, const Array<double>& normals,
                                const Array<long long>& groups, const Array<double>& parts,
                                const Array<long long>& part_counts, const Array<double>& frame,
                                double extent) {
    if (corners.ndim() != 2 || corners.shape(1) != 3 || q0.size() != 3 || nQ.size() != 3 ||
        RQ.size() < 6 || blockers.ndim() != 3 || blockers.shape(2) != 3 ||
        counts.size() != blockers.shape(0) || normals.size() != 3 * blockers.shape(0) ||
        groups.size() != blockers.shape(0) || parts.ndim() != 3 ||
        part_counts.size() != parts.shape(0) || frame.size() != 9)
        throw std::invalid_argument(std::string(who) + ": arrays of the wrong shapes");
    h.corners = corners.data();
    h.n_corners = corners.shape(0);
    h.q0 = q0.data();
    h.nQ = nQ.data();
    h.RQ = RQ.data();
    h.blockers = blockers.data();
    h.n_blockers = blockers.shape(0);
    h.blocker_stride = blockers.shape(1);
    h.counts = counts.data();
    h.normals = normals.data();
    h.groups = groups.data();
    h.parts = parts.data();
    h.n_parts = parts.shape(0);
    h.part_stride = parts.shape(1);
    h.part_counts = part_counts.data();
    h.frame = frame.data();
    h.extent = extent;
}

}  // namespace bind
}  // namespace exactff

#endif
