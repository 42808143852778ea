// penumbra — light-volume quadtree closure and restriction (billeter2010: "ensure max 1 level of
// difference between neighbours"), one level per dispatch (params.size.z = k):
//   PENUMBRA_LV_PASS 0 (restriction of level k): a subdivided cell with a subdivided child flags its
//     four edge neighbours (a newly flagged cell has no subdivided child, so the in-place writes
//     cannot change another invocation's decision);
//   PENUMBRA_LV_PASS 1 (closure into level k): a cell with a subdivided child is subdivided.
// The host runs, for k = 1 .. L: restriction of k - 1 (k >= 2), closure of k — the order of
// detail::light_volume::subdivisionFlags. One invocation per cell of level k.
// penumbra-permutation: PENUMBRA_LV_PASS=0
// penumbra-permutation: PENUMBRA_LV_PASS=1
#include "penumbra/light_volume/light_volume_shared.h"
#include "penumbra/common/dispatch.glsl"

#ifndef PENUMBRA_LV_PASS
#error penumbra/light_volume/restrict.comp.glsl needs PENUMBRA_LV_PASS (0 restriction, 1 closure)
#endif

layout(local_size_x = PENUMBRA_LV_GROUP_SIZE) in;
layout(std140, binding = PENUMBRA_LV_BINDING_PARAMS) uniform PenumbraLvParamsBlock { PenumbraLightVolumeParams penumbraLvParams; };
layout(std430, binding = PENUMBRA_LV_BINDING_FLAGS) buffer PenumbraLvFlagsBuffer { uint penumbraLvFlags[]; };

#include "penumbra/light_volume/light_volume.glsl"

bool penumbraLvAnyChild(uint k, int cx, int cy) {
    return penumbraLvSubdivided(k - 1u, 2 * cx, 2 * cy) || penumbraLvSubdivided(k - 1u, 2 * cx + 1, 2 * cy) ||
           penumbraLvSubdivided(k - 1u, 2 * cx, 2 * cy + 1) || penumbraLvSubdivided(k - 1u, 2 * cx + 1, 2 * cy + 1);
}

void main() {
    const uint k = penumbraLvParams.size.z, cells = penumbraLvCells(k);
    const uint index = penumbraLinearGroup() * PENUMBRA_LV_GROUP_SIZE + gl_LocalInvocationID.x;
    if (index >= cells * cells) return;
    const int cx = int(index % cells), cy = int(index / cells);
#if PENUMBRA_LV_PASS == 0
    if (!penumbraLvSubdivided(k, cx, cy) || !penumbraLvAnyChild(k, cx, cy)) return;
    const uint base = penumbraLvOffset(k);
    if (cx > 0) penumbraLvFlags[base + uint(cy) * cells + uint(cx - 1)] = 1u;
    if (uint(cx) + 1u < cells) penumbraLvFlags[base + uint(cy) * cells + uint(cx + 1)] = 1u;
    if (cy > 0) penumbraLvFlags[base + uint(cy - 1) * cells + uint(cx)] = 1u;
    if (uint(cy) + 1u < cells) penumbraLvFlags[base + uint(cy + 1) * cells + uint(cx)] = 1u;
#else
    if (penumbraLvAnyChild(k, cx, cy)) penumbraLvFlags[penumbraLvOffset(k) + index] = 1u;
#endif
}
