// penumbra — the light volume's draw command: DrawArraysIndirectCommand {3 T, 1, 0, 0} from the
// scanned counts (T = every triangle), then the floor's triangle count and T. One invocation.
#include "penumbra/light_volume/light_volume_shared.h"

layout(local_size_x = 1) in;
layout(std140, binding = PENUMBRA_LV_BINDING_PARAMS) uniform PenumbraLvParamsBlock { PenumbraLightVolumeParams penumbraLvParams; };
layout(std430, binding = PENUMBRA_LV_BINDING_COUNTS) readonly buffer PenumbraLvCounts { uint penumbraLvCounts[]; };
layout(std430, binding = PENUMBRA_LV_BINDING_INDIRECT) writeonly buffer PenumbraLvIndirect { uint penumbraLvIndirect[]; };

void main() {
    const uint triangles = penumbraLvCounts[penumbraLvParams.counts.y];
    penumbraLvIndirect[0] = 3u * triangles;
    penumbraLvIndirect[1] = 1u;
    penumbraLvIndirect[2] = 0u;
    penumbraLvIndirect[3] = 0u;
    penumbraLvIndirect[4] = penumbraLvCounts[penumbraLvParams.counts.x];
    penumbraLvIndirect[5] = triangles;
    penumbraLvIndirect[6] = 0u;
    penumbraLvIndirect[7] = 0u;
}
