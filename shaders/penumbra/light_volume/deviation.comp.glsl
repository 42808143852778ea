// penumbra — light-volume "needs subdivision" flags of level k (params.size.z = k >= 1; billeter2010's
// edge map and its mip hierarchy, replaced by the error-bounded flatness test of
// include/penumbra/light_volume.hpp, steps 1 and 2): closure — a cell with a subdivided child is
// subdivided — and otherwise the flatness test — the cell is subdivided when a lattice depth in its
// closed square is more than the flatness away from its corner plane, in double, each operation
// rounded alone (precise), in the host's order (detail::light_volume::subdivisionFlags). Static
// tessellation flags every cell. One invocation per row j = 0 .. s of a cell of size s = 2^k; row 0
// also writes the closure. The host runs, for k = 1 .. L: restriction of level k - 1 (k >= 2,
// restrict.comp.glsl), then this pass for level k, so the children's flags are final when read.
// Flags start cleared; every writer stores 1. A row stops at its first point off the plane and does
// not start when another row has already flagged the cell (a stale read of a flag just tests it), so
// each cell's flag is "closure or some point off the plane", whatever the order: the CPU twin's.
#include "penumbra/light_volume/light_volume_shared.h"
#include "penumbra/common/dispatch.glsl"

layout(local_size_x = PENUMBRA_LV_GROUP_SIZE) in;
layout(std140, binding = PENUMBRA_LV_BINDING_PARAMS) uniform PenumbraLvParamsBlock { PenumbraLightVolumeParams penumbraLvParams; };
layout(std430, binding = PENUMBRA_LV_BINDING_CORNERS) readonly buffer PenumbraLvCorners { float penumbraLvCorners[]; };
layout(std430, binding = PENUMBRA_LV_BINDING_FLAGS) buffer PenumbraLvFlagsBuffer { uint penumbraLvFlags[]; };

#include "penumbra/light_volume/light_volume.glsl"

double penumbraLvCorner(uint i, uint j) { return double(penumbraLvCorners[j * (penumbraLvParams.size.x + 1u) + i]); }

void main() {
    const uint k = penumbraLvParams.size.z, s = 1u << k, cells = penumbraLvCells(k);
    const uint index = penumbraLinearGroup() * PENUMBRA_LV_GROUP_SIZE + gl_LocalInvocationID.x;
    if (index >= cells * cells * (s + 1u)) return;
    const uint cell = index / (s + 1u), j = index % (s + 1u);
    const int cx = int(cell % cells), cy = int(cell / cells);
    const uint flag = penumbraLvOffset(k) + cell;
    if (penumbraLvParams.size.w != 0u) {  // static: every cell
        if (j == 0u) penumbraLvFlags[flag] = 1u;
        return;
    }
    if (penumbraLvAnyChild(k, cx, cy)) {
        if (j == 0u) penumbraLvFlags[flag] = 1u;  // closure
        return;
    }
    if (penumbraLvFlags[flag] != 0u) return;
    const double flatness = packDouble2x32(penumbraLvParams.flatness.xy);
    const uint x0 = uint(cx) * s, y0 = uint(cy) * s;
    const double p00 = penumbraLvCorner(x0, y0);
    precise double gx = (penumbraLvCorner(x0 + s, y0) - p00) / double(s);
    precise double gy = (penumbraLvCorner(x0, y0 + s) - p00) / double(s);
    precise double row = p00 + gy * double(j);
    const uint base = (y0 + j) * (penumbraLvParams.size.x + 1u) + x0;
    for (uint i = 0u; i <= s; ++i) {
        precise double plane = row + gx * double(i);
        precise double off = abs(double(penumbraLvCorners[base + i]) - plane);
        if (off > flatness) {
            penumbraLvFlags[flag] = 1u;
            return;
        }
    }
}
