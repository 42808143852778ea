// penumbra — constants shared by C++ and GLSL (valid as both). Host code includes it through
// include/penumbra/detail/shared.hpp, which maps GLSL types to GLM first.
#ifndef PENUMBRA_COMMON_SHARED_H
#define PENUMBRA_COMMON_SHARED_H

// GL guarantees at least 65 535 work groups per dispatch dimension (GL 4.5 §19, Table 23.75);
// larger 1D dispatches are folded into a 2D grid of at most this width.
#define PENUMBRA_MAX_GROUPS_PER_DIMENSION 65535u

#endif
