// penumbra — light-volume quadtree restriction of level k (params.size.z = k; billeter2010: "ensure
// max 1 level of difference between neighbours"): a subdivided cell with a subdivided child flags its
// four edge neighbours (a newly flagged cell has no subdivided child, so the in-place writes cannot
// change another invocation's decision). The host runs, for k = 1 .. L: this pass for level k - 1
// (k >= 2), then the flags of level k (deviation.comp.glsl: closure and flatness) — the order of
// detail::light_volume::subdivisionFlags. One invocation per cell of level k.
#include "penumbra/light_volume/light_volume_shared.h"
#include "penumbra/common/dispatch.glsl"

layout(local_size_x = PENUMBRA_LV_GROUP_SIZE) in;
layout(std140, binding = PENUMBRA_LV_BINDING_PARAMS) uniform PenumbraLvParamsBlock { PenumbraLightVolumeParams penumbraLvParams; };
layout(std430, binding = PENUMBRA_LV_BINDING_FLAGS) buffer PenumbraLvFlagsBuffer { uint penumbraLvFlags[]; };

#include "penumbra/light_volume/light_volume.glsl"

void main() {
    const uint k = penumbraLvParams.size.z, cells = penumbraLvCells(k);
    const uint index = penumbraLinearGroup() * PENUMBRA_LV_GROUP_SIZE + gl_LocalInvocationID.x;
    if (index >= cells * cells) return;
    const int cx = int(index % cells), cy = int(index / cells);
    if (!penumbraLvSubdivided(k, cx, cy) || !penumbraLvAnyChild(k, cx, cy)) return;
    const uint base = penumbraLvOffset(k);
    if (cx > 0) penumbraLvFlags[base + uint(cy) * cells + uint(cx - 1)] = 1u;
    if (uint(cx) + 1u < cells) penumbraLvFlags[base + uint(cy) * cells + uint(cx + 1)] = 1u;
    if (cy > 0) penumbraLvFlags[base + uint(cy - 1) * cells + uint(cx)] = 1u;
    if (uint(cy) + 1u < cells) penumbraLvFlags[base + uint(cy + 1) * cells + uint(cx)] = 1u;
}
