// penumbra — sample-based soft shadows, light pass, geometry stage (sintorn2008 §4.1, Fig. 5):
// each caster triangle's influence region (penumbra/influence_region/influence_region.glsl, the
// block-4 snippet: convex hull of the 3k far points, optional supporting-plane cut, corner-rule
// dilation, whole-grid fallbacks) emitted as a strip into the W x H grid viewport; the triangle's
// world vertices travel flat to the fragment stage. Degenerate triangles (the one rule,
// penumbra/alias_free_hard/degenerate.glsl) cast nothing and are culled here.
// Defines: the influence setup's (PENUMBRA_INFLUENCE_SIDES, PENUMBRA_INFLUENCE_CUT), PENUMBRA_SBS_COUNT_WORK.
// Closed casters' triangles with the whole light behind them are culled here (SoftSkips::closed_casters).
// PENUMBRA_SBS_DEFERRED (deferred pairs): a triangle that emits a region takes a slot in the
// triangles buffer and stores its world vertices there for the compute pass (light_pass.comp.glsl);
// with no slot left it passes PENUMBRA_SBS_NO_TRIANGLE, and its fragments flag the draws as
// overflowed (count_work's complement draw takes no slot: its fragments all return at once). Its
// culled-triangle count waits in the deferral buffer as the fragment stage's counters do.
// PENUMBRA_SBS_WEDGES (SoftSkips::wedges): the triangle's wedge planes (wedges.glsl) travel flat to
// the fragment stage, and into its slot.
// PENUMBRA_SBS_COVERAGE (SampleBasedSoftGpuOptions::coverage_texels, with PENUMBRA_SBS_DEFERRED):
// a region with a slot whose bounding box spans at most PENUMBRA_SBS_REGION_MAX_TEXELS texels is
// stored as a record (slot, polygon) after the PENUMBRA_SBS_REGION_BASE / PENUMBRA_SBS_TRIANGLE_WORDS
// slots, while the PENUMBRA_SBS_REGION_CAPACITY records last, and not emitted: the coverage pass
// (light_pass_coverage.comp.glsl) visits its texels.
// penumbra-permutation: PENUMBRA_INFLUENCE_SIDES=6 PENUMBRA_SBS_DEFERRED=1 PENUMBRA_SBS_WEDGES=1
// penumbra-permutation: PENUMBRA_INFLUENCE_SIDES=6 PENUMBRA_SBS_DEFERRED=1 PENUMBRA_SBS_WEDGES=1 PENUMBRA_SBS_COVERAGE=1 PENUMBRA_SBS_REGION_BASE=0u PENUMBRA_SBS_REGION_CAPACITY=16u PENUMBRA_SBS_REGION_MAX_TEXELS=4096u
// penumbra-permutation: PENUMBRA_INFLUENCE_SIDES=12 PENUMBRA_INFLUENCE_CUT=1 PENUMBRA_SBS_DEFERRED=1 PENUMBRA_SBS_COVERAGE=1 PENUMBRA_SBS_REGION_BASE=0u PENUMBRA_SBS_REGION_CAPACITY=16u PENUMBRA_SBS_REGION_MAX_TEXELS=64u
// penumbra-permutation: PENUMBRA_INFLUENCE_SIDES=6 PENUMBRA_SBS_WEDGES=1
// penumbra-permutation: PENUMBRA_INFLUENCE_SIDES=6
// penumbra-permutation: PENUMBRA_INFLUENCE_SIDES=12 PENUMBRA_INFLUENCE_CUT=1
// penumbra-permutation: PENUMBRA_INFLUENCE_SIDES=6 PENUMBRA_SBS_DEFERRED=1
#include "penumbra/influence_region/influence_region_shared.h"
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
#ifndef PENUMBRA_SBS_DEFERRED
#define PENUMBRA_SBS_DEFERRED 0
#endif
#ifndef PENUMBRA_SBS_WEDGES
#define PENUMBRA_SBS_WEDGES 0
#endif
#ifndef PENUMBRA_SBS_COVERAGE
#define PENUMBRA_SBS_COVERAGE 0  // 1 (with PENUMBRA_SBS_DEFERRED): small regions to the coverage pass
#endif
#if PENUMBRA_SBS_COVERAGE
#if !PENUMBRA_SBS_DEFERRED
#error PENUMBRA_SBS_COVERAGE needs PENUMBRA_SBS_DEFERRED
#endif
#ifndef PENUMBRA_SBS_REGION_BASE
#error PENUMBRA_SBS_COVERAGE needs PENUMBRA_SBS_REGION_BASE, PENUMBRA_SBS_REGION_CAPACITY and PENUMBRA_SBS_REGION_MAX_TEXELS
#endif
#endif

layout(triangles) in;
layout(triangle_strip, max_vertices = PENUMBRA_INFLUENCE_MAX_VERTICES(PENUMBRA_INFLUENCE_SIDES)) out;

layout(std140, binding = PENUMBRA_SBS_INFLUENCE_BINDING) uniform PenumbraSbsInfluenceBlock {
    PenumbraInfluenceParams penumbraSbsInfluence;
};

layout(std140, binding = PENUMBRA_SBS_PARAMS_BINDING) uniform PenumbraSbsParamsBlock {
    PenumbraSbsParams penumbraSbsParams;
};
#if PENUMBRA_SBS_COUNT_WORK
layout(std430, binding = PENUMBRA_SBS_WORK_BINDING) buffer PenumbraSbsWork { uint penumbraSbsWork[]; };
#endif

#if PENUMBRA_SBS_DEFERRED
layout(std430, binding = PENUMBRA_SBS_DEFERRAL_BINDING) buffer PenumbraSbsDeferral { uint penumbraSbsDeferral[]; };
layout(std430, binding = PENUMBRA_SBS_TRIANGLES_BINDING) writeonly buffer PenumbraSbsTriangles { uint penumbraSbsTriangles[]; };
#define PENUMBRA_SBS_TRIANGLES_WRITABLE 1
#endif

#include "penumbra/influence_region/influence_region.glsl"
#include "penumbra/sample_based_soft/triangle_store.glsl"

#if !PENUMBRA_SBS_DEFERRED
layout(location = 0) flat out vec3 penumbraSbsVertex0;
layout(location = 1) flat out vec3 penumbraSbsVertex1;
layout(location = 2) flat out vec3 penumbraSbsVertex2;
#endif
layout(location = 3) flat out uint penumbraSbsTriangle;
#if PENUMBRA_SBS_WEDGES
layout(location = 4) flat out vec4 penumbraSbsWedge[4];  // SoftSkips::wedges (wedges.glsl)
layout(location = 8) flat out vec2 penumbraSbsWedgeMargin;
#endif

void main() {
    const vec3 v0 = gl_in[0].gl_Position.xyz, v1 = gl_in[1].gl_Position.xyz, v2 = gl_in[2].gl_Position.xyz;
    if (penumbraAfhDegenerate(dvec3(v0), dvec3(v1), dvec3(v2))) return;
    bool away;  // SoftSkips::closed_casters (triangle_store.glsl)
    if (penumbraSbsClosedSkips(v0, v1, v2, away)) {
#if PENUMBRA_SBS_COUNT_WORK
        if (away && penumbraSbsParams.grid.w == 0u && (penumbraSbsParams.reserved.y & PENUMBRA_SBS_FLAG_COMPLEMENT) == 0u) {
#if PENUMBRA_SBS_DEFERRED
            atomicAdd(penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_PENDING + PENUMBRA_SBS_WORK_TRIANGLES_CULLED], 1u);
#else
            atomicAdd(penumbraSbsWork[PENUMBRA_SBS_WORK_TRIANGLES_CULLED], 1u);
#endif
        }
#endif
        return;
    }
    const int count = penumbraInfluenceRegion(v0, v1, v2, penumbraSbsInfluence);
    if (count <= 0) return;
    const vec2 half_grid = 0.5 * penumbraSbsInfluence.grid.xy;
    uint slot = PENUMBRA_SBS_NO_TRIANGLE;
#if PENUMBRA_SBS_WEDGES
    const PenumbraSbsWedges wedges = penumbraSbsWedgePlanes(dvec3(v0), dvec3(v1), dvec3(v2), penumbraSbsParams.center.xyz,
                                                            penumbraSbsParams.epsilon.w, penumbraSbsParams.epsilon.z);
#endif
#if PENUMBRA_SBS_DEFERRED
    if (count > 0 && (penumbraSbsParams.reserved.y & PENUMBRA_SBS_FLAG_COMPLEMENT) == 0u) {
        const uint k = atomicAdd(penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_TRIANGLES], 1u);
#if PENUMBRA_SBS_COVERAGE
        const uint slots = uint(PENUMBRA_SBS_REGION_BASE) / PENUMBRA_SBS_TRIANGLE_WORDS;  // the records follow the slots
#else
        const uint slots = uint(penumbraSbsTriangles.length()) / PENUMBRA_SBS_TRIANGLE_WORDS;
#endif
        if (k < slots) {
            slot = k;
#if PENUMBRA_SBS_WEDGES
            penumbraSbsStoreSlot(k, v0, v1, v2, penumbraSbsParams.grid.w, wedges);
#else
            penumbraSbsStoreSlot(k, v0, v1, v2, penumbraSbsParams.grid.w);
#endif
        }
    }
#endif
#if PENUMBRA_SBS_COVERAGE
    // A region of at most PENUMBRA_SBS_REGION_MAX_TEXELS texels in its bounding box, with a slot,
    // goes to the coverage pass (light_pass_coverage.comp.glsl) as a record, while records last:
    // nothing is emitted (llvmpipe's setup and rasterisation of the strip cost more than the
    // pass's loop over the box). The rest are drawn.
    if (slot != PENUMBRA_SBS_NO_TRIANGLE) {
        vec2 lo = penumbraInfluenceOut[0], hi = lo;
        for (int j = 1; j < count; ++j) {
            lo = min(lo, penumbraInfluenceOut[j]);
            hi = max(hi, penumbraInfluenceOut[j]);
        }
        const vec2 extent = min(hi, penumbraSbsInfluence.grid.xy) - max(lo, vec2(0.0)) + 2.0;
        if (extent.x * extent.y <= float(PENUMBRA_SBS_REGION_MAX_TEXELS)) {
            const uint r = atomicAdd(penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_REGIONS], 1u);
            if (r < uint(PENUMBRA_SBS_REGION_CAPACITY)) {
                penumbraSbsStoreRecord(r, slot, count);
                return;
            }
        }
    }
#endif
    // The convex polygon as a zig-zag strip: 0, 1, n-1, 2, n-2, ... (as influence_region.geom.glsl).
    for (int j = 0; j < count; ++j) {
        const int index = (j & 1) != 0 ? (j + 1) >> 1 : (count - (j >> 1)) % count;
        gl_Position = vec4(penumbraInfluenceOut[index] / half_grid - 1.0, 0.0, 1.0);
#if !PENUMBRA_SBS_DEFERRED
        penumbraSbsVertex0 = v0;
        penumbraSbsVertex1 = v1;
        penumbraSbsVertex2 = v2;
#endif
        penumbraSbsTriangle = slot;
#if PENUMBRA_SBS_WEDGES
        penumbraSbsWedge = wedges.planes;
        penumbraSbsWedgeMargin = wedges.margin;
#endif
        EmitVertex();
    }
    EndPrimitive();
}
