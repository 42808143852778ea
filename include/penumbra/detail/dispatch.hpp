// penumbra — dispatch-grid arithmetic (pure C++, unit-tested without a context).
//
// GL only guarantees 65 535 work groups per dimension, so a 1D problem of G groups is dispatched
// as an (x, y) grid with x <= 65 535 and x * y >= G; shaders recover the linear group id with
// penumbraLinearGroup() (shaders/penumbra/common/dispatch.glsl) and skip ids >= G.
#ifndef PENUMBRA_DETAIL_DISPATCH_HPP
#define PENUMBRA_DETAIL_DISPATCH_HPP

#include "penumbra/error.hpp"

#include <cstdint>

namespace penumbra::detail {

inline constexpr uint64_t kMaxGroupsPerDimension = 65535u;  // == PENUMBRA_MAX_GROUPS_PER_DIMENSION

/// ceil(n / d) without overflow; d > 0.
inline constexpr uint64_t divUp(uint64_t n, uint64_t d) { return n / d + (n % d != 0); }

struct DispatchGrid {
    uint32_t x = 0, y = 0;  ///< x * y >= groups, x <= max_x, y <= max_y; (0, 0) for no work
    uint64_t groups = 0;    ///< the real number of groups
};

/// Folds `groups` into a 2D grid. `max_x`/`max_y` default to the GL minimum maxima; pass the
/// driver's GL_MAX_COMPUTE_WORK_GROUP_COUNT values to use more. Throws penumbra::Error when
/// the grid cannot hold the groups.
inline DispatchGrid foldDispatch(uint64_t groups, uint64_t max_x = kMaxGroupsPerDimension,
                                 uint64_t max_y = kMaxGroupsPerDimension) {
    PENUMBRA_CHECK(max_x > 0 && max_y > 0, "penumbra: dispatch limits must be positive");
    DispatchGrid grid;
    grid.groups = groups;
    if (groups == 0) return grid;
    uint64_t y = divUp(groups, max_x);
    PENUMBRA_CHECK(y <= max_y, "penumbra: ", groups, " work groups exceed the ", max_x, " x ", max_y,
                   " dispatch grid");
    // Balance the rows so the wasted tail is < one row (at most x - 1 idle groups).
    uint64_t x = divUp(groups, y);
    grid.x = static_cast<uint32_t>(x);
    grid.y = static_cast<uint32_t>(y);
    return grid;
}

}  // namespace penumbra::detail

#endif
