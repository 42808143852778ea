// penumbra — sample-based soft shadows, the compute light pass's caster setup
// (SoftLightPass::Compute): one invocation per caster triangle does what the raster light pass's
// geometry stage (light_pass.geom.glsl) does with deferred pairs and coverage, for every region
// whatever its size: the degenerate and closed-caster culls, the influence region
// (penumbra/influence_region/influence_region.glsl), the wedge planes, a triangle slot (vertices,
// list block and flags, wedges) and a region record (slot, polygon) for the coverage pass
// (light_pass_coverage.comp.glsl), which visits the region's texels. Nothing is drawn.
// The triangles come from the caster hook (caster_buffer.glsl). One dispatch covers a range of
// triangles (x) and a run of list blocks (y, from the parameter block's list block on), and is
// indirect: PENUMBRA_SBS_SETUP_GATE=1, one invocation before it, writes its group counts from the
// lists' header (max_list_length), so blocks no list reaches cost nothing (llvmpipe would run
// an invocation that returns at once through all of its code under a lane mask). The host
// dispatches at most as many (triangle, block) pairs between two runs of the deferred passes as
// there are slots and records (PENUMBRA_SBS_REGION_CAPACITY, equal to the slots): none is ever
// without one.
// Defines: the influence setup's, PENUMBRA_SBS_COUNT_WORK, PENUMBRA_SBS_WEDGES,
// PENUMBRA_SBS_REGION_BASE and PENUMBRA_SBS_REGION_CAPACITY (as the geometry stage's),
// PENUMBRA_SBS_SETUP_GATE.
// penumbra-permutation: PENUMBRA_SBS_SETUP_GATE=1 PENUMBRA_SBS_REGION_BASE=0u PENUMBRA_SBS_REGION_CAPACITY=16u
// penumbra-permutation: PENUMBRA_INFLUENCE_SIDES=6 PENUMBRA_SBS_WEDGES=1 PENUMBRA_SBS_REGION_BASE=0u PENUMBRA_SBS_REGION_CAPACITY=16u
// penumbra-permutation: PENUMBRA_INFLUENCE_SIDES=12 PENUMBRA_INFLUENCE_CUT=1 PENUMBRA_SBS_COUNT_WORK=0 PENUMBRA_SBS_REGION_BASE=0u PENUMBRA_SBS_REGION_CAPACITY=16u
#include "penumbra/influence_region/influence_region_shared.h"
#include "penumbra/sample_lists/sample_lists_shared.h"
#include "penumbra/sample_based_soft/sample_based_soft_shared.h"
#include "penumbra/alias_free_hard/degenerate.glsl"
#include "penumbra/sample_based_soft/caster_plane.glsl"
#include "penumbra/sample_based_soft/wedges.glsl"

#ifndef PENUMBRA_SBS_COUNT_WORK
#define PENUMBRA_SBS_COUNT_WORK 1
#endif
#ifndef PENUMBRA_INFLUENCE_SIDES
#define PENUMBRA_INFLUENCE_SIDES PENUMBRA_INFLUENCE_DEFAULT_SIDES
#endif
#ifndef PENUMBRA_SBS_WEDGES
#define PENUMBRA_SBS_WEDGES 0
#endif
#if !defined(PENUMBRA_SBS_REGION_BASE) || !defined(PENUMBRA_SBS_REGION_CAPACITY)
#error light_pass_setup.comp.glsl needs PENUMBRA_SBS_REGION_BASE and PENUMBRA_SBS_REGION_CAPACITY
#endif

#ifndef PENUMBRA_SBS_SETUP_GATE
#define PENUMBRA_SBS_SETUP_GATE 0
#endif
#if PENUMBRA_SBS_SETUP_GATE
layout(local_size_x = 1) in;
#else
layout(local_size_x = PENUMBRA_SBS_SETUP_GROUP) in;
#endif

layout(std140, binding = PENUMBRA_SBS_INFLUENCE_BINDING) uniform PenumbraSbsInfluenceBlock {
    PenumbraInfluenceParams penumbraSbsInfluence;
};
layout(std140, binding = PENUMBRA_SBS_PARAMS_BINDING) uniform PenumbraSbsParamsBlock {
    PenumbraSbsParams penumbraSbsParams;
};
layout(std430, binding = PENUMBRA_SBS_HEADER_BINDING) readonly buffer PenumbraSbsHeaderBlock {
    PenumbraSampleListsHeader penumbraSbsHeader;
};
layout(std430, binding = PENUMBRA_SBS_DEFERRAL_BINDING) buffer PenumbraSbsDeferral { uint penumbraSbsDeferral[]; };
layout(std430, binding = PENUMBRA_SBS_TRIANGLES_BINDING) writeonly buffer PenumbraSbsTriangles { uint penumbraSbsTriangles[]; };
#define PENUMBRA_SBS_TRIANGLES_WRITABLE 1

#include "penumbra/influence_region/influence_region.glsl"
#include "penumbra/sample_based_soft/caster_buffer.glsl"
#include "penumbra/sample_based_soft/triangle_store.glsl"

#if PENUMBRA_SBS_SETUP_GATE
layout(location = 2) uniform uint penumbraSbsSetupBlocks;  // list blocks this dispatch may cover

// The setup dispatch's group counts: the range's triangles, and of the list blocks from the
// parameter block's on (at most penumbraSbsSetupBlocks) those the longest list reaches (what the
// raster pass's predicate points decide).
void main() {
    const uint length = penumbraSbsHeader.max_list_length, block = penumbraSbsParams.grid.z;
    const uint needed = length / block + ((length % block) != 0u ? 1u : 0u);
    const uint first = penumbraSbsParams.grid.w;
    penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_SETUP_ARGS] = (penumbraSbsCasterRange.y + uint(PENUMBRA_SBS_SETUP_GROUP) - 1u) /
                                                            uint(PENUMBRA_SBS_SETUP_GROUP);
    penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_SETUP_ARGS + 1] = needed > first ? min(needed - first, penumbraSbsSetupBlocks) : 0u;
    penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_SETUP_ARGS + 2] = 1u;
}
#else
void main() {
    const uint t = gl_GlobalInvocationID.x;
    if (t >= penumbraSbsCasterRange.y) return;
    // The list block: the parameter block's first, plus the dispatch's y.
    const uint list_block = penumbraSbsParams.grid.w + gl_WorkGroupID.y;
    vec3 v[3];
    if (!penumbraSbsCasterTriangle(penumbraSbsCasterRange.x + t, v)) {
        // Counted once (list block 0 of the first pass), as the culled triangles are; both setup
        // counts wait where an overflow does not drop them (the coverage pass's inline program
        // redoes the pairs, not the setup).
#if PENUMBRA_SBS_COUNT_WORK
        if (list_block == 0u && (penumbraSbsParams.reserved.y & PENUMBRA_SBS_FLAG_CULLED_PASS) == 0u)
            atomicAdd(penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_SETUP + 1], 1u);
#endif
        return;
    }
    const vec3 v0 = v[0], v1 = v[1], v2 = v[2];
    if (penumbraAfhDegenerate(dvec3(v0), dvec3(v1), dvec3(v2))) return;
    bool away;  // SoftSkips::closed_casters, as the geometry stage (triangle_store.glsl)
    if (penumbraSbsClosedSkips(v0, v1, v2, away)) {
#if PENUMBRA_SBS_COUNT_WORK
        if (away && list_block == 0u) atomicAdd(penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_SETUP], 1u);
#endif
        return;
    }
    const int count = penumbraInfluenceRegion(v0, v1, v2, penumbraSbsInfluence);
    if (count <= 0) return;
    // A slot and a record: the host keeps the triangles between two deferred runs within both.
    const uint k = atomicAdd(penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_TRIANGLES], 1u);
    const uint r = atomicAdd(penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_REGIONS], 1u);
    if (k >= uint(PENUMBRA_SBS_REGION_BASE) / PENUMBRA_SBS_TRIANGLE_WORDS || r >= uint(PENUMBRA_SBS_REGION_CAPACITY)) {
        penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_OVERFLOW] = 1u;  // never, by the host's chunks; loud if it were
        return;
    }
#if PENUMBRA_SBS_WEDGES
    penumbraSbsStoreSlot(k, v0, v1, v2, list_block,
                         penumbraSbsWedgePlanes(dvec3(v0), dvec3(v1), dvec3(v2), penumbraSbsParams.center.xyz,
                                                penumbraSbsParams.epsilon.w, penumbraSbsParams.epsilon.z));
#else
    penumbraSbsStoreSlot(k, v0, v1, v2, list_block);
#endif
    penumbraSbsStoreRecord(r, k, count);
}
#endif
