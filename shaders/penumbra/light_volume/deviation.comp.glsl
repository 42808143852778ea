// penumbra — light-volume "needs subdivision" flags (billeter2010's edge map, replaced by the
// error-bounded flatness test of include/penumbra/light_volume.hpp): lattice point (i, j) checks,
// at every level k >= 1, each cell of size 2^k whose closed square holds it, and flags the cell when
// its depth is more than the flatness away from the cell's corner plane — in double, each operation
// rounded alone (precise), in the host's order. Static tessellation flags every cell. One invocation
// per lattice point; flags start cleared; every writer stores 1.
#include "penumbra/light_volume/light_volume_shared.h"
#include "penumbra/common/dispatch.glsl"

layout(local_size_x = PENUMBRA_LV_GROUP_SIZE) in;
layout(std140, binding = PENUMBRA_LV_BINDING_PARAMS) uniform PenumbraLvParamsBlock { PenumbraLightVolumeParams penumbraLvParams; };
layout(std430, binding = PENUMBRA_LV_BINDING_CORNERS) readonly buffer PenumbraLvCorners { float penumbraLvCorners[]; };
layout(std430, binding = PENUMBRA_LV_BINDING_FLAGS) buffer PenumbraLvFlagsBuffer { uint penumbraLvFlags[]; };

#include "penumbra/light_volume/light_volume.glsl"

double penumbraLvCorner(uint i, uint j) { return double(penumbraLvCorners[j * (penumbraLvParams.size.x + 1u) + i]); }

bool penumbraLvOffPlane(uint k, uint cx, uint cy, uint i, uint j, double flatness) {
    const uint s = 1u << k, x0 = cx * s, y0 = cy * s;
    const double p00 = penumbraLvCorner(x0, y0);
    precise double gx = (penumbraLvCorner(x0 + s, y0) - p00) / double(s);
    precise double gy = (penumbraLvCorner(x0, y0 + s) - p00) / double(s);
    precise double row = p00 + gy * double(j - y0);
    precise double plane = row + gx * double(i - x0);
    precise double off = abs(penumbraLvCorner(i, j) - plane);
    return off > flatness;
}

void main() {
    const uint r = penumbraLvParams.size.x, n = r + 1u;
    const uint index = penumbraLinearGroup() * PENUMBRA_LV_GROUP_SIZE + gl_LocalInvocationID.x;
    if (index >= n * n) return;
    const uint i = index % n, j = index / n;
    const bool all = penumbraLvParams.size.w != 0u;
    const double flatness = packDouble2x32(penumbraLvParams.flatness.xy);
    for (uint k = 1u; k <= penumbraLvLevels(); ++k) {
        const uint s = 1u << k, cells = r >> k;
        uint xs[2], ys[2];
        uint nx = 0u, ny = 0u;
        if (i / s < cells) xs[nx++] = i / s;
        if (i % s == 0u && i / s >= 1u) xs[nx++] = i / s - 1u;
        if (j / s < cells) ys[ny++] = j / s;
        if (j % s == 0u && j / s >= 1u) ys[ny++] = j / s - 1u;
        for (uint a = 0u; a < nx; ++a) {
            for (uint b = 0u; b < ny; ++b) {
                const uint cell = penumbraLvOffset(k) + ys[b] * cells + xs[a];
                if (all) {
                    if (i == xs[a] * s && j == ys[b] * s) penumbraLvFlags[cell] = 1u;
                } else if (penumbraLvOffPlane(k, xs[a], ys[b], i, j, flatness)) {
                    penumbraLvFlags[cell] = 1u;
                }
            }
        }
    }
}
