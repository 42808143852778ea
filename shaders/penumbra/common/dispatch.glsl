// penumbra — linear work-group ids for 1D problems dispatched as 2D grids.
//
// Host side: penumbra::detail::foldDispatch (include/penumbra/detail/dispatch.hpp) turns a group
// count into (x, y) with x <= PENUMBRA_MAX_GROUPS_PER_DIMENSION; the last row may hold groups
// past the count, which kernels must skip (penumbraLinearGroup() >= their group count).
#ifndef PENUMBRA_COMMON_DISPATCH_GLSL
#define PENUMBRA_COMMON_DISPATCH_GLSL

#include "penumbra/common/common_shared.h"

uint penumbraLinearGroup() {
    return gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x;
}

#endif
