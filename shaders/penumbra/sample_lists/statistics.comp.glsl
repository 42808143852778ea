// penumbra — list statistics of sintorn2008 Fig. 9 ("% of occupied lists", average and maximum
// list size): a reduction over the W x H list lengths, per work group in shared memory, then one
// atomic per quantity and group into the header. The host derives percentages and averages
// (penumbra::SampleListStatistics), exactly as the CPU twin does from its own counts.
//
// Bindings: uniform block 0 = params (grid.xy); SSBO 2 counts uint[W*H], 3 header (statistics
// words zeroed by the host).
#include "penumbra/common/dispatch.glsl"
#include "penumbra/sample_lists/sample_lists_shared.h"

layout(local_size_x = PENUMBRA_SAMPLE_LISTS_GROUP_SIZE) in;

layout(std140, binding = PENUMBRA_SAMPLE_LISTS_BINDING_PARAMS) uniform PenumbraSampleListsParamsBlock {
    PenumbraSampleListsParams penumbraSampleListsParams;
};
layout(std430, binding = PENUMBRA_SAMPLE_LISTS_BINDING_COUNTS) readonly buffer PenumbraSampleListsCountsBlock {
    uint penumbraSampleListsCounts[];
};
layout(std430, binding = PENUMBRA_SAMPLE_LISTS_BINDING_HEADER) buffer PenumbraSampleListsHeaderBlock {
    PenumbraSampleListsHeader penumbraSampleListsHeader;
};

// occupied lists, longest list, listed samples.
shared uint penumbraSampleListsStatisticsShared[3];

void main() {
    const uint local = gl_LocalInvocationID.x;
    if (local < 3u) penumbraSampleListsStatisticsShared[local] = 0u;
    barrier();

    const uint list = penumbraLinearGroup() * uint(PENUMBRA_SAMPLE_LISTS_GROUP_SIZE) + local;
    const uint lists = penumbraSampleListsParams.grid.x * penumbraSampleListsParams.grid.y;
    if (list < lists) {
        uint count = penumbraSampleListsCounts[list];
        if (count != 0u) {
            atomicAdd(penumbraSampleListsStatisticsShared[0], 1u);
            atomicMax(penumbraSampleListsStatisticsShared[1], count);
            atomicAdd(penumbraSampleListsStatisticsShared[2], count);
        }
    }
    barrier();

    if (local < 3u) {
        uint value = penumbraSampleListsStatisticsShared[local];
        if (value != 0u) {
            if (local == 0u) atomicAdd(penumbraSampleListsHeader.occupied_lists, value);
            else if (local == 1u) atomicMax(penumbraSampleListsHeader.max_list_length, value);
            else atomicAdd(penumbraSampleListsHeader.listed_samples, value);
        }
    }
}
