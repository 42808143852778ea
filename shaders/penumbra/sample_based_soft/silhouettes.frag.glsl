// penumbra — sample-based soft shadows, silhouette pass, fragment stage (SoftSkips::silhouettes):
// marks the light texel as a penumbra texel (the light pass walks its view samples with the full
// N-sample test; unmarked texels take one exact test from the light centre per pair). No colour
// output. Bit 0: a potential silhouette's region (idempotent plain stores, drawn first).
// With PENUMBRA_SBS_NEAR_PASS = 1 (silhouettes.geom.glsl's triangle regions, drawn after a
// barrier): bit 1 where one of the texel's view samples p has T's edges opened by the oracle's
// coplanar rule (penumbraSbsCoplanarOpen): outside every silhouette's region p's light is then not
// all-or-nothing. The sample lists are bound as for the light pass; the walk covers the samples
// the light pass gives masks (params.counts.y per list).
// penumbra-permutation: PENUMBRA_SBS_NEAR_PASS=0
// penumbra-permutation: PENUMBRA_SBS_NEAR_PASS=1
#include "penumbra/sample_based_soft/sample_based_soft_shared.h"

#ifndef PENUMBRA_SBS_NEAR_PASS
#define PENUMBRA_SBS_NEAR_PASS 0
#endif

layout(std140, binding = PENUMBRA_SBS_PARAMS_BINDING) uniform PenumbraSbsParamsBlock {
    PenumbraSbsParams penumbraSbsParams;
};

#if PENUMBRA_SBS_NEAR_PASS
layout(std430, binding = PENUMBRA_SBS_MARKS_BINDING) buffer PenumbraSbsMarks { uint penumbraSbsMarks[]; };
layout(std430, binding = PENUMBRA_SBS_COUNTS_BINDING) readonly buffer PenumbraSbsCounts { uint penumbraSbsCounts[]; };
layout(std430, binding = PENUMBRA_SBS_OFFSETS_BINDING) readonly buffer PenumbraSbsOffsets { uint penumbraSbsOffsets[]; };
layout(std430, binding = PENUMBRA_SBS_POSITIONS_BINDING) readonly buffer PenumbraSbsPositions { vec4 penumbraSbsPositions[]; };
#define PENUMBRA_SAMPLE_LISTS_LOAD_COUNT(list) penumbraSbsCounts[list]
#define PENUMBRA_SAMPLE_LISTS_LOAD_OFFSET(list) penumbraSbsOffsets[list]
#define PENUMBRA_SAMPLE_LISTS_LOAD_POSITION(slot) penumbraSbsPositions[slot]
#define PENUMBRA_SAMPLE_LISTS_LOAD_ID(slot) 0u
#define PENUMBRA_SAMPLE_LISTS_GRID_WIDTH penumbraSbsParams.grid.x
#include "penumbra/sample_lists/sample_lists.glsl"
#define PENUMBRA_AFH_EXACT 1
#include "penumbra/alias_free_hard/blocker_test.glsl"
#include "penumbra/sample_based_soft/caster_plane.glsl"

layout(location = 0) flat in vec3 penumbraSbsNearVertex0;
layout(location = 1) flat in vec3 penumbraSbsNearVertex1;
layout(location = 2) flat in vec3 penumbraSbsNearVertex2;
#else
layout(std430, binding = PENUMBRA_SBS_MARKS_BINDING) writeonly buffer PenumbraSbsMarks { uint penumbraSbsMarks[]; };
#endif

void main() {
    const uvec2 texel = uvec2(gl_FragCoord.xy);
    const uint index = texel.y * penumbraSbsParams.grid.x + texel.x;
#if PENUMBRA_SBS_NEAR_PASS
    if (penumbraSbsMarks[index] != 0u) return;  // a penumbra texel already
    const PenumbraSbsParams P = penumbraSbsParams;
    const dvec3 v0 = dvec3(penumbraSbsNearVertex0), v1 = dvec3(penumbraSbsNearVertex1), v2 = dvec3(penumbraSbsNearVertex2);
    const PenumbraSbsCasterPlane caster = penumbraSbsCasterPlane(v0, v1, v2, P.center.xyz, P.bounds.x);
    const double light_distance2 = penumbraAfhPointTriangleDistance2(P.center.xyz, v0, v1, v2);
    const uvec2 range = penumbraSampleListsRange(ivec2(texel));
    const uint end = range.x + min(range.y, P.counts.y);
    for (uint slot = range.x; slot < end; ++slot) {
        const dvec3 p = dvec3(penumbraSampleListsPosition(slot));
        const double scale_v = max(penumbraSbsMaxAbs(v0 - p), max(penumbraSbsMaxAbs(v1 - p), penumbraSbsMaxAbs(v2 - p)));
        if (penumbraSbsCoplanarOpen(caster, p, scale_v, penumbraAfhPointTriangleDistance2(p, v0, v1, v2), light_distance2,
                                    P.center.xyz, P.bounds.x, P.epsilon.x, P.center.w)) {
            atomicOr(penumbraSbsMarks[index], 2u);
            return;
        }
    }
#else
    penumbraSbsMarks[index] = 1u;
#endif
}
